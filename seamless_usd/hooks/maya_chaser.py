"""Maya USD export chaser: the exported materials get tileable textures (Maya only).

Register once per Maya session (``userSetup.py``)::

    import seamless_usd.hooks.maya_chaser as chaser
    chaser.register()

then export with the chaser named, settings as chaser arguments (all optional)::

    cmds.mayaUSDExport(file="/shots/a/scene.usda", chaser=["seamless_usd"],
                       chaserArgs=[("seamless_usd", "preset", "draft"),
                                   ("seamless_usd", "materials", "/Looks/Brick*")])

``register()`` also adds "Seamless USD textures" to the export dialog's plugin configurations
(it turns the chaser on with the default settings). See docs/maya.md.

``PostExport`` runs after every prim and frame is written and before mayaUSD saves the layer, so
the edits land in the saved file. Importing this module imports ``mayaUsd.lib``: only Maya loads it.
"""
from __future__ import annotations

import logging

import mayaUsd.lib as mayaUsdLib

from seamless_usd.errors import SeamlessUsdError
from seamless_usd.hooks import common
from seamless_usd.hooks.common import HookError, HookSettings, Level, LogLine

__all__ = ["CHASER_NAME", "JOB_CONTEXT", "SeamlessUsdChaser", "settings_from_job_args", "register", "unregister"]

CHASER_NAME = "seamless_usd"
JOB_CONTEXT = "seamless_usd"
log = logging.getLogger("seamless_usd.hooks.maya")


def settings_from_job_args(job_args) -> HookSettings:
    """The chaser's arguments (``chaserArgs`` for ``seamless_usd``) as settings."""
    all_args = getattr(job_args, "allChaserArgs", None) or {}
    return common.settings_from_mapping(dict(all_args.get(CHASER_NAME, {})))


def _emit(line: LogLine) -> None:
    # Maya's Script Editor shows Python logging and print; errors as warnings keep the export going.
    print(str(line))
    if line.level is not Level.INFO:
        log.log(logging.ERROR if line.level is Level.ERROR else logging.WARNING, line.text)


class SeamlessUsdChaser(mayaUsdLib.ExportChaser):
    """Runs ``seamless_usd.process_stage`` on the exported stage in ``PostExport``."""

    def __init__(self, factoryContext, *args, **kwargs):
        super().__init__(factoryContext, *args, **kwargs)
        self._stage = factoryContext.GetStage()
        self._bad_args = None  # arguments the chaser cannot use: said in PostExport, the export goes on unless strict
        try:
            self._settings = settings_from_job_args(factoryContext.GetJobArgs())
        except SeamlessUsdError as exc:
            self._bad_args, self._settings = str(exc), None
            self._strict = _strict_argument(factoryContext.GetJobArgs())

    def ExportDefault(self):
        return True

    def ExportFrame(self, frame):
        return True

    def PostExport(self):
        """True when the export may go on; false (mayaUSD then reports the export as failed) with ``strict`` when a
        stack failed or the chaser's arguments cannot be used, as docs/maya.md says; never an exception."""
        if self._bad_args is not None:
            _emit(LogLine(Level.ERROR, f"seamless-usd: chaser arguments not used, textures left as exported: "
                                       f"{self._bad_args}"))
            return not self._strict
        try:
            run = common.run_hook(self._stage, self._settings, emit=_emit)
        except HookError:  # strict: already logged; mayaUSD reports a chaser's false as a failed export
            return False
        return common.export_ok(run, self._settings)


def _strict_argument(job_args) -> bool:
    """Whether the chaser's own ``strict`` argument asks for it, read alone (the others could not be used)."""
    raw = dict((getattr(job_args, "allChaserArgs", None) or {}).get(CHASER_NAME, {}))
    try:
        return common.parse_bool(raw.get("strict", "0"))
    except SeamlessUsdError:
        return False


def _job_context_enabler():
    return {"chaser": [CHASER_NAME]}


def register() -> None:
    """Register the chaser, and the export-dialog plugin configuration where mayaUSD has it."""
    mayaUsdLib.ExportChaser.Register(SeamlessUsdChaser, CHASER_NAME)
    registry = getattr(mayaUsdLib, "JobContextRegistry", None)
    if registry is not None and hasattr(registry, "RegisterExportJobContext"):
        registry.RegisterExportJobContext(
            JOB_CONTEXT,
            "Seamless USD textures",
            "Make the exported material textures tileable with SeamlessGAN",
            _job_context_enabler,
        )


def unregister() -> None:
    mayaUsdLib.ExportChaser.Unregister(SeamlessUsdChaser, CHASER_NAME)
