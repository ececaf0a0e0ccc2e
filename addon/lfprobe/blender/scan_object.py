"""A scan cloud as a Blender object: a mesh of vertices only holding a display subsample,
colours in the point attribute "Col", rendered as points by a Geometry Nodes modifier
("Mesh to Points" + a material that emits the scan colour) and drawn in the viewport by
scan_display in its colours. The full cloud stays in the scan files and lfprobe's parse
cache; the object references them (source_paths).

Cycles renders the points in 3.4 and 5.x, and EEVEE from 4.2 (EEVEE Next); the legacy EEVEE
of 3.4 does not draw point cloud geometry. The modifier is off in the viewport (scan_display
draws the points there, coloured in any shading mode; turn it on to preview render points),
and the object shows its bounds so that it can be clicked.
"""

from __future__ import annotations

import json
import math
import os

import bpy
import numpy as np

from .properties import COLOR_ATTRIBUTE

NODE_GROUP_NAME = "lfprobe Scan Points"
MATERIAL_NAME = "lfprobe Scan Colour"
MODIFIER_NAME = "lfprobe Points"


def _new_socket(group, name: str, in_out: str, socket_type: str):
    """Adds a group socket with the API of either Blender version (4.0 moved it to interface)."""
    if hasattr(group, "interface"):
        return group.interface.new_socket(name=name, in_out=in_out, socket_type=socket_type)
    sockets = group.inputs if in_out == "INPUT" else group.outputs
    return sockets.new(socket_type, name)


def scan_material() -> bpy.types.Material:
    """Emission of the "Col" attribute: scans hold lit colour, so no scene light is added."""
    material = bpy.data.materials.get(MATERIAL_NAME)
    if material is not None:
        return material
    material = bpy.data.materials.new(MATERIAL_NAME)
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    attribute = nodes.new("ShaderNodeAttribute")
    attribute.attribute_type = "GEOMETRY"
    attribute.attribute_name = COLOR_ATTRIBUTE
    emission = nodes.new("ShaderNodeEmission")
    output = nodes.new("ShaderNodeOutputMaterial")
    attribute.location, emission.location, output.location = (-400, 0), (-150, 0), (100, 0)
    links = material.node_tree.links
    links.new(attribute.outputs["Color"], emission.inputs["Color"])
    links.new(emission.outputs["Emission"], output.inputs["Surface"])
    material.diffuse_color = (0.8, 0.8, 0.8, 1.0)
    return material


def points_node_group() -> bpy.types.NodeTree:
    """Geometry Nodes: vertices → points of an adjustable radius, with the scan material."""
    group = bpy.data.node_groups.get(NODE_GROUP_NAME)
    if group is not None:
        return group
    group = bpy.data.node_groups.new(NODE_GROUP_NAME, "GeometryNodeTree")
    _new_socket(group, "Geometry", "INPUT", "NodeSocketGeometry")
    radius_socket = _new_socket(group, "Point Radius", "INPUT", "NodeSocketFloat")
    radius_socket.default_value = 0.005
    radius_socket.min_value = 0.0
    _new_socket(group, "Geometry", "OUTPUT", "NodeSocketGeometry")
    if hasattr(group, "is_modifier"):
        group.is_modifier = True
    nodes = group.nodes
    group_in = nodes.new("NodeGroupInput")
    to_points = nodes.new("GeometryNodeMeshToPoints")
    set_material = nodes.new("GeometryNodeSetMaterial")
    group_out = nodes.new("NodeGroupOutput")
    set_material.inputs["Material"].default_value = scan_material()
    group_in.location, to_points.location = (-400, 0), (-150, 0)
    set_material.location, group_out.location = (100, 0), (350, 0)
    links = group.links
    links.new(group_in.outputs[0], to_points.inputs["Mesh"])
    links.new(group_in.outputs[1], to_points.inputs["Radius"])
    links.new(to_points.outputs["Points"], set_material.inputs["Geometry"])
    links.new(set_material.outputs["Geometry"], group_out.inputs[0])
    return group


def _set_modifier_input(modifier, group, name: str, value) -> None:
    # Modifier inputs are keyed by socket identifier ("Input_2" in 3.4, "Socket_1" in 4.x).
    if hasattr(group, "interface"):
        items = [i for i in group.interface.items_tree if getattr(i, "in_out", "") == "INPUT"]
    else:
        items = list(group.inputs)
    for item in items:
        if item.name == name:
            modifier[item.identifier] = value
            return


def build_scan_object(
    name: str,
    positions: np.ndarray,
    colors: np.ndarray | None,
    *,
    point_count: int,
    source_paths: list,
    world_offset,
    scanners: list,
    bounds: tuple,
    point_radius: float,
    collection: bpy.types.Collection,
) -> bpy.types.Object:
    """Makes the scan object from display positions (n, 3) and linear colours (n, 3) in the
    local frame (world = world_offset + local)."""
    positions = np.ascontiguousarray(positions, dtype=np.float32)
    n = len(positions)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(n)
    mesh.vertices.foreach_set("co", positions.ravel())
    rgba = np.ones((n, 4), dtype=np.float32)
    if colors is not None:
        rgba[:, :3] = colors
    else:
        rgba[:, :3] = 0.5  # no colour in the file: neutral grey
    attribute = mesh.attributes.new(COLOR_ATTRIBUTE, "FLOAT_COLOR", "POINT")
    attribute.data.foreach_set("color", rgba.ravel())
    if hasattr(mesh, "color_attributes"):
        mesh.color_attributes.active_color = attribute
    mesh.update()

    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)
    group = points_node_group()
    modifier = obj.modifiers.new(MODIFIER_NAME, "NODES")
    modifier.node_group = group
    modifier.show_viewport = False
    _set_modifier_input(modifier, group, "Point Radius", float(point_radius))
    obj.show_bounds = True
    # Blender draws a mesh of loose vertices as black dots in Solid mode, over the scan's own
    # colours (ui/scan_display.py draws those): as bounds, the object leaves the points to it.
    # Final renders (Cycles) still render the Geometry Nodes points.
    obj.display_type = "BOUNDS"
    obj.data.materials.append(scan_material())

    props = obj.lfprobe_scan
    props.is_scan = True
    props.source_paths = json.dumps([os.path.abspath(p) for p in source_paths])
    props.point_count = int(point_count)
    props.display_count = n
    props.world_offset = tuple(float(v) for v in world_offset)
    props.world_offset_json = json.dumps([float(v) for v in world_offset])
    props.scanner_positions_json = json.dumps(scanners)
    props.bounds_min, props.bounds_max = bounds
    return obj


def scan_objects(scene) -> list:
    return [obj for obj in scene.objects if obj.type == "MESH" and obj.lfprobe_scan.is_scan]


# A scene whose objects sit in a georeferenced frame (world = offset + Blender location) names
# it in this custom property, as the demo scenes do (blend/build_blend.py): Blender's float32
# locations cannot hold UTM coordinates themselves.
SCENE_OFFSET_PROPERTY = "lfprobe_world_offset"


def frame_offset(scene):
    """The scene's world offset: its `lfprobe_world_offset` property when set, else the one
    the scene's scan objects share (their local frame), else None."""
    explicit = scene.get(SCENE_OFFSET_PROPERTY)
    if explicit is not None:
        try:
            values = [float(v) for v in explicit]
        except (TypeError, ValueError):
            values = []
        if len(values) == 3 and all(math.isfinite(v) for v in values):
            return tuple(values)
    for obj in scan_objects(scene):
        return obj.lfprobe_scan.offset()
    return None
