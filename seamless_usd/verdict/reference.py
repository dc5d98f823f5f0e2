"""What the verdict reads, prepared once: a source stack (:class:`Reference`) and a tile read against it
(:class:`Reading`).

A stack's source is judged against many times (each candidate tile, then the written tile, then its join
figures), and a written tile is read twice (its verdict and its join figures). Each of these needs the maps in
the verdict's working form (:func:`.prepare.prepare_maps`, side by side in one joint array), the source's
neighbourhood index (:class:`.copies.SourceIndex`), its mean neighbour steps and, for the tile, where each of its
texels was copied from (:func:`.copies.copy_origins`). Made here once, and passed down.
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from .copies import INFER, SourceIndex, copy_origins, step_unit
from .prepare import joint, joined, map_weights, prepare_maps, to_working
from .tone import tone_reference
from .visibility import CODE_8BIT

__all__ = ["Reference", "Reading"]


class Reference:
    """A source stack (maps in the network domain, at the tile's texel scale) prepared for the verdict.

    >>> ref = Reference([np.zeros((16, 16, 3)), np.ones((16, 16))], [False, False], ["albedo", "rough"])
    >>> ref.joint.shape, [m.shape for m in ref.maps]
    ((16, 16, 4), [(16, 16, 3), (16, 16, 1)])
    """

    def __init__(self, sources: list[np.ndarray], normals: list[bool], names: list[str], keep_index: bool = True):
        if not (len(sources) == len(normals) == len(names)):
            raise ValueError(f"{len(sources)} sources, {len(normals)} normal flags and {len(names)} names: one each")
        self.sources = list(sources)  # as given, for the fidelity figures
        self.normals = list(normals)
        self.names = list(names)
        self.joint, self.maps = joined(prepare_maps(self.sources, self.normals))  # per-map views of one array
        # False: the index is let go once one tile's copies are looked up (a 4K source's index is 0.27 GB),
        # for a reference read against a single tile
        self.keep_index = keep_index
        self._units: dict[int | None, dict[int, float]] = {}
        self._tone: dict[float, tuple[list[float], dict[str, float]]] = {}

    @cached_property
    def index(self) -> SourceIndex:
        """The maps' joint 3 x 3 neighbourhoods, sorted for looking copies up."""
        return SourceIndex(self.joint)

    def units(self, which: int | None = None) -> dict[int, float]:
        """The mean neighbour step by axis (:func:`.copies.step_unit`) of the maps together (``which`` None) or of
        map ``which``."""
        if which not in self._units:
            source = self.joint if which is None else np.ascontiguousarray(self.maps[which])
            self._units[which] = {axis: step_unit(source, axis) for axis in (0, 1)}
        return self._units[which]

    def tone(self, factor: float) -> tuple[list[float], dict[str, float]]:
        """At the working resolution ``factor``: each map's weight in the joint image (:func:`.prepare.map_weights`)
        and the source's strongest strip steps (:func:`.tone.tone_reference`) of that image."""
        if factor not in self._tone:
            working = to_working(self.maps, factor, periodic=False)
            weights = map_weights(working)
            self._tone[factor] = (weights, tone_reference(joint(working, weights)))
        return self._tone[factor]


class Reading:
    """A tile (its maps, in the source's order) prepared for the verdict, against ``reference`` (None: a texture
    judged on its own)."""

    def __init__(self, tiles: list[np.ndarray], normals: list[bool], names: list[str],
                 reference: Reference | None = None, codes: list[float] | None = None):
        if reference is not None and (reference.normals != list(normals) or len(reference.names) != len(tiles)):
            raise ValueError("the tile's maps must be the reference's maps, in its order")
        #: each map's code value in network units (one step of its file: 2 / 255 for 8 bits, 0 for half and float),
        #: which decides how small a step can be seen in it (:func:`.visibility.floor`); 8-bit where not given
        self.codes = list(codes) if codes is not None else [CODE_8BIT] * len(tiles)
        self.tiles = list(tiles)
        self.normals = list(normals)
        self.names = list(names)
        self.reference = reference
        self.joint, self.maps = joined(prepare_maps(self.tiles, self.normals))

    @property
    def size(self) -> tuple[int, int]:
        return tuple(int(v) for v in self.maps[0].shape[:2])

    @cached_property
    def origins(self) -> tuple[np.ndarray, float]:
        """Where each texel was copied from in the reference (``(H, W, 2)``, -1 where none is placed), and the
        share found exactly (:func:`.copies.copy_origins`, with blended bands inferred)."""
        if self.reference is None:
            raise ValueError("a texture judged on its own has no source to look copies up in")
        found = copy_origins(self.joint, self.reference.joint, INFER, self.reference.index)
        if not self.reference.keep_index:
            del self.reference.index
        return found
