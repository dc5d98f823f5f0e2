"""Loading the maps of one stack onto a common working grid in the network domain.

For each map: read the file (pixel limit checked on the header first), replace non-finite
values (reported as a ``non-finite-pixels`` warning; channel problems such as a role reading
an alpha the file lacks become ``map-channels`` warnings), fit its :class:`MapEncoding`, decode to
[-1, 1], then resample to the working size chosen by the :class:`WorkingResolution` policy.
Resampling happens in the network domain (linear light for LDR maps, since that map is affine;
the log domain for HDR maps); afterwards values are clipped to [-1, 1] (filter ringing) and
normals renormalised. :class:`StackPixels` records what was done for the report.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from seamless_usd.textures import ImageInfo, TextureMap
from seamless_usd.errors import InputError
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref
from seamless_usd.imaging.encoding import MapEncoding, decode_map
from seamless_usd.imaging.finite import replace_nonfinite
from seamless_usd.imaging.io import DEFAULT_MAX_PIXELS, read_image
from seamless_usd.imaging.normals import renormalise
from seamless_usd.imaging.resample import WorkingResolution, resample

__all__ = ["StackPixels", "load_stack_pixels"]


@dataclass
class StackPixels:
    """The maps of one stack, decoded to the network domain on one working grid.

    ``values[i]`` is map ``i`` as ``(H, W, C_i)`` float32 in [-1, 1] with
    ``(W, H) == working_size``; sizes are ``(W, H)`` pairs throughout.
    """

    maps: tuple[TextureMap, ...]
    infos: tuple[ImageInfo, ...]
    encodings: tuple[MapEncoding, ...]
    values: tuple[np.ndarray, ...]
    original_sizes: tuple[tuple[int, int], ...]
    working_size: tuple[int, int]
    scale_factors: tuple[tuple[float, float], ...]  # working / original, per map (x, y)
    policy: WorkingResolution
    findings: list[Finding] = field(default_factory=list)

    @property
    def channel_counts(self) -> tuple[int, ...]:
        return tuple(v.shape[2] for v in self.values)

    def stacked(self) -> np.ndarray:
        """All maps concatenated along channels: ``(H, W, sum(C_i))``."""
        return np.concatenate(self.values, axis=2)

    def split(self, stacked: np.ndarray) -> list[np.ndarray]:
        """Inverse of :meth:`stacked` for any ``(H', W', sum(C_i))`` array (e.g. a tile)."""
        bounds = np.cumsum(self.channel_counts)[:-1]
        return list(np.split(np.asarray(stacked), bounds, axis=2))

    @property
    def resampled(self) -> tuple[bool, ...]:
        return tuple(s != self.working_size for s in self.original_sizes)

    @property
    def policy_record(self) -> dict:
        """What the working-resolution policy did, for the report (JSON-ready)."""
        return {
            "policy": self.policy.to_dict(),
            "working_size": list(self.working_size),
            "maps": [
                {
                    "asset": m.asset,
                    "original_size": list(size),
                    "scale": list(scale),
                    "resampled": changed,
                }
                for m, size, scale, changed in zip(
                    self.maps, self.original_sizes, self.scale_factors, self.resampled
                )
            ],
        }

    def to_dict(self) -> dict:
        """JSON form (no pixels): the policy record, encodings and findings."""
        d = self.policy_record
        d["encodings"] = [e.to_dict() for e in self.encodings]
        d["findings"] = [f.to_dict() for f in self.findings]
        return d


def load_stack_pixels(
    maps: Sequence[TextureMap],
    policy: WorkingResolution | None = None,
    *,
    max_pixels: int | None = DEFAULT_MAX_PIXELS,
    encodings: Sequence[MapEncoding] | None = None,
) -> StackPixels:
    """Read, decode and resample the maps of one stack (see the module docstring).

    Parameters
    ----------
    maps
        The stack's maps; each needs a ``resolved`` file path.
    policy
        The working-resolution policy; default :meth:`WorkingResolution.native`.
    max_pixels
        Per-file header limit, as in :func:`~seamless_usd.imaging.io.read_info`.
    encodings
        Per map, the encoding to decode it with instead of its own (a tile read as its source was: a float
        file's fitted range is its source's, not one fitted to the tile's own values).

    Returns
    -------
    StackPixels
        Network-domain values on the working grid, their encodings and what was done.

    Raises
    ------
    InputError
        A map without a resolved file, an unreadable file, a file above the pixel limit, or a
        normal map whose scale cannot be inverted.
    """
    policy = policy or WorkingResolution.native()
    if not maps:
        raise ValueError("load_stack_pixels needs at least one map")
    findings: list[Finding] = []
    given, infos, encodings, decoded = encodings, [], [], []
    for i, m in enumerate(maps):
        if not m.resolved:
            raise InputError(f"{asset_ref(m.asset)}: unresolved texture of {prim_ref(m.node)}; fix the asset path")
        pixels, info = read_image(m.resolved, max_pixels=max_pixels)
        pixels, counts = replace_nonfinite(pixels)
        if counts.total:
            findings.append(
                Finding(
                    Severity.WARNING,
                    "non-finite-pixels",
                    asset_ref(m.asset),
                    f"{counts} replaced (NaN by 0, inf by the channel's finite extreme); "
                    "check the texture's export",
                )
            )
        try:
            encoding = given[i] if given is not None else MapEncoding.for_map(m, info, pixels)
        except ValueError as exc:
            raise InputError(f"{prim_ref(m.node)} {asset_ref(m.asset)}: {exc}; fix its scale/bias") from exc
        findings.extend(
            Finding(Severity.WARNING, "map-channels", f"{prim_ref(m.node)} {asset_ref(m.asset)}", w)
            for w in encoding.warnings
        )
        infos.append(info)
        encodings.append(encoding)
        decoded.append(decode_map(pixels, encoding))

    sizes = tuple((i.width, i.height) for i in infos)
    working = policy.working_size(sizes)
    values = []
    for enc, val in zip(encodings, decoded):
        if (val.shape[1], val.shape[0]) != working:
            val = np.clip(resample(val, working, policy.filter), -1.0, 1.0)
            if enc.normal is not None:
                normals = enc.channel_groups()[1]
                val[..., normals] = renormalise(val[..., normals]).astype(np.float32)
        values.append(np.ascontiguousarray(val, dtype=np.float32))
    scales = tuple((working[0] / w, working[1] / h) for w, h in sizes)
    return StackPixels(
        maps=tuple(maps),
        infos=tuple(infos),
        encodings=tuple(encodings),
        values=tuple(values),
        original_sizes=sizes,
        working_size=working,
        scale_factors=scales,
        policy=policy,
        findings=findings,
    )

