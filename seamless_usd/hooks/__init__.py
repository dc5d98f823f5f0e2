"""DCC export hooks: thin adapters over :func:`seamless_usd.process_stage`.

- :mod:`seamless_usd.hooks.common`: the shared, DCC-free part (settings, output folder, log lines);
- :mod:`seamless_usd.hooks.blender`: the Blender USD export hook (the add-on in
  ``blender_addon/seamless_usd_export`` calls it); imports ``bpy``;
- :mod:`seamless_usd.hooks.maya_chaser`: the mayaUSD export chaser; imports ``mayaUsd``;
- :mod:`seamless_usd.hooks.houdini`: the USD ROP output processor (the processor file itself is in
  ``houdini/husdplugins/outputprocessors/``); only that file imports ``hou``.

Only :mod:`~seamless_usd.hooks.common` and :mod:`~seamless_usd.hooks.houdini` can be imported
outside a DCC. See docs/blender.md, docs/maya.md and docs/houdini.md.
"""
