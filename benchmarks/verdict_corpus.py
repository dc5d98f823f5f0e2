"""A labelled corpus of tiles, seamless or seamed by construction, for ``benchmarks/verdict.py``.

Every item is a tile (one map or a stack of maps, network domain ``[-1, 1]``), the source it was made
from at the same texel scale, and its label. The textures are the periodic MaterialX maps in
``../shared/textures`` (each one tiles as a whole) and synthetic periodic noise.

Seamless by construction
    ``rolled``      a whole period of a tileable texture, rolled by an arbitrary offset (not for the cloth
                    photo, which does not tile as a whole);
    ``noise``       periodic random-phase noise (power-law spectra, some anisotropic);
    ``lattice``     the product's lattice cut of an off-grid window of a repeating texture;
    ``refined``     the product's toroidal refinement of a window (random start), looked at and judged:
                    seamless on the wood roughness, blocky (broken courses, threads, grain cut
                    by hard block ends at 3x) on the bricks, the weave and the wood colour.
    ``lattice-blended`` the lattice cut with a band of 3 texels around its joins blended in the
                    gradient domain (the refinement's ``blend``): a seamless cut stays seamless.
    ``blended``     the refined tile's field with its joins blended the same way, looked at and judged
                    (3 x 3 repeats at 1x and 3x).
    ``lattice-lit`` the lattice cut of the brick lit unevenly (a tone ramp across the source), looked at
                    (join bands at 3x): seamless at a ramp of 0.02, seamed at 0.05, where the cut crosses
                    bricks of two tones (held back: the verdict was not tuned on it).
Seamed by construction
    ``naive``       an off-grid window used as its own tile (a seam at the wrap);
    ``splice``      a tileable texture with a strip from elsewhere spliced in (two interior seams);
    ``half-roll``   an off-grid window rolled by half its size (seams on the centre lines);
    ``crossfade``   the linear border crossfade of a window (a ghosted band);
    ``blocky``      a mosaic of 12-40 px blocks copied from the source with no care for their edges.
    ``blocky-blended`` the same mosaic with a band of 3 texels around its blocks' edges blended: the
                    tone steps go, the structure stays cut.

The source of each item is an off-grid window of the same texture at the tile's texel scale, 1.15-1.4
periods long, so it holds every texel of a tile made from the texture and does not tile itself.

Split: items from ``brick_base_gray``, ``wood_color`` and noise of exponent 2 and 3 are the *tuning*
part; everything else (``brick_roughness``, ``brick_normal``, ``wood_roughness``, ``cloth``,
``brick_mask``, the three-map brick stack and the other noise) is *held back*: never looked at while
choosing the verdict's settings.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from baselines import crossfade_tile  # noqa: E402

SHARED = ROOT.parent / "shared" / "textures"
TUNING = ("brick_base_gray", "wood_color", "noise2", "noise3")
SEAMLESS = ("rolled", "noise", "lattice", "refined")
#: The random-start refinements looked at (3 x 3 repeats at 1x, and zoomed 3x) and judged seamless: the
#: wood roughness. On the bricks and the weave the refinement breaks the courses and threads along the
#: copied blocks' edges, and the wood colour shows the blocks' hard vertical ends across its grain at 3x:
#: blocky refinements, labelled seamed.
REFINED_SEAMLESS = frozenset({"wood_roughness"})
#: The same refinements with their joins blended, looked at the same way and judged seamless.
BLENDED_SEAMLESS = frozenset({"wood_roughness"})
#: Tone ramps (network units across the source) of the unevenly lit brick whose lattice cuts were looked at:
#: at 0.02 the bricks along the cut keep one tone; at 0.05 the cut crosses bricks and splits their tone
#: diagonally (seen at 3x).
LIT_LATTICE = {0.02: True, 0.05: False}
#: Width (texels) of the blended band in the ``*-blended`` items: the refinement's ``blend`` lever as measured.
BAND = 3
SEAMLESS = SEAMLESS + ("lattice-blended",)
SEAMED = ("naive", "splice", "half-roll", "crossfade", "blocky", "blocky-blended")


@dataclass
class Item:
    name: str
    family: str  # texture or noise family
    kind: str  # how it was made (see the module notes)
    seamless: bool
    tile: list[np.ndarray]
    source: list[np.ndarray]
    normals: list[bool]
    split: str = "tuning"
    notes: dict = field(default_factory=dict)


_CACHE: dict[tuple[str, int], np.ndarray] = {}


def texture(name: str, side: int) -> np.ndarray:
    """A whole periodic texture resized to ``side`` (periodic area filter), network domain."""
    key = (name, side)
    if key not in _CACHE:
        buf = oiio.ImageBuf(str(SHARED / f"{name}.jpg"))
        spec = buf.spec()
        a = buf.get_pixels(oiio.FLOAT).reshape(spec.height, spec.width, spec.nchannels)
        k = spec.width // side  # whole-period box filter: the sizes used divide the textures' own
        assert k * side == spec.width, f"{name}: {spec.width} px is not a multiple of {side}"
        a = a.reshape(side, k, side, k, spec.nchannels).mean(axis=(1, 3))
        _CACHE[key] = (2.0 * a - 1.0).astype(np.float32)
    return _CACHE[key]


def lit_brick(kind: str, amount: float) -> np.ndarray:
    """The MaterialX brick's base colour (one period at 512 px) over 1.3 periods, with a tone ramp of
    ``amount`` (network units across the window, half that down it: a wall lit unevenly) or a scale drifting
    by ``amount`` across it (perspective-like): a texture that repeats less exactly as ``amount`` grows."""
    from scipy import ndimage

    base = texture("brick_base_gray", 512)
    n = int(512 * 1.3)
    yy, xx = np.mgrid[0:n, 0:n].astype(np.float64)
    scale = 1 + amount * xx / n if kind == "drift" else 1.0
    out = np.stack([ndimage.map_coordinates(base[..., c], [yy * scale, xx * scale], order=3, mode="wrap")
                    for c in range(base.shape[2])], -1)
    if kind == "ramp":
        out = np.clip(out + ((xx / n - 0.5) * 2 * amount + (yy / n - 0.5) * amount)[..., None], -1, 1)
    return out.astype(np.float32)


def noise(side: int, beta: float, aniso: float, seed: int) -> np.ndarray:
    """Periodic random-phase noise with power ~ 1 / f^beta (stretched by ``aniso`` along x)."""
    rng = np.random.default_rng(seed)
    fy = np.fft.fftfreq(side)[:, None]
    fx = np.fft.rfftfreq(side)[None, :] * aniso
    f = np.sqrt(fx ** 2 + fy ** 2)
    f[0, 0] = 1.0
    amp = f ** (-beta / 2.0)
    amp[0, 0] = 0.0
    spec = amp * np.exp(2j * np.pi * rng.uniform(size=amp.shape))
    u = np.fft.irfft2(spec, s=(side, side))
    u = (u - u.mean()) / (3.0 * u.std())
    return np.clip(u, -1, 1).astype(np.float32)[..., None]


def window(t: np.ndarray, size: int, rng: np.random.Generator) -> np.ndarray:
    """An off-grid ``size`` window of a periodic texture (wrapping), at an arbitrary origin."""
    n = t.shape[0]
    y, x = rng.integers(0, n, 2)
    return np.take(np.take(t, np.arange(y, y + size) % n, 0), np.arange(x, x + size) % n, 1)


def _rolled(t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return np.roll(t, tuple(rng.integers(1, t.shape[0], 2)), (0, 1))


def _splice(t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    n = t.shape[0]
    out = _rolled(t, rng)
    width = int(n * rng.uniform(0.15, 0.35))
    at = int(rng.integers(n // 8, n - width - n // 8))
    other = window(t, n, rng)
    if rng.uniform() < 0.5:
        out[:, at:at + width] = other[:, at:at + width]
    else:
        out[at:at + width] = other[at:at + width]
    return out


def _blocky_field(shape: tuple[int, int], side: int, rng: np.random.Generator) -> np.ndarray:
    """The (side, side, 2) field of a mosaic of square blocks copied from random places of a ``shape`` source."""
    block = int(rng.integers(max(12, side // 40), max(16, side // 12)))
    field = np.empty((side, side, 2), np.int64)
    hs, ws = shape
    r, c = np.meshgrid(np.arange(block), np.arange(block), indexing="ij")
    for y in range(0, side, block):
        for x in range(0, side, block):
            sy, sx = rng.integers(0, hs - block), rng.integers(0, ws - block)
            h, w = min(block, side - y), min(block, side - x)
            field[y:y + h, x:x + w, 0] = (r + sy)[:h, :w]
            field[y:y + h, x:x + w, 1] = (c + sx)[:h, :w]
    return field


def _through(sources: list[np.ndarray], field: np.ndarray) -> list[np.ndarray]:
    return [np.ascontiguousarray(s[field[..., 0], field[..., 1]], np.float32) for s in sources]


def _blended(sources: list[np.ndarray], field: np.ndarray, normals: list[bool]) -> list[np.ndarray]:
    from seamless_usd.synthesis.refinement.blend import blend_band

    return blend_band(sources, field, BAND, normals)[0]


def _product(kind: str, sources: list[np.ndarray], normals: list[bool], seed: int
             ) -> tuple[list[np.ndarray], np.ndarray] | None:
    """The product's lattice cut or random-start refinement of ``sources`` and its field (None when no
    lattice)."""
    from seamless_usd.synthesis.lattice.cut import find_lattice, lattice_cut, lattice_tile_size
    from seamless_usd.synthesis.refinement.refine import RefineConfig, refine

    if kind == "lattice":
        lat = find_lattice(sources)
        sizes = lattice_tile_size(sources[0].shape[:2], lat) if lat.found else None
        if sizes is None:
            return None
        fld, _ = lattice_cut(sources, *sizes)
        return _through(sources, fld), fld
    result = refine(sources, None, sources[0].shape[:2], RefineConfig(lattice=False), seed=seed)
    return [np.asarray(m, np.float32) for m in result.maps], result.field


def _families(side: int):
    """(family, maps, normals, split) for every texture of the corpus at ``side`` px."""
    for name, normal in (("brick_base_gray", False), ("wood_color", False), ("brick_roughness", False),
                         ("brick_normal", True), ("wood_roughness", False), ("brick_mask", False)):
        yield name, [texture(name, side)], [normal], "tuning" if name in TUNING else "held-back"
    yield "brick_stack", [texture(n, side) for n in ("brick_base_gray", "brick_normal", "brick_roughness")], \
        [False, True, False], "held-back"


def items(sides: tuple[int, ...] = (256, 512), products: bool = True, seed: int = 0):
    """Every corpus item, deterministic for ``seed``; the product's tiles at the first side only (the ones
    looked at)."""
    rng = np.random.default_rng(seed)
    for side in sides:
        for family, maps, normals, split in _families(side):
            yield from _texture_items(family, maps, normals, split, side, rng, products and side == sides[0])
        for beta, aniso, fam in ((2.0, 1.0, "noise2"), (3.0, 1.0, "noise3"), (2.5, 3.0, "noise2.5a"),
                                 (1.6, 1.0, "noise1.6")):
            big = noise(2 * side, beta, aniso, int(rng.integers(1 << 30)))
            tile = noise(side, beta, aniso, int(rng.integers(1 << 30)))
            split = "tuning" if fam in TUNING else "held-back"
            src = [window(big, int(side * 1.25), rng)]
            yield Item(f"{fam}-{side}-noise", fam, "noise", True, [tile], src, [False], split)
            yield Item(f"{fam}-{side}-naive", fam, "naive", False, src, src, [False], split)
            yield Item(f"{fam}-{side}-splice", fam, "splice", False, [_splice(tile, rng)], src, [False], split)
    # the cloth photo (640 px) does not tile as a whole (its wrap reads seam ratios 4.1 and 11.8), though its
    # weave repeats: windows inside it, no rolled or spliced whole
    for side in (320, 640):
        yield from _texture_items("cloth", [texture("cloth", side)], [False], "held-back", side, rng,
                                  products and side == 320, tileable=False)
    if products:  # a wall lit unevenly: the lattice cut joins bricks of two tones (looked at, 3x)
        for amount, seamless in LIT_LATTICE.items():
            src = [lit_brick("ramp", amount)]
            tile, _ = _product("lattice", src, [False], 0)
            yield Item(f"brick_lit-{amount}-lattice", "brick_lit", "lattice-lit", seamless, tile, src, [False],
                       "held-back", {"judged": "by eye, join bands at 3x"})


def _texture_items(family, maps, normals, split, side, rng, products, tileable=True):
    if tileable:
        # the window spans more than one period, so it holds every texel of the tileable texture (a tile
        # made of them is judged against a source that has them all) and does not tile itself
        size = int(side * rng.uniform(1.15, 1.4))
        state = rng.integers(1 << 30)
        wins = [window(m, size, np.random.default_rng(state)) for m in maps]
    else:  # a window inside the picture, never across its own (seamed) wrap
        size = int(side * 0.6)
        y, x = rng.integers(0, side - size, 2)
        wins = [m[y:y + size, x:x + size] for m in maps]
    make = lambda kind, seamless, tile, **notes: Item(f"{family}-{side}-{kind}", family, kind, seamless, tile,
                                                     wins, normals, split, notes)
    if tileable:
        offset = tuple(rng.integers(1, side, 2))
        yield make("rolled", True, [np.roll(m, offset, (0, 1)) for m in maps])
        sp_state = rng.integers(1 << 30)
        yield make("splice", False, [_splice(m, np.random.default_rng(sp_state)) for m in maps])
    yield make("naive", False, wins)
    yield make("half-roll", False, [np.roll(w, (size // 2, size // 2), (0, 1)) for w in wins])
    yield make("crossfade", False, [crossfade_tile(w, n) for w, n in zip(wins, normals)])
    bl_state = rng.integers(1 << 30)
    blocks = _blocky_field(wins[0].shape[:2], size, np.random.default_rng(bl_state))
    yield make("blocky", False, _through(wins, blocks))
    yield make("blocky-blended", False, _blended(wins, blocks, normals))
    if products:
        for kind in ("lattice", "refined"):
            made = _product(kind, wins, normals, int(rng.integers(1 << 16)))
            if made is None:
                continue
            tile, fld = made
            seamless = kind == "lattice" or family in REFINED_SEAMLESS
            yield make(kind, seamless, tile, judged="by eye, 3 x 3 repeats")
            if kind == "lattice":
                yield make("lattice-blended", True, _blended(wins, fld, normals))
            else:
                yield make("blended", family in BLENDED_SEAMLESS, _blended(wins, fld, normals),
                           judged="by eye, 3 x 3 repeats")
