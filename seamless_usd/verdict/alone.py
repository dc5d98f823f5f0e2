"""A texture judged on its own, read from its files: the one reading that ``check`` and the scan's triage share,
so that both give the same answer on the same files.

Each file is decoded at its smallest MIP level still at least :data:`READ_SIDE` px, its channels in use are kept
(alpha only when a role reads it), and it is reduced to at most :data:`READ_SIDE` px with bins that cover the
whole image (:func:`reduce_bins`: a periodic texture stays periodic, its wrap is not blurred into its far side).
The maps, in the verdict's domain (``2 v - 1`` of the file values), are judged against themselves by
:func:`.judge.judge`, and the seams are given back in texels of the full-size file.

Maps of one stack at different resolutions but one aspect are brought to the smallest one's reading and judged
together; maps of different aspects are judged each alone.
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from seamless_usd.errors import InputError
from seamless_usd.findings import asset_ref
from seamless_usd.memo import ContentMemo

from .judge import Verdict, judge
from .lines import Seam

__all__ = ["READ_SIDE", "MIN_SIDE", "FileMap", "reduce_bins", "read_alone", "judge_alone", "normal_doubts",
           "file_map", "left_unread"]

#: Longest side (px) a texture judged on its own is read at: the line breaks read lines at this size.
READ_SIDE = 512
#: Shortest side (px) of a reading that is judged: below it the line figures have too few lines and texels to
#: stand on (at 32 px a smooth tileable noise read a seam 30 times over the margin, and some pictures none at
#: all); at 64 px the held-back textures of ``benchmarks/texture_verdict.py`` read 64 % / 82 % right.
MIN_SIDE = 64


@dataclass(frozen=True)
class FileMap:
    """One file of a texture judged on its own: its path, the channels read (``"rgb"``, ``"r"``, ``"rgba"``...),
    whether it is a normal map, and its name in the verdict."""

    path: str
    channels: str = "rgb"
    is_normal: bool = False
    name: str = ""
    scale: tuple = ()  # a normal map's authored scale and bias (4 values each; none: the conventional 2 and -1),
    bias: tuple = ()  # which bring its file values to vectors, as the shader and ``process`` read them


def reduce_bins(a: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The mean over near-equal bins covering the whole image, ``shape`` bins per axis (at most the image's own
    size): a periodic image stays periodic.

    >>> reduce_bins(np.arange(16.0).reshape(4, 4, 1), (2, 2))[..., 0]
    array([[ 2.5,  4.5],
           [10.5, 12.5]])
    """
    for axis in (0, 1):
        n = a.shape[axis]
        k = min(shape[axis], n)
        edges = np.round(np.linspace(0, n, k + 1)).astype(int)
        counts = np.diff(edges)
        bins = [1] * a.ndim
        bins[axis] = -1
        step = max(1, k * (1 << 22) // max(1, a.size))  # bins a part: summed in float64 without a float64 copy
        parts = []
        for i in range(0, k, step):
            where = [slice(None)] * a.ndim
            where[axis] = slice(edges[i], edges[min(k, i + step)])
            parts.append(np.add.reduceat(a[tuple(where)], edges[i:min(k, i + step)] - edges[i], axis=axis,
                                         dtype=np.float64))
        a = np.concatenate(parts, axis=axis) / counts.reshape(bins)
    return a


def file_map(m) -> FileMap:
    """The :class:`FileMap` of a stack's map (a ``TextureMap``): its file, the channels its roles read, and a normal
    map's scale and bias. ``check`` and the scan's triage judge a stack so."""
    normal = m.is_normal
    return FileMap(m.resolved, m.channels_used, normal, m.asset, tuple(m.scale) if normal else (),
                   tuple(m.bias) if normal else ())


def _reading_shape(h: int, w: int, side: int = READ_SIDE) -> tuple[int, int]:
    f = min(1.0, side / max(h, w))
    return max(1, round(h * f)), max(1, round(w * f))


def read_alone(m: FileMap) -> tuple[np.ndarray, tuple[int, int], float]:
    """The file's channels in use, reduced to at most :data:`READ_SIDE` px, in the verdict's domain, its full size
    ``(h, w)`` and one code value of the file in that domain (0 for half and float files: see
    :func:`.visibility.floor`). Raises :class:`InputError` naming the file when it cannot be read or holds NaN / inf
    texels."""
    from seamless_usd.imaging import read_image
    from seamless_usd.imaging.io import alpha_channel

    pixels, info = read_image(m.path, min_side=READ_SIDE, stored=True)  # a large picture is reduced as stored
    alpha = alpha_channel(info) if info.channels > 1 else None
    colour = [i for i in range(info.channels) if i != alpha]
    picks: list[int] = []
    for c in m.channels:
        k = alpha if c == "a" else (colour["rgb".index(c)] if "rgb".index(c) < len(colour) else None)
        if k is not None and k not in picks:
            picks.append(k)
    a = pixels[..., picks or colour[:1] or [0]]
    if a.dtype.kind == "f" and not np.isfinite(a).all():
        bad = int((~np.isfinite(a)).sum())
        raise InputError(f"{asset_ref(m.path)}: {bad} {'texel is' if bad == 1 else 'texels are'} NaN or infinite; it "
                         f"cannot be judged until {'it is' if bad == 1 else 'they are'} replaced (re-export the image)")
    reduced = reduce_bins(a, _reading_shape(*a.shape[:2]))  # summed in float64
    top = float(np.iinfo(a.dtype).max) if a.dtype.kind == "u" else 1.0  # file values: an integer code over its largest
    reduced = reduced / top
    vectors = _normal_decoding(m, info, a, top) if m.is_normal and a.shape[-1] >= 3 else None
    if m.is_normal and a.shape[-1] < 3:  # read as plain values (:func:`_judge_alone`), as ``process`` reads it
        _DOUBTS[_doubt_key(m)] = (f"does not read as a normal map: it has {a.shape[-1]} channel(s) in use, not the "
                                  "three (x, y, z) of one; it is judged as plain values (check the file wired to the "
                                  "normal input)")
    code = 2.0 / top if a.dtype.kind == "u" else 0.0
    if vectors is None:
        return 2.0 * reduced - 1.0, (info.height, info.width), code
    scale, bias = vectors  # a normal map's xyz as the vectors it holds (the same as 2 v - 1 for the usual encoding)
    reduced[..., :3] = reduced[..., :3] * np.asarray(scale) + np.asarray(bias)
    reduced[..., 3:] = 2.0 * reduced[..., 3:] - 1.0
    return reduced, (info.height, info.width), code


#: Why each normal map read does not read as one (None: it does), by its file and decoding: said by ``check`` and the
#: scan's triage, which read the file once.
_DOUBTS: dict[tuple, str | None] = {}


def _normal_decoding(m: FileMap, info, a: np.ndarray, top: float):
    """The xyz scale and bias of a normal map's file values (as ``process`` decodes them: the authored ones, the
    conventional ones when none, a signed float file as stored), with why it does not read as a normal map kept
    for :func:`normal_doubts`; None when they cannot be had (a zero scale: ``process`` says so)."""
    from seamless_usd.imaging.normals import encoding_doubt, normal_scale_bias, signed_as_stored

    scale4, bias4 = (m.scale or (1.0, 1.0, 1.0, 1.0)), (m.bias or (0.0, 0.0, 0.0, 0.0))
    step = max(1, max(a.shape[:2]) // 64)
    sample = np.asarray(a[::step, ::step, :3], np.float64) / top
    try:
        scale, bias = normal_scale_bias(scale4, bias4)
    except ValueError:
        return None
    if signed_as_stored(scale4, bias4, info.dtype, sample):
        scale, bias = (1.0, 1.0, 1.0), (0.0, 0.0, 0.0)
    if len(_DOUBTS) > 4096:
        _DOUBTS.clear()
    _DOUBTS[_doubt_key(m)] = encoding_doubt(sample, scale, bias)
    return scale, bias


def _doubt_key(m: FileMap) -> tuple:
    try:
        st = os.stat(m.path)
    except OSError:
        return (m.path, m.scale, m.bias)
    return (os.path.realpath(m.path), st.st_size, st.st_mtime_ns, m.scale, m.bias)


def normal_doubts(maps: Sequence[FileMap]) -> list[str]:
    """For each normal map of ``maps`` that does not read as a tangent-space normal map with its scale and bias (a
    colour photo wired as a normal, a signed float map read as 0-1): why, naming it
    (:func:`seamless_usd.imaging.normals.encoding_doubt`, which ``process`` warns with too)."""
    out = []
    for m in maps:
        if not m.is_normal:
            continue
        key = _doubt_key(m)
        if key not in _DOUBTS:
            try:
                read_alone(m)
            except (InputError, ValueError, OSError, RuntimeError):
                continue
        doubt = _DOUBTS.get(key)
        if doubt:
            out.append(f"{asset_ref(m.name or m.path)} {doubt}")
    return out


def left_unread(m: FileMap, info) -> str:
    """What of ``m``'s file (``info``: its header, :func:`seamless_usd.imaging.io.read_info`; None when unreadable)
    its reading (:func:`read_alone`) leaves out, in words, or "": its alpha when only colour is read, channels beyond
    colour and alpha (an OpenEXR's other layers, a depth channel), and every part after the first (a multi-part
    OpenEXR, a multi-page TIFF). ``check`` says so beside its answer."""
    from seamless_usd.imaging.io import alpha_channel, image_count

    if info is None:
        return ""  # the reading names why it cannot be read
    parts = image_count(m.path)
    names = (info.channel_names if len(info.channel_names) == info.channels
             else tuple(str(i) for i in range(info.channels)))
    alpha = alpha_channel(info) if info.channels > 1 else None
    if alpha is not None and names[alpha].lower() not in ("a", "alpha", str(alpha)):
        alpha = None  # a named channel that is not alpha (an OpenEXR's Z): one more channel
    colour = [i for i in range(info.channels) if i != alpha]
    read = set(colour[:3] if m.is_normal or "r" in m.channels or not m.channels else [])
    read |= {alpha} if alpha is not None and "a" in m.channels else set()
    left = []
    if alpha is not None and alpha not in read:
        left.append("its alpha channel")
    extra = [names[i] for i in colour[3:]]
    if extra:
        left.append(f"its other channel(s) {', '.join(extra[:6])}{', ...' if len(extra) > 6 else ''}")
    if parts > 1:
        left.append(f"{'its second image' if parts == 2 else f'its images 2-{parts}'} (the file holds {parts}; "
                    "only the first is read)")
    return f"not judged: {'; '.join(left)}" if left else ""


def _scaled(v: Verdict, reduced: tuple[int, int], full: tuple[int, int]) -> Verdict:
    """``v`` (found on a reading of ``reduced`` size) with its seams in texels of the ``full`` size."""
    sy, sx = full[0] / reduced[0], full[1] / reduced[1]

    def scale(s: Seam) -> Seam:
        across, along = (sx, sy) if s.axis == "x" else (sy, sx)
        limit = (full[0] if s.axis == "x" else full[1]) - 1
        return Seam(s.axis, int(round(s.position * across)) % (full[1] if s.axis == "x" else full[0]),
                    int(s.start * along), min(limit, int((s.end + 1) * along) - 1), s.figure, s.map)

    v.seams = [scale(s) for s in v.seams]
    v.size = full
    return v


#: Verdicts by the files they were given for (path, size, modification time, channels, normal, name): the scan's
#: triage and ``check`` on the same stage judge the same files once. A verdict is a few hundred bytes.
_VERDICTS: ContentMemo[dict] = ContentMemo(keep=1024)


def _stamp(maps: Sequence[FileMap]) -> tuple | None:
    try:
        stats = [os.stat(m.path) for m in maps]
    except OSError:
        return None
    return tuple((os.path.realpath(m.path), st.st_size, st.st_mtime_ns, m.channels, m.is_normal, m.name, m.scale,
                  m.bias) for m, st in zip(maps, stats))


def judge_alone(maps: Sequence[FileMap]) -> tuple[Verdict, np.ndarray]:
    """The verdict on the files ``maps`` judged against themselves (seams in texels of the first map's full size),
    and the first map's reading (for a thumbnail). Raises :class:`InputError` on a file that cannot be read and
    ``ValueError`` on one too small to judge. The same unchanged files are judged once per process."""
    key = _stamp(maps)
    if key is None:
        return _judge_alone(maps)
    made: list[tuple[Verdict, np.ndarray]] = []

    def compute() -> dict:
        made.append(_judge_alone(maps))
        return made[0][0].as_dict()

    kept = _VERDICTS.get_keyed(key, compute)
    if made:  # judged now: its reading is at hand
        return made[0]
    return Verdict.from_dict(kept), read_alone(maps[0])[0]


def _judge_alone(maps: Sequence[FileMap]) -> tuple[Verdict, np.ndarray]:
    read = [read_alone(m) for m in maps]
    for m, (pixels, full, _) in zip(maps, read):
        if min(pixels.shape[:2]) < MIN_SIDE:
            thin = min(full) >= MIN_SIDE  # both sides large enough, but read at READ_SIDE across it is too thin
            why = (f"a strip thinner than 1:{READ_SIDE // MIN_SIDE} is too thin to be judged on its own: read at "
                   f"{READ_SIDE} px across, as the verdict reads a texture with no separate source, its short side "
                   f"falls under {MIN_SIDE} px; judge it against its source (a tile this tool wrote is) or in square "
                   f"pieces") if thin else (
                   f"too small to be judged on its own (a texture with no separate source is judged from {MIN_SIDE} "
                   f"px on each side)")
            raise ValueError(f"{asset_ref(m.path)}: {full[1]} x {full[0]} px: {why}")
    names = [m.name or m.path for m in maps]
    normals = [m.is_normal and p.shape[-1] >= 3 for m, (p, _, _) in zip(maps, read)]  # xyz vectors, as process reads
    shapes = [p.shape[:2] for p, _, _ in read]
    same_aspect = all(abs(h * shapes[0][1] - w * shapes[0][0]) <= max(h, w, *shapes[0]) for h, w in shapes)
    if same_aspect:
        common = min(shapes, key=lambda s: s[0] * s[1])
        pixels = [p if p.shape[:2] == common else reduce_bins(p, common) for p, _, _ in read]
        v = judge(pixels, None, normals, names, fidelity=False, codes=[c for _, _, c in read])
        return _scaled(v, common, read[0][1]), read[0][0]
    # each map alone, its seams at the same place in the texture (UV) given in texels of the first map
    verdicts = [_scaled(judge([p], None, [normal], [n], fidelity=False, codes=[c]), p.shape[:2], read[0][1])
                for (p, _, c), normal, n in zip(read, normals, names)]
    seams = sorted((s for v in verdicts for s in v.seams), key=lambda s: -s.figure)
    first = verdicts[0]
    return Verdict(not seams, True, seams, max(v.strongest for v in verdicts), first.margin, "itself",
                   first.method, first.size), read[0][0]
