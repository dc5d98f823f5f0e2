"""The facts shown beside a stack in the HTML report, as readable lines: the working resolution, the seeds trained,
what the tile was made from (the cut or the GAN's layout, the lattice, the candidates tried), Q, and how far
straightening, levelling or evening moved the source's texels (:mod:`.html` lays them out)."""
from __future__ import annotations

from seamless_usd.report.htmlparts import esc, fmt
from seamless_usd.report.model import StackReport

__all__ = ["stack_facts"]


def _policy_text(record: dict) -> str | None:
    """``{"policy": {...}, "working_size": [W, H], "maps": [...]}`` as one readable line."""
    if not record:
        return None
    policy = record.get("policy", {})
    cap = policy.get("max_size")
    text = f"cap {cap} px" if cap else "native size (no cap)"
    text += f", common size: {policy.get('common', 'largest')}, filter {policy.get('filter', 'auto')}"
    changed = [m for m in record.get("maps", []) if m.get("resampled")]
    if changed:
        text += "; resampled: " + ", ".join(
            f"@{m['asset']}@ {m['original_size'][0]}x{m['original_size'][1]}" for m in changed
        )
    else:
        text += "; no map resampled"
    return text


def _seeds_text(seeds: list[dict] | None) -> str | None:
    """The seeds trained side by side, each with its worst figure in units of its target, and the one kept."""
    if not seeds:
        return None
    return ", ".join(f"seed {s['seed']}: {s['score']:.2f}" + (" (Q passed)" if s.get("q_passed") else "")
                     + (" — kept" if s.get("chosen") else "") for s in seeds) + " (worst figure / its target)"


_LAYOUTS = {"gan": "the SeamlessGAN tile, refined",
            "random": "a random start, refined (the GAN tile's feature scale was implausible)",
            "lattice": "a cut of whole lattice periods from the source",
            "window": "one window of the source, joined across its wraps along minimum-error cuts",
            "quilt": "large source blocks quilted on a torus, joined along minimum-error cuts",
            "mend": "the source kept whole and rolled by half, a band over its seams re-laid from itself along "
                    "minimum-error cuts"}


