"""The variant space of a stage: every selection of its variant sets, nested sets included.

Production assets keep their looks in variant sets (a ``shadingVariant`` inside a
``modelVariant``, inside a payload), and most of those variants are not the selected ones. A
material found only under another selection, or bound only there, must be judged under that
selection. :class:`VariantSpace` composes a private copy of the stage (same root layer, its own
session layer) under each selection in turn:

- ``all``: every combination, depth first, nested sets as their parents' selections reveal them,
  the stage's own selection first; used while there are at most ``limit`` combinations;
- ``each-set``: beyond that, one set at a time from the stage's own selection (its nested sets
  from the selection that reveals them): a linear walk that names what it left out.

Variant sets on instance proxies are not explored (a selection cannot be set inside a prototype).
"""
from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

from pxr import Sdf, Usd

from seamless_usd.textures import Selection, VariantChoice

__all__ = ["VariantSpace", "apply_selection", "private_stage", "MAX_COMBINATIONS"]

MAX_COMBINATIONS = 256  # above this many combinations the space is walked one set at a time


def private_stage(stage: Usd.Stage) -> Usd.Stage:
    """The stage's root layer opened again, loaded as ``stage`` is, with a session layer of its own that
    sublayers the stage's session layer: selections authored there leave ``stage`` as it is.

    A stage with payloads left unloaded (an export hook's, a user's) is opened with the same ones loaded: opened
    whole, the sets inside the unloaded payloads read as choices the stage does not make, so every material, the
    loaded ones too, was found under a selection other than the stage's own and could not be edited."""
    session = Sdf.Layer.CreateAnonymous(".usda")
    own = stage.GetSessionLayer()
    if own is not None and not own.empty:
        session.subLayerPaths.append(own.identifier)
    loaded = set(stage.GetLoadSet())
    if all(path in loaded for path in stage.FindLoadable()):
        return Usd.Stage.Open(stage.GetRootLayer(), session, stage.GetPathResolverContext(), Usd.Stage.LoadAll)
    private = Usd.Stage.Open(stage.GetRootLayer(), session, stage.GetPathResolverContext(), Usd.Stage.LoadNone)
    private.LoadAndUnload(loaded, [], Usd.LoadWithoutDescendants)
    return private


def apply_selection(layer: Sdf.Layer, selection: Selection) -> None:
    """Author ``selection`` as variant selections in ``layer`` (a session layer), replacing any
    selection it held before."""
    with Sdf.ChangeBlock():
        for prim in list(layer.rootPrims):
            del layer.rootPrims[prim.name]
        for choice in selection:
            spec = Sdf.CreatePrimInLayer(layer, Sdf.Path(choice.prim))
            spec.variantSelections[choice.set] = choice.variant


@dataclass
class _Set:
    prim: str
    name: str
    variants: tuple[str, ...]
    selected: str  # as composed under the current selection ("" for none)

    @property
    def key(self) -> tuple[str, str]:
        return (self.prim, self.name)


