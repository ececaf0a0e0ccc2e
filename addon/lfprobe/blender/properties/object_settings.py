"""The add-on's data model: what a scan cloud object and a probe grid object carry.

Scan cloud: a mesh of vertices only (a display subsample of the cloud) with its colours in
the point attribute "Col" and ``obj.lfprobe_scan``. Probe grid: an Empty whose cube
[-1, 1]^3, transformed by its location and scale, is the grid's box, with ``obj.lfprobe_grid``.
The engine's scene settings (``scene.lfprobe_render``) are in render_settings.py.
"""

import json

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    IntVectorProperty,
    PointerProperty,
    StringProperty,
)

from ...core import defaults

COLOR_ATTRIBUTE = "Col"

# Blender 4.5+ warns about "//" in path properties unless they say they support it.
_BLEND_RELATIVE = {"PATH_SUPPORTS_BLEND_RELATIVE"} if bpy.app.version >= (4, 5, 0) else set()


class LFProbeScanProperties(bpy.types.PropertyGroup):
    is_scan: BoolProperty(name="Is Scan Cloud", default=False)
    source_paths: StringProperty(
        name="Source Files", description="JSON list of the absolute paths of the scan files", default="[]"
    )
    point_count: IntProperty(name="Points", description="Points in the full cloud", min=0)
    display_count: IntProperty(
        name="Displayed", description="Points in the display subsample (the object's vertices)", min=0
    )
    world_offset: FloatVectorProperty(
        name="World Offset",
        description="World position of the object's origin (world = offset + local); single precision, "
        "see world_offset_json for the exact value",
        size=3,
        subtype="TRANSLATION",
        unit="LENGTH",
    )
    world_offset_json: StringProperty(
        name="World Offset (exact)", description="The world offset in double precision, as JSON", default="[0, 0, 0]"
    )
    scanner_positions_json: StringProperty(
        name="Scanner Positions",
        description="JSON list with one world position (or null) per source file",
        default="[]",
    )
    bounds_min: FloatVectorProperty(
        name="Bounds Min", description="Lower corner of the full cloud, local frame", size=3, subtype="XYZ"
    )
    bounds_max: FloatVectorProperty(
        name="Bounds Max", description="Upper corner of the full cloud, local frame", size=3, subtype="XYZ"
    )

    def paths(self) -> list:
        return list(json.loads(self.source_paths or "[]"))

    def offset(self) -> tuple:
        """The world offset in double precision."""
        return tuple(float(v) for v in json.loads(self.world_offset_json or "[0, 0, 0]"))

    def scanners(self) -> list:
        return list(json.loads(self.scanner_positions_json or "[]"))


class LFProbeGridSource(bpy.types.PropertyGroup):
    obj: PointerProperty(
        name="Object",
        type=bpy.types.Object,
        description="A scan cloud or a mesh to bake the probes from",
        poll=lambda _self, obj: obj.type == "MESH",
    )


