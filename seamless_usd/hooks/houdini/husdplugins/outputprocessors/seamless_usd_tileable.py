"""Houdini USD ROP output processor "Seamless USD: Tileable Textures" (Houdini only).

Each layer the ROP saves is handed to ``seamless_usd.process_stage`` just before it is written;
tileable maps go beside it (``tileable/``) and the layer is saved with the new texture paths, wrap
modes and UV transforms. The logic lives in ``seamless_usd.hooks`` (tested without Houdini).
"""
import logging

import hou
from husd.outputprocessor import OutputProcessor

from seamless_usd.hooks import common
from seamless_usd.hooks.common import HookSettings, Level
from seamless_usd.hooks.houdini import PARMS, PROCESSOR_NAME, save_path_for, settings_from_parms

log = logging.getLogger("seamless_usd.hooks.houdini")


def _emit(line):
    # The ROP's console; with strict on, a failure raises from common.run_hook and the ROP errors.
    print(str(line))
    if line.level is not Level.INFO:
        log.log(logging.ERROR if line.level is Level.ERROR else logging.WARNING, line.text)


def _template(spec):
    if spec.kind == "toggle":
        return hou.ToggleParmTemplate(spec.name, spec.label, default_value=bool(spec.default), help=spec.help)
    if spec.kind == "int":
        return hou.IntParmTemplate(spec.name, spec.label, 1, default_value=(int(spec.default),), help=spec.help)
    string_type = hou.stringParmType.FileReference if spec.kind in ("directory", "file") else hou.stringParmType.Regular
    kwargs = {"file_type": hou.fileType.Directory} if spec.kind == "directory" else {}
    return hou.StringParmTemplate(
        spec.name, spec.label, 1, default_value=(str(spec.default),), string_type=string_type, help=spec.help, **kwargs
    )


class SeamlessUsdOutputProcessor(OutputProcessor):
    def __init__(self):
        super().__init__()
        self._settings = HookSettings(enabled=False)
        self._rop_output = None

    @staticmethod
    def name():
        return PROCESSOR_NAME

    @staticmethod
    def displayName():
        return "Seamless USD: Tileable Textures"

    @staticmethod
    def parameters():
        group = hou.ParmTemplateGroup()
        for spec in PARMS:
            group.append(_template(spec))
        return group.asDialogScript()

    def beginSave(self, config_node, config_overrides, lop_node, t, *args, **kwargs):
        super().beginSave(config_node, config_overrides, lop_node, t, *args, **kwargs)
        values = {spec.name: self.evalConfig(spec.name, config_node, config_overrides, t) for spec in PARMS}
        self._settings = settings_from_parms(values)
        self._rop_output = self.evalConfig("lopoutput", config_node, config_overrides, t)

    def processLayer(self, layer, *args, **kwargs):
        layer_save_path = args[0] if args else kwargs.get("layersavepath")
        save_path = save_path_for(layer.identifier, layer.anonymous, layer_save_path, self._rop_output)
        run = common.process_layer(layer, save_path, self._settings, emit=_emit)  # strict: raises HookError
        return run.report is not None


def usdOutputProcessor():
    return SeamlessUsdOutputProcessor