@dataclass
class VariantSpace:
    """Selections of a stage's variant sets, composed one after another on a private stage."""

    stage: Usd.Stage
    limit: int = MAX_COMBINATIONS
    mode: str = "all"  # "all" or "each-set" (set by :meth:`selections`)
    combinations: int = 1  # counted (or, in each-set mode, at least this many)
    _private: Usd.Stage | None = field(default=None, repr=False)
    _defaults: dict = field(default_factory=dict, repr=False)  # (prim, set) -> the stage's own selection

    @property
    def current(self) -> Usd.Stage:
        """The stage composed under the selection being explored (the caller's stage itself
        when it has nothing to explore; it is never changed)."""
        return self._private if self._private is not None else self.stage

    def private_stage(self) -> Usd.Stage:
        if self._private is None:
            self._private = private_stage(self.stage)
        return self._private

    def selections(self) -> Iterator[Selection]:
        """Each selection to explore, the stage's own first (``()``); while the consumer works on
        one, :attr:`current` is composed under it."""
        own = self._sets(self.stage)
        self._defaults = {s.key: s.selected for s in own}
        if not any(len(s.variants) > 1 for s in own):
            self.combinations, self.mode = 1, "all"
            yield ()
            return
        stage = self.private_stage()
        leaves = self._count()
        if leaves is not None:
            self.combinations, self.mode = leaves, "all"
            yield from self._product({})
        else:
            self.mode = "each-set"
            yield from self._each_set()
        apply_selection(stage.GetSessionLayer(), ())

    # -- composition under a selection --------------------------------------------------------

    def _sets(self, stage: Usd.Stage) -> list[_Set]:
        found = []
        for prim in stage.Traverse():
            if not prim.HasVariantSets():
                continue
            vsets = prim.GetVariantSets()
            for name in vsets.GetNames():
                vset = vsets.GetVariantSet(name)
                found.append(_Set(str(prim.GetPath()), name, tuple(vset.GetVariantNames()),
                                  vset.GetVariantSelection()))
        return found

    def in_instances(self) -> list[tuple[str, str, tuple[str, ...], str, int]]:
        """The variant sets with a choice on prims inside instances, which no selection can reach (an instance's
        prims are its prototype's, and take no opinion of their own): each ``(prim, set, variants, instance,
        count)``, once per prototype prim and set (``count``: the instances that hold it, ``prim`` and ``instance``
        the first's)."""
        found: dict[tuple[str, str], list] = {}
        if not self.stage.GetPrototypes():  # no instance: nothing to walk again
            return []
        for prim in self.stage.Traverse(Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)):
            if not prim.IsInstanceProxy() or not prim.HasVariantSets():
                continue
            root = prim
            while root.IsInstanceProxy():
                root = root.GetParent()
            vsets = prim.GetVariantSets()
            for name in vsets.GetNames():
                variants = tuple(vsets.GetVariantSet(name).GetVariantNames())
                if len(variants) > 1:
                    key = (str(prim.GetPrimInPrototype().GetPath()), name)
                    if key in found:
                        found[key][4] += 1
                    else:
                        found[key] = [str(prim.GetPath()), name, variants, str(root.GetPath()), 1]
        return [tuple(v) for v in found.values()]

    def compose(self, selection: Selection) -> Usd.Stage:
        """:attr:`current`, composed under ``selection``."""
        if not selection and self._private is None:
            return self.stage
        stage = self.private_stage()
        apply_selection(stage.GetSessionLayer(), selection)
        return stage

    def _compose(self, chosen: dict) -> list[_Set]:
        return self._sets(self.compose(self._as_selection(chosen)))

    def _as_selection(self, chosen: dict) -> Selection:
        """The choices of ``chosen`` that differ from the stage's own selection (parents first)."""
        return tuple(VariantChoice(prim, name, variant) for (prim, name), variant in chosen.items()
                     if self._defaults.get((prim, name)) != variant)

    def _open(self, sets: list[_Set], chosen: dict) -> list[_Set]:
        return [s for s in sets if s.key not in chosen and len(s.variants) > 1]

    @staticmethod
    def _ordered(s: _Set) -> list[str]:
        return ([s.selected] if s.selected in s.variants else []) + [v for v in s.variants if v != s.selected]

    # -- every combination --------------------------------------------------------------------

    def _count(self) -> int | None:
        """Combinations of the whole space, or None as soon as there are more than ``limit``."""
        leaves = 0
        stack = [{}]
        while stack:
            chosen = stack.pop()
            pending = self._open(self._compose(chosen), chosen)
            if not pending:
                leaves += 1
                if leaves > self.limit:
                    return None
                continue
            s = pending[0]
            stack.extend({**chosen, s.key: v} for v in reversed(self._ordered(s)))
        return leaves

    def _product(self, chosen: dict) -> Iterator[Selection]:
        pending = self._open(self._compose(chosen), chosen)
        if not pending:
            yield self._as_selection(chosen)
            return
        s = pending[0]
        for variant in self._ordered(s):
            yield from self._product({**chosen, s.key: variant})

    # -- one set at a time --------------------------------------------------------------------

    def _each_set(self) -> Iterator[Selection]:
        yield ()
        explored = 1
        queue: list[tuple[dict, list[_Set]]] = [({}, self._compose({}))]
        seen: set[tuple[str, str, str]] = set()
        while queue:
            base, sets = queue.pop(0)
            for s in sets:
                if len(s.variants) < 2:
                    continue
                for variant in s.variants:
                    if (s.prim, s.name, variant) in seen or variant == s.selected:
                        seen.add((s.prim, s.name, variant))
                        continue
                    seen.add((s.prim, s.name, variant))
                    chosen = {**base, s.key: variant}
                    revealed = self._compose(chosen)
                    explored += 1
                    yield self._as_selection(chosen)
                    queue.append((chosen, [r for r in revealed if r.key not in chosen]))
        self.combinations = explored
