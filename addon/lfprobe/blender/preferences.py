"""The add-on's preferences (Edit › Preferences › Add-ons › lfprobe): settings that belong to
the user's machine rather than to a .blend: where parsed scans are cached, and the Dask
scheduler that bakes run on."""

import bpy
from bpy.props import StringProperty

from ..core.sources import default_cache_dir

# The add-on's own package: "lfprobe" as a legacy add-on, "bl_ext.<repository>.lfprobe" as an
# extension; Blender keys the preferences by it.
ADDON_PACKAGE = __package__.rsplit(".", 1)[0]


class LFPROBE_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = ADDON_PACKAGE

    scheduler_address: StringProperty(
        name="Dask Scheduler",
        description="Address of a running Dask scheduler (tcp://HOST:8786, from `dask scheduler`) "
        "that Bake hands the probes of scan bakes to; empty bakes on this machine. The scans, "
        "the parse cache and the probe folder must be at the same paths on every worker",
        default="",
    )

    cache_folder: StringProperty(
        name="Scan Cache",
        description="Where parsed scans are cached so that a cloud is parsed once (empty: the "
        "extension's user folder in Blender 4.2+, else $LFPROBE_CACHE or ~/.cache/lfprobe/scans)",
        subtype="DIR_PATH",
        default="",
    )

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "cache_folder")
        if not self.cache_folder:
            layout.label(text=f"Caching in {scan_cache_dir(context)}", icon="FILE_FOLDER")
        layout.prop(self, "scheduler_address")
        if self.scheduler_address:
            layout.label(text="Workers: PYTHONPATH=<lfprobe>/addon dask worker ADDRESS --nthreads 1", icon="INFO")


def _preferences(context=None):
    addon = (context or bpy.context).preferences.addons.get(ADDON_PACKAGE)
    return None if addon is None else addon.preferences


def scan_cache_dir(context=None) -> str:
    """The parse cache's folder: the preferences' Scan Cache when set; as an extension (Blender
    4.2+), its user folder, which Blender keeps per extension; else core's default."""
    prefs = _preferences(context)
    chosen = str(getattr(prefs, "cache_folder", "") or "").strip() if prefs is not None else ""
    if chosen:
        return bpy.path.abspath(chosen)
    if ADDON_PACKAGE.startswith("bl_ext.") and hasattr(bpy.utils, "extension_path_user"):
        try:
            return bpy.utils.extension_path_user(ADDON_PACKAGE, path="scans", create=True)
        except (ValueError, OSError):
            pass
    return default_cache_dir()


def scheduler_address(context=None) -> str:
    """The scheduler address the preferences hold; empty when unset (or the add-on's preferences
    are not registered, as when its modules are loaded without enabling it)."""
    prefs = _preferences(context)
    if prefs is None:
        return ""
    return str(getattr(prefs, "scheduler_address", "")).strip()


register, unregister = bpy.utils.register_classes_factory((LFPROBE_AP_preferences,))
