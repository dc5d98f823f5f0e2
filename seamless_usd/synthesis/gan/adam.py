"""Adam (Kingma and Ba, 2015) with the update ``torch.optim.Adam`` makes at its defaults, outside ``torch.optim``.

``torch.optim``'s optimisers import ``torch._dynamo`` on their first call whatever the device: 1.2 s
of every ``process`` run on 2 cores, a sixth of a small run. This is torch's single-tensor Adam
(no amsgrad, weight decay or maximize; the state on the parameters' device, the step count a float32
CPU scalar) written with the ``_foreach`` ops: on the CPU they run the same per-tensor kernels, so the
parameters follow ``torch.optim.Adam`` to the bit (tested); on a GPU each op is one launch for all
tensors. The state has torch's names (``exp_avg``, ``exp_avg_sq``, ``step``) and indices, so
checkpoints read and write as before. ``param_groups`` is what ``torch.amp.GradScaler`` and the
learning-rate schedule use.
"""
from __future__ import annotations

from collections.abc import Iterable

import torch

__all__ = ["Adam"]

_STATE = ("exp_avg", "exp_avg_sq", "step")


class Adam:
    """Adam over one group of parameters; ``step()`` updates those that have a gradient."""

    def __init__(self, params: Iterable[torch.Tensor], lr: float = 1e-3,
                 betas: tuple[float, float] = (0.9, 0.999), eps: float = 1e-8) -> None:
        if not 0.0 <= lr or not 0.0 <= betas[0] < 1.0 or not 0.0 <= betas[1] < 1.0 or not 0.0 <= eps:
            raise ValueError(f"Adam needs lr >= 0, 0 <= betas < 1 and eps >= 0 (got {lr}, {betas}, {eps})")
        self.param_groups = [{"params": list(params), "lr": lr, "betas": tuple(betas), "eps": eps}]
        self.state: dict[int, dict[str, torch.Tensor]] = {}  # parameter index -> exp_avg, exp_avg_sq, step

    def zero_grad(self, set_to_none: bool = True) -> None:
        for p in self.param_groups[0]["params"]:
            if set_to_none:
                p.grad = None
            elif p.grad is not None:
                p.grad.detach_().zero_()

    @torch.no_grad()
    def step(self) -> None:
        group = self.param_groups[0]
        beta1, beta2 = group["betas"]
        lr, eps = group["lr"], group["eps"]
        params, grads, avgs, squares, sizes, corrections = [], [], [], [], [], []
        for i, p in enumerate(group["params"]):
            if p.grad is None:
                continue
            st = self.state.get(i)
            if st is None:
                st = self.state[i] = {"exp_avg": torch.zeros_like(p, memory_format=torch.preserve_format),
                                      "exp_avg_sq": torch.zeros_like(p, memory_format=torch.preserve_format),
                                      "step": torch.tensor(0.0, dtype=torch.float32)}
            st["step"] += 1
            step = st["step"].item()
            params.append(p)
            grads.append(p.grad)
            avgs.append(st["exp_avg"])
            squares.append(st["exp_avg_sq"])
            sizes.append(-(lr / (1 - beta1 ** step)))
            corrections.append((1 - beta2 ** step) ** 0.5)
        if not params:
            return
        torch._foreach_lerp_(avgs, grads, 1 - beta1)
        torch._foreach_mul_(squares, beta2)
        torch._foreach_addcmul_(squares, grads, grads, value=1 - beta2)
        denominators = torch._foreach_sqrt(squares)
        torch._foreach_div_(denominators, corrections)
        torch._foreach_add_(denominators, eps)
        torch._foreach_addcdiv_(params, avgs, denominators, sizes)

    def state_tensors(self, prefix: str) -> dict[str, torch.Tensor]:
        """The state as named CPU tensors: ``{prefix}.{parameter index}.{exp_avg|exp_avg_sq|step}``."""
        return {f"{prefix}.{i}.{name}": t.detach().cpu().contiguous()
                for i, st in self.state.items() for name, t in st.items()}

    def load_state_tensors(self, prefix: str, tensors: dict[str, torch.Tensor]) -> None:
        """Take the state written by :meth:`state_tensors` (or by ``torch.optim.Adam``'s ``state_dict``
        flattened the same way); moments go to their parameter's device and dtype."""
        params = self.param_groups[0]["params"]
        state: dict[int, dict[str, torch.Tensor]] = {}
        for key, t in tensors.items():
            if not key.startswith(prefix + "."):
                continue
            index, name = key[len(prefix) + 1:].split(".", 1)
            i = int(index)
            if name not in _STATE or not 0 <= i < len(params):
                raise ValueError(f"{key}: not an Adam state tensor of these {len(params)} parameters")
            p = params[i]
            if name == "step":
                state.setdefault(i, {})[name] = t.detach().to(torch.float32).cpu().reshape(())
            elif t.shape != p.shape:
                raise ValueError(f"{key}: shape {tuple(t.shape)}, the parameter's is {tuple(p.shape)}")
            else:
                state.setdefault(i, {})[name] = t.detach().to(device=p.device, dtype=p.dtype).clone()
        incomplete = [i for i, st in state.items() if set(st) != set(_STATE)]
        if incomplete:
            raise ValueError(f"{prefix}: Adam state incomplete for parameters {incomplete}")
        self.state = state
