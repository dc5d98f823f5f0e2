"""A labelled corpus of textures judged on their own (``seamless-usd check`` on a picture, the scan's triage).

Every item is one picture in the network domain ``[-1, 1]`` (``(H, W, C)``), seamless or seamed by
construction, with no separate source. The textures are real: the periodic MaterialX maps of
``../shared/textures`` (each tiles as a whole; colour, scalar and a normal map), the MaterialX weave photo
(``cloth``, which does not tile), scikit-image's brick, grass and gravel photos (512 px, grey, which do not
tile) and periodic random-phase noise.

Seamless by construction (only from textures that tile)
    ``rolled``    the whole texture at the item's size (whole-period area filter), rolled anywhere;
    ``halved``    the same rolled by exactly half on both axes;
    ``turned``    turned by 90 degrees, then rolled;
    ``noise``     periodic random-phase noise (power-law spectra, some anisotropic).
Seamed by construction
    ``window``    a plain window of a photo, or an off-grid window of a periodic texture (its wrap joins
                  places that are not neighbours);
    ``half-roll`` a window rolled by half: its wrap is clean, its seams run through the middle;
    ``splice``    a seamless texture with a strip from elsewhere spliced in off-centre (two interior seams);
    ``crossfade`` a window whose borders are crossfaded over an eighth of it (a ghosted band, as quick
                  "make seamless" scripts do);
    ``lit``       a seamless texture under a tone ramp across it (a photo lit unevenly): its wrap steps in
                  tone only, as a lit photo's seam looks at 1x.

Split: the *tuning* part is the MaterialX brick colour and wood colour, the grass photo and noise of
exponent 2; everything else (brick mask, roughness and normal, wood roughness, the weave, the brick and
gravel photos, the other noise) is *held back*: never looked at while choosing a rule's settings.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

from baselines import crossfade_tile  # noqa: E402
from verdict_corpus import noise  # noqa: E402

SHARED = ROOT.parent / "shared" / "textures"
PERIODIC = ("brick_base_gray", "wood_color", "brick_mask", "brick_roughness", "brick_normal", "wood_roughness")
PHOTOS = ("grass", "cloth", "brick", "gravel")  # do not tile
NOISE = ((2.0, 1.0), (3.0, 1.0), (2.5, 3.0), (1.6, 1.0))  # (exponent, anisotropy)
TUNING = frozenset({"brick_base_gray", "wood_color", "grass", "noise2"})
SEAMLESS = ("rolled", "halved", "turned", "noise")
SEAMED = ("window", "half-roll", "splice", "crossfade", "lit")
SIZES = (128, 256, 512)


@dataclass
class Item:
    name: str
    family: str
    kind: str
    seamless: bool
    picture: np.ndarray  # (H, W, C) float32 in [-1, 1]
    is_normal: bool = False

    @property
    def split(self) -> str:
        return "tuning" if self.family in TUNING else "held-back"


def _read(path: Path) -> np.ndarray:
    buf = oiio.ImageBuf(str(path))
    spec = buf.spec()
    a = buf.get_pixels(oiio.FLOAT).reshape(spec.height, spec.width, spec.nchannels)
    return (2.0 * a - 1.0).astype(np.float32)


def _area(a: np.ndarray, side: int) -> np.ndarray:
    """``a`` reduced to ``side`` px by whole-bin means (a periodic texture stays periodic)."""
    k = a.shape[0] // side
    assert k * side == a.shape[0] == a.shape[1], f"{a.shape} is not a square multiple of {side}"
    return a.reshape(side, k, side, k, a.shape[2]).mean(axis=(1, 3)).astype(np.float32)


def _photo(name: str) -> np.ndarray:
    if name == "cloth":
        return _read(SHARED / "cloth.jpg")
    from skimage import data

    return (getattr(data, name)().astype(np.float32)[..., None] / 127.5 - 1.0).astype(np.float32)


def _crop(a: np.ndarray, size: int, rng: np.random.Generator, periodic: bool) -> np.ndarray:
    """A ``size`` window at an arbitrary origin: wrapping on a periodic texture, inside a photo."""
    h, w = a.shape[:2]
    if periodic:
        y, x = rng.integers(0, h), rng.integers(0, w)
        return np.take(np.take(a, np.arange(y, y + size) % h, 0), np.arange(x, x + size) % w, 1)
    y, x = rng.integers(0, h - size + 1), rng.integers(0, w - size + 1)
    return np.ascontiguousarray(a[y:y + size, x:x + size])


def _roll(a: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    n = a.shape[0]
    return np.roll(a, (int(rng.integers(1, n)), int(rng.integers(1, n))), (0, 1))


def _splice(base: np.ndarray, other: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    n = base.shape[0]
    out = base.copy()
    width = int(n * rng.uniform(0.12, 0.3))
    at = int(rng.integers(n // 8, n - width - n // 8))
    if rng.uniform() < 0.5:
        out[:, at:at + width] = other[:, at:at + width]
    else:
        out[at:at + width] = other[at:at + width]
    return out


def _lit(a: np.ndarray, amount: float) -> np.ndarray:
    n = a.shape[0]
    yy, xx = np.mgrid[0:n, 0:n] / n
    return np.clip(a + (amount * (xx - 0.5) + 0.5 * amount * (yy - 0.5))[..., None], -1, 1).astype(np.float32)


def _unit(a: np.ndarray, is_normal: bool) -> np.ndarray:
    if not is_normal:
        return a
    return (a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), 1e-6)).astype(np.float32)


def build(sizes: tuple[int, ...] = SIZES, seed: int = 0) -> list[Item]:
    """Every item of the corpus (see the module notes), deterministic for a seed."""
    rng = np.random.default_rng(seed)
    items: list[Item] = []

    def add(family: str, kind: str, size: int, picture: np.ndarray, is_normal: bool = False) -> None:
        seamless = kind in SEAMLESS
        items.append(Item(f"{family}-{size}-{kind}", family, kind, seamless,
                          _unit(np.ascontiguousarray(picture, np.float32), is_normal), is_normal))

    for name in PERIODIC:
        if not (SHARED / f"{name}.jpg").exists():
            continue
        full = _read(SHARED / f"{name}.jpg")
        normal = name == "brick_normal"
        for size in sizes:
            whole = _area(full, size)
            add(name, "rolled", size, _roll(whole, rng), normal)
            add(name, "halved", size, np.roll(whole, (size // 2, size // 2), (0, 1)), normal)
            if not normal:  # a turned normal map's x and y would need swapping and flipping
                add(name, "turned", size, _roll(np.rot90(whole).copy(), rng))
            # an off-grid window: 0.6-0.9 of a period at the item's texel scale, anywhere
            win = _crop(_area(full, size), int(size * rng.uniform(0.6, 0.9)), rng, periodic=True)
            add(name, "window", size, win, normal)
            add(name, "half-roll", size, np.roll(win, (size // 2, size // 2), (0, 1)), normal)
            add(name, "splice", size, _splice(_roll(whole, rng), _roll(whole, rng), rng), normal)
            if not normal:
                add(name, "crossfade", size, crossfade_tile(win))
                add(name, "lit", size, _lit(_roll(whole, rng), float(rng.uniform(0.15, 0.3))))
    for name in PHOTOS:
        if name == "cloth" and not (SHARED / "cloth.jpg").exists():
            continue
        photo = _photo(name)
        for size in (s for s in sizes if s < min(photo.shape[:2])):
            win = _crop(photo, size, rng, periodic=False)
            add(name, "window", size, win)
            add(name, "half-roll", size, np.roll(_crop(photo, size, rng, periodic=False), (size // 2, size // 2), (0, 1)))
            add(name, "crossfade", size, crossfade_tile(win))
    for beta, aniso in NOISE:
        family = f"noise{beta:g}" + ("a" if aniso != 1.0 else "")
        for size in sizes:
            add(family, "noise", size, noise(size, beta, aniso, int(rng.integers(1 << 30))))
            other = noise(size, beta, aniso, int(rng.integers(1 << 30)))
            add(family, "splice", size, _splice(noise(size, beta, aniso, int(rng.integers(1 << 30))), other, rng))
            add(family, "lit", size, _lit(noise(size, beta, aniso, int(rng.integers(1 << 30))), 0.25))
    return items