def _layout_text(gan: dict) -> str | None:
    """What the tile was made from, the lattice the stack repeats on, and both candidates' figures."""
    kind = gan.get("layout")
    if kind is None:
        return None
    text = _LAYOUTS.get(kind, kind)
    lattice = gan.get("lattice") or {}
    periods = lattice.get("period_px") or [None, None]
    if any(p is not None for p in periods):
        axes = " x ".join("none" if p is None else f"{p:g}" for p in periods[::-1])
        text += f"; repeats every {axes} px (across x, down y)"
    refused = lattice.get("window_refused")
    if refused:
        lags = ", ".join(f"{axis} {value:.2f}" for axis, value in refused["lag_difference"].items())
        text += (f"; no window cut: the texture does not continue itself at any window's lags (difference {lags};"
                 f" a cut is offered at {refused['most']:.2f} or less)")
    for kind in ("quilt", "mend", "lattice"):
        refused = lattice.get(f"{kind}_refused")
        if refused:
            what = ("its wrap across the axis that does not repeat joins places that differ" if kind == "lattice"
                    else "its blocks differ along a cut")
            text += (f"; {kind}{' cut' if kind == 'lattice' else ''} not written: the verdict passes it, but {what} "
                     f"by {refused['difference_worst']:.2f} (its joins hide at {refused['most']:.2f} or less)")
    tried = lattice.get("candidates")
    if tried:
        text += "; cut from the source, tried in turn: " + ", ".join(
            f"{c['kind']} {c['score']:.2f}" + (" (passed as cut)" if c["passes"] else "") for c in tried)
    if "score" in lattice:
        def verdict(suffix: str) -> str:
            q = lattice.get("q_passed" + suffix)
            ratio = lattice.get("lattice_ratio" + suffix)
            parts = ["" if "gan" in lattice else "Q passed" if q else "Q not passed",  # "gan": no GAN, no Q
                     "" if ratio is None else f"lattice ratio {ratio:.2f}",
                     "passed as cut" if lattice.get("passes" + suffix) else ""]
            return ", ".join(p for p in parts if p) or "does not pass"
        rival = next((k[len("score_"):] for k in lattice if k.startswith("score_")), None)
        name = {"window": "window cut", "quilt": "quilt", "mend": "mend"}.get(lattice.get("cut"), "lattice cut")
        blocks = ""
        if lattice.get("cut") == "quilt" and "cells" in lattice:
            blocks = (f" of {lattice['cells'][0]}x{lattice['cells'][1]} blocks (worst difference along a cut "
                      f"{lattice['difference_worst']:.3f})")
        elif lattice.get("cut") == "lattice" and lattice.get("open_axes"):
            blocks = (f" (no repeat along {' or '.join(lattice['open_axes'])}: difference along that wrap's cut "
                      f"{lattice['difference_worst']:.3f})")
        elif lattice.get("cut") == "mend" and "band" in lattice:
            blocks = (f", band {2 * sum(lattice['band'])} px wide (worst difference along a cut "
                      f"{lattice['difference_worst']:.3f})")
        text += (f"; {name} {lattice['tile'][1]}x{lattice['tile'][0]} px{blocks} scored {lattice['score']:.2f}"
                 f" ({verdict('')})")
        if rival is not None:
            text += (f" against {lattice['score_' + rival]:.2f} from {rival} ({verdict('_' + rival)})")
        text += ("; each score is the candidate's worst figure over its target, under 1 passing as cut (the tile "
                 "written is judged again, read back at full resolution: the status above)")
    if lattice.get("gan"):
        text += f"; SeamlessGAN {lattice['gan']}"
    return text


def _q_text(q: dict) -> str | None:
    """``{"passed": True, "tau": 0.41, ...}`` as ``"passed (tau 0.41, ...)"``."""
    if not q:
        return None
    rest = ", ".join(f"{k} {fmt(v)}" for k, v in q.items() if k != "passed")
    state = {True: "passed", False: "not passed"}.get(q.get("passed"), "")
    return f"{state} ({rest})" if state and rest else (state or rest)


#: Why a straightened tile is written straight although its turn was to go back in the UVs.
UV_TURN_REFUSED = ("the UVs of these texture nodes cannot turn (a tiledimage, a glTF image, texture coordinates "
                   "not connected); an image node fed by a UV transform keeps the asset's look")


def _straightened_text(facts: dict | None) -> str | None:
    """What ``--straighten`` found and did (None when it was not asked for)."""
    from seamless_usd.imaging.orientation import MIN_DEGREES, MIN_STRENGTH

    if not facts:
        return None
    found = facts.get("orientation", {})
    rectified = facts.get("rectified")
    if rectified:
        (vx, vy), (w, h) = rectified["vanishing"], facts.get("size", (0, 0))
        said = (f"rectified: its near-vertical lines met at ({vx:.2f}, {vy:.2f}) of its width and height (leans "
                f"spread {rectified['spread']:g} degrees), resampled so that they run parallel, at the far row's "
                f"texel size; written rectified, since no UV transform undoes a keystone")
        if not facts.get("degrees"):
            return f"{said}; cut to {w} x {h}"
        return f"{said}; then " + _turned_text(facts, found)
    if not facts.get("degrees"):
        return (f"not turned: lines at {found.get('degrees', 0):g} degrees, strength {found.get('strength', 0):g} "
                f"(turned from {MIN_DEGREES:g} degrees at a strength of {MIN_STRENGTH:g})")
    return _turned_text(facts, found)


