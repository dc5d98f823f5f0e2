"""Export-hook settings: one value for every DCC's options, parsed from strings, mappings or
attributes, and written back as a Maya chaser's arguments."""
from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

from seamless_usd.errors import SeamlessUsdError, UsageError

__all__ = [
    "HookError",
    "HookSettings",
    "SETTING_NAMES",
    "parse_bool",
    "parse_patterns",
    "settings_from_mapping",
    "settings_from_attributes",
    "settings_to_chaser_args",
]


class HookError(SeamlessUsdError):
    """Raised by :func:`run_hook` in strict mode, so that the DCC's export itself fails."""


@dataclass(frozen=True)
class HookSettings:
    """The settings every DCC exposes, in DCC-neutral form (strings are as the user typed them).

    Empty strings and zeros mean "the library's default", so that a DCC's blank text field or
    zeroed number field never overrides :class:`seamless_usd.Options`.
    """

    enabled: bool = True  # run at export time at all
    preset: str = "default"  # synthesis preset name; validated by the library
    materials: tuple[str, ...] = ()  # glob patterns on material prim paths; empty = every material
    output_dir: str = ""  # "" = <folder of the exported layer>/tileable; relative = from that folder
    device: str = ""  # "" = CUDA when present, else CPU
    seed: int = 0
    dry_run: bool = False  # plan only: nothing written, the stage left as it is
    report: str = ""  # HTML report path ("" = none); relative = from the exported layer's folder
    cache_dir: str = ""  # "" = the user's cache folder
    max_size: int = 0  # working-resolution cap in px (longest side); 0 = native size
    iterations: int = 0  # training iterations; 0 = the preset's
    seeds: int = 0  # seeds trained side by side, the best tile kept; 0 = the preset's
    straighten: bool = False  # turn stacks whose lines run at an angle straight; the UVs turn the tile back
    strict: bool = False  # fail the DCC's export when a stack fails or the run raises

    def with_(self, **changes: Any) -> "HookSettings":
        return replace(self, **changes)


SETTING_NAMES: tuple[str, ...] = tuple(f.name for f in fields(HookSettings))

_TRUE = {"1", "true", "yes", "on", "y", "t"}
_FALSE = {"0", "false", "no", "off", "n", "f", ""}


def parse_bool(value: object) -> bool:
    """A DCC's boolean: a bool, an int toggle (Houdini) or a string (Maya chaser args).

    >>> parse_bool("On"), parse_bool(0), parse_bool("false")
    (True, False, False)
    """
    if isinstance(value, bool):
        return value
    if isinstance(value, (int, float)):
        return value != 0
    text = str(value).strip().lower()
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    raise UsageError(f"not a yes/no value: {value!r} (use one of 1/0, true/false, yes/no, on/off)")


def parse_patterns(value: object) -> tuple[str, ...]:
    """Glob patterns from a text field: separated by commas, semicolons or whitespace.

    >>> parse_patterns("/root/_materials/Brick*, /World/Looks/*;  ")
    ('/root/_materials/Brick*', '/World/Looks/*')
    """
    if value is None:
        return ()
    if isinstance(value, (list, tuple)):
        items: Iterable[str] = (str(v) for v in value)
    else:
        items = str(value).replace(",", " ").replace(";", " ").split()
    return tuple(p.strip() for p in items if p.strip())


def _parse_int(value: object) -> int:
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, (int, float)):
        return int(value)
    text = str(value).strip()
    if not text:
        return 0
    try:
        return int(text)
    except ValueError:
        raise UsageError(f"not a whole number: {value!r}") from None


def _parse_str(value: object) -> str:
    return "" if value is None else str(value).strip()


# One parser per setting (a registry rather than if/elif on names).
_PARSERS: dict[str, Callable[[object], Any]] = {
    "enabled": parse_bool,
    "preset": lambda v: _parse_str(v) or "default",
    "materials": parse_patterns,
    "output_dir": _parse_str,
    "device": _parse_str,
    "seed": _parse_int,
    "dry_run": parse_bool,
    "report": _parse_str,
    "cache_dir": _parse_str,
    "max_size": _parse_int,
    "iterations": _parse_int,
    "seeds": _parse_int,
    "straighten": parse_bool,
    "strict": parse_bool,
}
assert set(_PARSERS) == set(SETTING_NAMES), "every HookSettings field needs a parser"


def settings_from_mapping(
    values: Mapping[str, object], *, prefix: str = "", base: HookSettings | None = None, strict_keys: bool = True
) -> HookSettings:
    """Settings from name/value pairs: Maya chaser args (all strings) or Houdini parm values.

    ``prefix`` is stripped from names first (Houdini parm names are prefixed to stay unique on the
    ROP). Names that do not start with ``prefix`` are ignored; an unknown name after the prefix is
    an error listing the valid names (unless ``strict_keys`` is false).

    >>> settings_from_mapping({"seamlessusd_seed": "3", "lopoutput": "x.usd"}, prefix="seamlessusd_").seed
    3
    """
    changes: dict[str, Any] = {}
    for raw_name, value in values.items():
        if not raw_name.startswith(prefix):
            continue
        name = raw_name[len(prefix):]
        parser = _PARSERS.get(name)
        if parser is None:
            if strict_keys:
                raise UsageError(
                    f"unknown seamless-usd hook setting {raw_name!r}; valid: "
                    + ", ".join(prefix + n for n in SETTING_NAMES)
                )
            continue
        try:
            changes[name] = parser(value)
        except UsageError as exc:
            raise UsageError(f"hook setting {raw_name!r}: {exc}") from None
    return replace(base or HookSettings(), **changes)


def settings_from_attributes(obj: object, *, base: HookSettings | None = None) -> HookSettings:
    """Settings from an object with attributes of the same names (Blender add-on preferences).

    Attributes the object does not have keep their defaults.
    """
    values = {name: getattr(obj, name) for name in SETTING_NAMES if hasattr(obj, name)}
    return settings_from_mapping(values, base=base)


def settings_to_chaser_args(chaser: str, settings: HookSettings) -> list[list[str]]:
    """``[[chaser, name, value], ...]`` for Maya's ``chaserArgs`` (only non-default settings).

    >>> settings_to_chaser_args("seamless_usd", HookSettings(preset="draft", materials=("/a*", "/b")))
    [['seamless_usd', 'preset', 'draft'], ['seamless_usd', 'materials', '/a*,/b']]
    """
    default = HookSettings()
    out = []
    for name in SETTING_NAMES:
        value = getattr(settings, name)
        if value == getattr(default, name):
            continue
        if isinstance(value, tuple):
            text = ",".join(value)
        elif isinstance(value, bool):
            text = "1" if value else "0"
        else:
            text = str(value)
        out.append([chaser, name, text])
    return out


