"""The add-on's preferences (Edit › Preferences › Add-ons › lfprobe): settings that belong to
the user's machine rather than to a .blend, such as the Dask scheduler that bakes run on."""

import bpy
from bpy.props import StringProperty

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

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "scheduler_address")
        if self.scheduler_address:
            layout.label(text="Workers: PYTHONPATH=<lfprobe>/addon dask worker ADDRESS --nthreads 1", icon="INFO")


def scheduler_address(context=None) -> str:
    """The scheduler address the preferences hold; empty when unset (or the add-on's preferences
    are not registered, as when its modules are loaded without enabling it)."""
    preferences = (context or bpy.context).preferences
    addon = preferences.addons.get(ADDON_PACKAGE)
    if addon is None or addon.preferences is None:
        return ""
    return str(getattr(addon.preferences, "scheduler_address", "")).strip()


register, unregister = bpy.utils.register_classes_factory((LFPROBE_AP_preferences,))
