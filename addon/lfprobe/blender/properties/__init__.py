"""The add-on's PropertyGroups: what scan cloud and probe grid objects carry
(object_settings.py, registered here, first of all), the scene's trace settings
(render_settings.py, registered with the engine) and the camera names Add Probes for Views
takes (camera_name.py, registered with that operator)."""

import bpy
from bpy.props import PointerProperty

from .object_settings import COLOR_ATTRIBUTE, LFProbeGridProperties, LFProbeGridSource, LFProbeScanProperties  # noqa: F401

_CLASSES = (LFProbeScanProperties, LFProbeGridSource, LFProbeGridProperties)


_register_classes, _unregister_classes = bpy.utils.register_classes_factory(_CLASSES)


def register():
    _register_classes()
    bpy.types.Object.lfprobe_scan = PointerProperty(type=LFProbeScanProperties)
    bpy.types.Object.lfprobe_grid = PointerProperty(type=LFProbeGridProperties)


def unregister():
    del bpy.types.Object.lfprobe_grid
    del bpy.types.Object.lfprobe_scan
    _unregister_classes()
