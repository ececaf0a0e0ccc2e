"""A camera's name as a PropertyGroup, for Add Probes for Views' `cameras` (registered with
that operator)."""

import bpy


class LFProbeCameraName(bpy.types.PropertyGroup):
    """A camera object's name (PropertyGroup.name): the operator's `cameras`, as file import
    operators take `files`."""
