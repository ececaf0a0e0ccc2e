"""lfprobe: light field probes from laser scans of interiors.

The package has two layers: ``lfprobe.core`` (the pipeline, the command line, reports),
which imports without Blender, and the Blender add-on's UI modules in ``lfprobe.blender``.
The native core is the extension module ``lfprobe._native``, built by ``tools/setup.sh``.

The same folder is a legacy add-on (``bl_info``, Blender 3.4) and an extension
(``blender_manifest.toml``, Blender 4.2+); as an extension its package name is
``bl_ext.<repository>.lfprobe``, so everything inside imports relatively.
"""

bl_info = {
    "name": "Light Field Probes (lfprobe)",
    "author": "lfprobe contributors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > Scan Cloud; Add > Light Field Probe Grid; Render engine list",
    "description": "Bake light field probes from laser scans and render views by tracing them",
    "category": "Render",
}

# Registered in this order, unregistered in reverse (the layout contract of the add-on).
_MODULE_NAMES = ("preferences", "properties", "operators.scan_import", "operators.grid", "ui.overlay", "operators.bake",
                 "operators.place_views", "ui.panels", "engine", "operators.compare")
_registered = []


def _blender_modules():
    # Imported here, not at the top: lfprobe.core must import without bpy.
    import importlib

    return [importlib.import_module(f"{__name__}.blender.{name}") for name in _MODULE_NAMES]


def register():
    modules = _blender_modules()
    try:
        for module in modules:
            module.register()
            _registered.append(module)
    except Exception:
        # Leave Blender as it was: a half-registered add-on cannot be disabled cleanly.
        unregister()
        raise


def unregister():
    if _registered:
        # Jobs still running (a bake, an import) stop before their operators go.
        import importlib

        importlib.import_module(f"{__name__}.blender.operators.job_modal").release_running_jobs()
    while _registered:
        _registered.pop().unregister()
