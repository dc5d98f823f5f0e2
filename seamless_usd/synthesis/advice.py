"""What a cut's recorded figures mean: when its joins hide, the lattice ratio of what was written, and what would
help a stack whose joins show. Plain Python on the figures as recorded (a cached stack's metadata, a report), so
reading them needs no torch.
"""
from __future__ import annotations

__all__ = ["WINDOW_MAX_DIFFERENCE", "QUILT_MAX_DIFFERENCE", "joins_hide", "written_lattice_ratio",
           "structure_advice"]

#: The most a chosen lag's difference (see :func:`.lattice.window.window_tile_size`) may be, on either axis, for the window
#: cut to be offered. Window cuts looked at along their wraps: the clean ones (a weave whose windows repeat
#: exactly, a repeating brick with a slight tone ramp or scale drift) read at most 0.039 on their worse axis,
#: the broken ones 0.059 and more (``benchmarks/experiments/results/window_gate.md``).
WINDOW_MAX_DIFFERENCE = 0.05

#: A quilt whose two blocks differ along some cut by more than this (mean squared difference over that of
#: two unrelated texels) may be written only where the verdict does not pass it. The window cut's
#: threshold, fixed on window cuts looked at along their wraps (``benchmarks/experiments/results/window_gate.md``);
#: quilts looked at afterwards: the two the verdict passed at or under it are seamless, the three it
#: passed over it (0.10-0.36) show two-tone stones, stepped tone patches and stripes ending at a cut.
QUILT_MAX_DIFFERENCE = WINDOW_MAX_DIFFERENCE


def joins_hide(figures: dict) -> bool:
    """Whether the joins of a quilt, or of a mend of a texture with long lines, hide: the two sides agree along
    every cut to within QUILT_MAX_DIFFERENCE (its ``difference_worst``). Where they do not, the verdict passed
    seamed quilts (two-tone stones, tone patches, stripes ending at a cut:
    ``benchmarks/experiments/results/quilt_gate.md``) and the mend of curved stripes whose lines end in its band
    (``tests/test_synthesis_mend.py``)."""
    return figures["difference_worst"] <= QUILT_MAX_DIFFERENCE


def written_lattice_ratio(lattice: dict, layout_kind: str | None) -> float | None:
    """The lattice ratio of the written tile, from ``MadeTile.lattice`` and ``MadeTile.layout_kind`` (as
    recorded, e.g. in a cached stack's metadata); None when the stack does not repeat."""
    cut = layout_kind in ("lattice", "window", "quilt", "mend")  # the cut's figures carry no suffix
    return lattice.get("lattice_ratio" if cut else f"lattice_ratio_{layout_kind}")


def structure_advice(lattice: dict, layout_kind: str | None) -> str | None:
    """What would help a stack whose written tile's joins cannot hide, from ``MadeTile.lattice`` and
    ``MadeTile.layout_kind`` as recorded; None for any other. Such a stack neither repeats (no lattice) nor
    continues itself at a window's lags (its window was refused), and what was written is a mend, the refined
    tile or a quilt whose blocks differ along a cut: every lever measured on such stacks leaves joins that show
    (two-tone stones, stepped tone patches, jogging courses, stripes that end;
    ``benchmarks/experiments/results/levers*.md``). Every join is drawn from the source itself, so what helps is
    more of the same surface to draw from, or a source made to repeat; never retouching by hand, which a
    stochastic texture (gravel, grass, soil) does not need."""
    refused = lattice.get("window_refused")
    if refused is None or any(p is not None for p in lattice.get("period_px") or []):
        return None
    if layout_kind == lattice.get("cut") and lattice.get("passes"):  # the cut written passed
        return None
    if layout_kind == "quilt" and joins_hide(lattice):
        return None
    lags = ", ".join(f"{axis} {value:.2f}" for axis, value in refused["lag_difference"].items())
    return (f"the texture neither repeats nor continues itself (its window lags differ by {lags}; a cut hides at "
            f"{refused['most']:.2f} or less), so joins between copies of it show: a larger photo of the same "
            "surface (more to draw each join from) or a source made to repeat would help")
