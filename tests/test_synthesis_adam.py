"""The training's Adam against ``torch.optim.Adam``: the same parameters to the bit, step after step, with
gradients missing on some steps, a learning rate changed between steps, and a state handed over midway."""
from __future__ import annotations

import subprocess
import sys

import pytest
import torch
from torch import nn

from seamless_usd.synthesis.gan.adam import Adam

pytestmark = pytest.mark.usefixtures("one_thread")


def _net(seed: int) -> nn.Module:
    torch.manual_seed(seed)
    return nn.Sequential(nn.Conv2d(3, 8, 3, padding=1), nn.InstanceNorm2d(8, affine=True), nn.ReLU(),
                         nn.Conv2d(8, 2, 1))


def _grads(net: nn.Module, step: int) -> None:
    """Gradients of a fixed loss; on odd steps the last layer gets none (a frozen part, as D in G's step)."""
    gen = torch.Generator().manual_seed(100 + step)
    x = torch.randn(2, 3, 12, 12, generator=gen)
    loss = net(x).square().mean()
    params = list(net.parameters())
    grads = torch.autograd.grad(loss, params)
    for i, (p, g) in enumerate(zip(params, grads)):
        p.grad = None if (step % 2 and i >= len(params) - 2) else g


def _run(net: nn.Module, opt, steps: range, lrs) -> None:
    for step in steps:
        for group in opt.param_groups:
            group["lr"] = lrs[step]
        _grads(net, step)
        opt.step()


def _flat(torch_opt: torch.optim.Adam, prefix: str) -> dict[str, torch.Tensor]:
    return {f"{prefix}.{i}.{name}": t for i, st in torch_opt.state_dict()["state"].items() for name, t in st.items()}


def test_each_step_gives_torch_adams_parameters_and_state_to_the_bit():
    ours_net, torch_net = _net(0), _net(0)
    betas = (0.5, 0.999)  # the paper's
    ours = Adam(ours_net.parameters(), lr=2e-4, betas=betas)
    theirs = torch.optim.Adam(torch_net.parameters(), lr=2e-4, betas=betas)
    lrs = [2e-4] * 4 + [1e-4, 5e-5, 2.5e-5, 1e-5]
    for step in range(len(lrs)):
        _run(ours_net, ours, range(step, step + 1), lrs)
        _run(torch_net, theirs, range(step, step + 1), lrs)
        for a, b in zip(ours_net.parameters(), torch_net.parameters()):
            assert torch.equal(a, b), step
    start = next(iter(ours_net.parameters())).detach().clone()
    assert not torch.equal(start, _net(0)[0].weight)  # it moved
    mine = ours.state_tensors("opt")
    assert mine.keys() == _flat(theirs, "opt").keys()
    assert all(torch.equal(mine[k], v) for k, v in _flat(theirs, "opt").items())
    last = len(list(ours_net.parameters())) - 1
    assert float(mine["opt.0.step"]) == 8 and float(mine[f"opt.{last}.step"]) == 4  # skipped on odd steps


def test_a_state_taken_over_midway_continues_as_torch_adam_does():
    """Ours and torch's state are the same tensors by the same names: a checkpoint written by either goes
    on in the other, and a run resumed from our own state equals one that never stopped."""
    lrs = [1e-3] * 6
    straight_net = _net(1)
    straight = Adam(straight_net.parameters(), lr=1e-3)
    _run(straight_net, straight, range(6), lrs)

    torch_net = _net(1)
    theirs = torch.optim.Adam(torch_net.parameters(), lr=1e-3)
    _run(torch_net, theirs, range(3), lrs)
    resumed_net = _net(1)
    resumed_net.load_state_dict(torch_net.state_dict())
    resumed = Adam(resumed_net.parameters(), lr=1e-3)
    resumed.load_state_tensors("optG", _flat(theirs, "optG") | {"optD.0.step": torch.tensor(9.0)})
    _run(resumed_net, resumed, range(3, 6), lrs)
    again_net = _net(1)
    again_net.load_state_dict(resumed_net.state_dict())
    again = Adam(again_net.parameters(), lr=1e-3)
    again.load_state_tensors("optG", resumed.state_tensors("optG"))
    for a, b in zip(straight_net.parameters(), resumed_net.parameters()):
        assert torch.equal(a, b)
    assert all(torch.equal(t, again.state_tensors("optG")[k]) for k, t in resumed.state_tensors("optG").items())


def test_a_state_of_other_parameters_is_refused():
    opt = Adam(_net(0).parameters())
    with pytest.raises(ValueError, match="shape"):
        opt.load_state_tensors("o", {"o.0.exp_avg": torch.zeros(3), "o.0.exp_avg_sq": torch.zeros(3),
                                     "o.0.step": torch.tensor(1.0)})
    with pytest.raises(ValueError, match="not an Adam state tensor"):
        opt.load_state_tensors("o", {"o.99.exp_avg": torch.zeros(3)})
    with pytest.raises(ValueError, match="incomplete"):
        opt.load_state_tensors("o", {"o.1.step": torch.tensor(1.0)})
    with pytest.raises(ValueError, match="lr >= 0"):
        Adam(_net(0).parameters(), lr=-1.0)


def test_training_does_not_load_the_compiler():
    """What the optimiser is for: a training run on the CPU never imports ``torch._dynamo`` (1.2 s)."""
    code = ("import sys, numpy as np\n"
            "from seamless_usd.synthesis import MapInput, get_preset, train\n"
            "m = [MapInput('albedo', np.zeros((32, 32, 3), np.float32))]\n"
            "train(m, get_preset('tiny').replace(iterations=2), seed=0, device='cpu')\n"
            "print('torch._dynamo' in sys.modules)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == "False"


def test_a_grad_scaler_steps_it_as_it_steps_torch_adam():
    """The fp16 path (a GPU's) runs the optimiser through ``torch.amp.GradScaler``: scaled gradients are
    unscaled, a step with an infinite gradient is skipped, and the parameters follow torch's Adam."""
    results = []
    for make in (Adam, torch.optim.Adam):
        net = _net(3)
        opt = make(net.parameters(), lr=1e-3)
        scaler = torch.amp.GradScaler("cpu", init_scale=2.0 ** 8)
        for step in range(4):
            x = torch.randn(2, 3, 12, 12, generator=torch.Generator().manual_seed(step))
            loss = net(x).square().mean() * (float("inf") if step == 2 else 1.0)
            opt.zero_grad(set_to_none=True)
            scaler.scale(loss).backward()
            scaler.step(opt)
            scaler.update()
        results.append([p.detach().clone() for p in net.parameters()])
        assert scaler.get_scale() < 2.0 ** 8  # the infinite step lowered the scale (and was skipped)
    assert all(torch.equal(a, b) for a, b in zip(*results))
