"""Blender mesh objects → one native Mesh (Embree scene) for ground truth and mesh bakes.

Each object is evaluated (modifiers applied), triangulated through its loop triangles and
placed by its world matrix in double precision. What a triangle's base colour is follows the
object's material as Blender shades it, reduced to what the native mesh holds (docs/DESIGN.md §4:
unlit base colour): the Principled BSDF's "Base Color" value, an Image Texture feeding it
(sampled with the active UV map), or a colour attribute feeding it; objects without a
material show their active colour attribute, else Blender's default grey.

`native_mesh_from_objects` is the one place where objects cross to the native side.
"""

from __future__ import annotations

from typing import Iterable, Optional, Sequence

import numpy as np

from ..core import native
from ..core.errors import InputError
from ..core.mesh_arrays import MeshParts

DEFAULT_BASE_COLOR = (0.8, 0.8, 0.8)  # Blender's default material colour
_COLOR_NODES = {"VERTEX_COLOR", "ATTRIBUTE"}  # Color Attribute node (3.x/4.x), Attribute node


class MeshExportError(InputError):
    """Objects that cannot become a mesh for Embree (the message names the object)."""


class _Material:
    """What the native mesh needs of one Blender material slot."""

    def __init__(self, name: str, base_color, texture: Optional[dict] = None, uses_colors: bool = False):
        self.name = name
        self.base_color = tuple(float(c) for c in base_color[:3])
        self.texture = texture
        self.uses_colors = uses_colors

    def as_dict(self) -> dict:
        d = {"name": self.name, "base_color": list(self.base_color)}
        if self.texture is not None:
            d.update(self.texture)
        return d


def _principled_base_color_input(material):
    if not material.use_nodes or material.node_tree is None:
        return None
    for node in material.node_tree.nodes:
        if node.type == "BSDF_PRINCIPLED":
            return node.inputs.get("Base Color")
    return None


def _image_texture(image) -> dict:
    """A Blender image as the native mesh's texture: its pixels (bottom row first, as
    Image.pixels gives them), sRGB-encoded for byte images in an sRGB colour space."""
    width, height = image.size
    if width == 0 or height == 0:
        raise MeshExportError(f"image '{image.name}' has no pixels (missing file {image.filepath!r}?)")
    channels = image.channels
    pixels = np.empty(width * height * channels, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(height, width, channels)
    if channels < 3:  # grey (and alpha): the native texture wants RGB
        pixels = np.repeat(pixels[..., :1], 3, axis=2)
    srgb = (not image.is_float) and image.colorspace_settings.name == "sRGB"
    return {
        "texture": np.ascontiguousarray(pixels[..., :4]),
        "texture_srgb": srgb,
        "texture_bottom_up": True,
    }


def material_of(material) -> _Material:
    """The base colour of a Blender material: Principled "Base Color" (its image texture or
    colour attribute when one is linked), else the viewport display colour."""
    if material is None:
        return _Material("default", DEFAULT_BASE_COLOR, uses_colors=True)
    socket = _principled_base_color_input(material)
    if socket is None:
        return _Material(material.name, tuple(material.diffuse_color))
    if socket.is_linked:
        source = socket.links[0].from_node
        if source.type == "TEX_IMAGE" and source.image is not None:
            return _Material(material.name, (1.0, 1.0, 1.0), texture=_image_texture(source.image))
        if source.type in _COLOR_NODES:
            return _Material(material.name, (1.0, 1.0, 1.0), uses_colors=True)
    return _Material(material.name, tuple(socket.default_value))


def _corner_colors(mesh, loops: np.ndarray) -> Optional[np.ndarray]:
    """Linear colours (3T, 3) of the active colour attribute per triangle corner, or None."""
    attributes = getattr(mesh, "color_attributes", None)
    attribute = attributes.active_color if attributes is not None else None
    if attribute is None:
        return None
    rgba = np.empty(len(attribute.data) * 4, dtype=np.float32)
    attribute.data.foreach_get("color", rgba)
    rgba = rgba.reshape(-1, 4)
    if attribute.domain == "CORNER":
        return rgba[loops, :3]
    if attribute.domain == "POINT":
        vertex_of_loop = np.empty(len(mesh.loops), dtype=np.int64)
        mesh.loops.foreach_get("vertex_index", vertex_of_loop)
        return rgba[vertex_of_loop[loops], :3]
    return None


def _corner_normals(mesh, loops: np.ndarray) -> np.ndarray:
    """Shading normals per triangle corner in object space (Blender 4.1 replaced split
    normals with Mesh.corner_normals)."""
    if hasattr(mesh, "corner_normals"):
        normals = np.empty(len(mesh.corner_normals) * 3, dtype=np.float32)
        mesh.corner_normals.foreach_get("vector", normals)
    else:
        mesh.calc_normals_split()
        normals = np.empty(len(mesh.loops) * 3, dtype=np.float32)
        mesh.loops.foreach_get("normal", normals)
    return normals.reshape(-1, 3)[loops]


def _add_object(parts: MeshParts, obj, evaluated, world_offset: Sequence[float]) -> None:
    """Reads one evaluated object's triangles and corner arrays into parts (core.mesh_arrays
    moves them to the world frame)."""
    mesh = evaluated.to_mesh()
    try:
        mesh.calc_loop_triangles()
        count = len(mesh.loop_triangles)
        if count == 0:
            return
        co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        tris = np.empty(count * 3, dtype=np.int64)
        mesh.loop_triangles.foreach_get("vertices", tris)
        loops = np.empty(count * 3, dtype=np.int64)
        mesh.loop_triangles.foreach_get("loops", loops)
        slots = np.empty(count, dtype=np.int64)
        mesh.loop_triangles.foreach_get("material_index", slots)

        uvs = None
        uv_layer = mesh.uv_layers.active
        if uv_layer is not None:
            uv = np.empty(len(uv_layer.data) * 2, dtype=np.float32)
            uv_layer.data.foreach_get("uv", uv)
            uvs = uv.reshape(-1, 2)[loops]

        # Material slots → the mesh's material indices; a slot without a material shades grey.
        materials = [slot.material for slot in evaluated.material_slots] or [None]
        slot_materials = [parts.material_slot(m.name if m is not None else None, lambda m=m: material_of(m))
                          for m in materials]
        parts.add_object(obj.name, co, evaluated.matrix_world, world_offset, tris, slots, slot_materials,
                         uvs, _corner_colors(mesh, loops), _corner_normals(mesh, loops))
    finally:
        evaluated.to_mesh_clear()


def native_mesh_from_objects(objects: Iterable, depsgraph, world_offset: Sequence[float] = (0.0, 0.0, 0.0),
                             name: str = "Blender objects"):
    """One native Mesh of the given mesh objects as the depsgraph evaluates them, in world
    coordinates: world = world_offset + Blender position (the scene's frame offset, so
    that meshes line up with georeferenced scans and their probe sets)."""
    _native = native.load()
    parts = MeshParts()
    for obj in objects:
        if obj.type != "MESH":
            raise MeshExportError(f"object '{obj.name}' is a {obj.type.lower()}, not a mesh")
        _add_object(parts, obj, obj.evaluated_get(depsgraph), world_offset)
    if not parts.triangles:
        names = ", ".join(f"'{o.name}'" for o in objects) or "none given"
        raise MeshExportError(f"no triangles to trace in the reference objects ({names}): they need faces")
    return _native.mesh_from_arrays(**parts.mesh_arrays(name))