def _turned_text(facts: dict, found: dict) -> str:
    """What the turn of ``--straighten`` did (``facts["degrees"]`` not 0)."""
    w, h = facts.get("size", (0, 0))
    shown = ("the tile is written straight and the asset's UVs turn it back, so the asset looks as before "
             "(normal maps keep the source's vectors)" if facts.get("uv_turn") else
             "the tile is written straight, so the pattern on the asset turns by that angle")
    if facts.get("uv_turn_refused"):
        shown += f" ({UV_TURN_REFUSED}: {', '.join(facts['uv_turn_refused'])})"
    return (f"turned {facts['degrees']:g} degrees clockwise (strength {found.get('strength', 0):g}) and cut to "
            f"{w} x {h}; {shown}")


def _remade_text(facts: dict | None, what: str, done: str, moved) -> str | None:
    """How far the source was remade before the cut (its ``what`` was ``done``; ``moved(most, mean)`` says how far
    from the facts' ``moved`` and ``moved_mean``); None when it was not."""
    if not facts:
        return None
    how = moved(facts.get("moved", 0), facts.get("moved_mean", 0))
    return f"the source's {what} was {done} before the cut ({how}); the tile is judged against the {done} source"


#: Where a stack's result came from, in words ("trained": the GAN trained this run, whatever the tile was made from).
_ORIGINS = {"trained": "this run, SeamlessGAN trained (the tile: see 'tile made from')",
            "cut": "this run, cut from the source (nothing trained)",
            "cache": "the cache (an earlier run's result for the same files and settings)",
            "duplicate": "an identical stack earlier in this run"}


def stack_facts(stack: StackReport) -> tuple[str, str]:
    """The stack's facts as table rows: the main ones, and the ones shown on request."""
    uv = stack.uv_scale
    cover = f" (one tile covers {fmt(tuple(1.0 / v for v in uv))} of the source's UV square)" if uv else ""
    main = {
        "source": stack.source,
        "variant selection": stack.variant or None,
        "tile size (w x h)": fmt(tuple(stack.tile_size[::-1])) if stack.tile_size else None,
        "UV scale": f"{fmt(tuple(uv))}{cover}" if uv else None,
        "crop size (w x h)": fmt(tuple(stack.crop_size[::-1])) if stack.crop_size and stack.model_hash else None,  # GAN crop
        "Q (the discriminator's view)": _q_text(stack.q),
        "straightened": _straightened_text(stack.resampled.get("straightened")),
        "levelled": _remade_text(stack.resampled.get("levelled"), "light", "levelled",
                                 lambda most, mean: f"its texel values scaled by up to {100 * most:.0f} %, "
                                                    f"{100 * mean:.1f} % on average"),
        "evened": _remade_text(stack.resampled.get("evened"), "drifting lattice", "evened",
                               lambda most, mean: f"texels moved by up to {most:.1f} texels, {mean:.2f} on average, "
                                                  "every map alike"),
        "same as": stack.duplicate_of,
        "result from": _ORIGINS.get(stack.origin, stack.origin) or None,
    }
    more = {
        "working size (w x h)": fmt(stack.working_size) if stack.working_size else None,
        "working resolution": _policy_text(stack.resampled),
        "candidates tried": stack.candidates or None,
        "GAN seeds": _seeds_text(stack.resampled.get("gan", {}).get("seeds")),
        "tile made from": _layout_text(stack.resampled.get("gan", {})),
        "timings (s)": ", ".join(f"{k} {v:.1f}" for k, v in stack.timings.items()) or None,
        "device / precision": " / ".join(p for p in (stack.device, stack.precision) if p) or None,
        "model hash": stack.model_hash or None,
        "peak memory (MB)": f"{stack.peak_rss_mb:.0f}" if stack.peak_rss_mb else None,
    }

    def rows(d: dict) -> str:
        return "".join(f"<tr><td class=muted>{esc(k)}</td><td>{esc(v)}</td></tr>" for k, v in d.items() if v)

    return rows(main), rows(more)