class LFProbeGridProperties(bpy.types.PropertyGroup):
    is_grid: BoolProperty(name="Is Probe Grid", default=False)
    counts: IntVectorProperty(
        name="Counts",
        description="Probes along X, Y and Z; the corner probes sit on the box corners",
        size=3,
        min=1,
        soft_max=64,
        default=(2, 2, 2),
    )
    resolution: IntProperty(
        name="Resolution",
        description="Octahedral map size of each probe (texels per side)",
        min=8,
        soft_max=4096,
        default=defaults.bake("resolution"),
    )
    coarse_resolution: IntProperty(
        name="Coarse Resolution",
        description="Size of the coarsest min-distance level kept when the probes are loaded for tracing (0 = every level down to 1x1; larger keeps less memory)",
        min=0,
        soft_max=512,
        default=0,
    )
    # How the baked probes load into memory for tracing (the manifest's "storage"); the files
    # keep full precision either way, so switching needs no rebake (Apply Storage).
    storage: EnumProperty(
        name="Storage",
        description="How the probes are held in memory for tracing (the probe files keep full precision)",
        items=(
            ("FULL", "Full", "Half-float radiance and confidence, float32 distance, half-float normals: "
             "18 bytes a texel"),
            ("COMPACT", "Compact", "8-bit sRGB radiance, 16-bit distance in steps of Distance Step, "
             "8+8-bit octahedral normals, no confidence: 7 bytes a texel"),
        ),
        default="FULL",
    )
    distance_step: FloatProperty(
        name="Distance Step",
        description="Compact storage: the distance quantum in metres (1 mm is half the range noise of "
        "a FARO-class scanner at 10 m); a probe whose farthest surface needs more than 65534 steps "
        "takes a coarser step of its own",
        min=0.0001,
        max=1.0,
        soft_max=0.01,
        precision=4,
        step=1,
        unit="LENGTH",
        default=defaults.storage("distance_step"),
    )
    sources: CollectionProperty(type=LFProbeGridSource, name="Sources")
    active_source_index: IntProperty(name="Active Source", default=0)
    probe_dir: StringProperty(
        name="Probe Folder",
        description="Where the probe set is written; // is the folder of the .blend",
        subtype="DIR_PATH",
        options=_BLEND_RELATIVE,
        default="",
    )
    plan_from_data: BoolProperty(
        name="Plan From Data",
        description="Before baking, give each probe the resolution its points support (Resolution "
        "is then the largest allowed), move probes out of geometry and off walls, and drop "
        "the ones that stay useless (scan sources only)",
        default=True,
    )
    plan_json: StringProperty(
        name="Plan",
        description="Per-probe plan after a planned bake (JSON list: class, moved, dropped, resolution)",
        default="[]",
    )
    # Add Probes for Views (place_views.py): probes at the eyes of the views that trace the most
    # UNKNOWN, added to the grid's probes until a target or a memory budget.
    views_from: EnumProperty(
        name="Views",
        description="The views that Add Probes for Views serves",
        items=(
            ("SELECTED", "Selected Cameras", "The selected camera objects, each at the current frame"),
            ("CAMERA_PATH", "Scene Camera Path",
             "The scene camera over the scene's frame range, one view every Frame Step frames"),
        ),
        default="SELECTED",
    )
    frame_step: IntProperty(
        name="Frame Step",
        description="Scene Camera Path: one view every this many frames from the scene's start frame",
        min=1,
        soft_max=250,
        default=10,
    )
    target_unknown: FloatProperty(
        name="Target UNKNOWN",
        description="Stop adding probes when every view traces at most this fraction of its pixels "
        "UNKNOWN (no probe knows what is there)",
        min=0.0,
        max=1.0,
        precision=3,
        step=1,
        default=0.01,
    )
    budget_mib: FloatProperty(
        name="Memory Budget (MiB)",
        description="Add no probe that would take the whole probe set (loaded maps and coarse "
        "levels) over this many MiB; 0: no budget",
        min=0.0,
        soft_max=65536.0,
        default=0.0,
    )
    max_added: IntProperty(
        name="Max Added Probes",
        description="The most probes Add Probes for Views adds to the grid's probes",
        min=1,
        soft_max=256,
        default=16,
    )
    placement_json: StringProperty(
        name="Probes for Views",
        description="What Add Probes for Views did (JSON: added probes in Blender's frame, UNKNOWN "
        "before and after, memory, why it stopped); {} after a plain bake",
        default="{}",
    )
    # Kept for files saved before the set on disk said whether a grid is baked (grid.bound_set).
    baked: BoolProperty(name="Baked", default=False)
    grid_id: StringProperty(
        name="Grid ID",
        description="Binds the grid to the probe sets baked for it (recorded in their manifest); "
        "a duplicate gets its own when it is baked",
        default="",
    )
    estimate_json: StringProperty(
        name="Coverage Estimate",
        description="Estimate Coverage's result: the counts and resolution it was made for and each "
        "probe's unknown fraction from a coarse bake (JSON)",
        default="{}",
    )
    coverage_json: StringProperty(
        name="Coverage",
        description="Per-probe coverage after baking (JSON list of {surface, inferred, empty, unknown})",
        default="[]",
    )

    def storage_choice(self) -> tuple:
        """(storage, distance_step) as BakeOptions and set_probe_set_storage take them."""
        if self.storage == "COMPACT":
            # The property is single precision: 6 digits give the manifest 0.001, not 0.0010000000475.
            return "compact", float(f"{self.distance_step:.6g}")
        return "full", 0.0

    def plan(self) -> list:
        try:
            return list(json.loads(self.plan_json or "[]"))
        except ValueError:
            return []

    def placement(self) -> dict:
        try:
            value = json.loads(self.placement_json or "{}")
        except ValueError:
            return {}
        return value if isinstance(value, dict) else {}

    def estimate(self) -> dict:
        try:
            value = json.loads(self.estimate_json or "{}")
        except ValueError:
            return {}
        return value if isinstance(value, dict) else {}

    def coverage(self) -> list:
        try:
            return list(json.loads(self.coverage_json or "[]"))
        except ValueError:
            return []
