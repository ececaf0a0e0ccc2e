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

from typing import Iterable, List, Optional, Sequence

import numpy as np

from ..core import native
from ..core.errors import InputError

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


class _Arrays:
    """The mesh_from_arrays inputs, gathered object by object."""

    def __init__(self):
        self.vertices: List[np.ndarray] = []
        self.triangles: List[np.ndarray] = []
        self.uvs: List[Optional[np.ndarray]] = []
        self.colors: List[Optional[np.ndarray]] = []
        self.normals: List[np.ndarray] = []
        self.material: List[np.ndarray] = []
        self.object: List[np.ndarray] = []
        self.materials: List[_Material] = []
        self.material_index = {}
        self.object_names: List[str] = []
        self.vertex_count = 0

    def material_slot(self, material) -> int:
        key = material.name if material is not None else None
        if key not in self.material_index:
            self.material_index[key] = len(self.materials)
            self.materials.append(material_of(material))
        return self.material_index[key]


def _add_object(arrays: _Arrays, obj, evaluated, world_offset: Sequence[float]) -> None:
    mesh = evaluated.to_mesh()
    try:
        mesh.calc_loop_triangles()
        count = len(mesh.loop_triangles)
        if count == 0:
            return
        co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        matrix = np.array(evaluated.matrix_world, dtype=np.float64)
        local = co.reshape(-1, 3).astype(np.float64)
        world = local @ matrix[:3, :3].T + matrix[:3, 3] + np.asarray(world_offset, dtype=np.float64)
        tris = np.empty(count * 3, dtype=np.int64)
        mesh.loop_triangles.foreach_get("vertices", tris)
        loops = np.empty(count * 3, dtype=np.int64)
        mesh.loop_triangles.foreach_get("loops", loops)
        slots = np.empty(count, dtype=np.int64)
        mesh.loop_triangles.foreach_get("material_index", slots)

        uv_layer = mesh.uv_layers.active
        if uv_layer is not None:
            uv = np.empty(len(uv_layer.data) * 2, dtype=np.float32)
            uv_layer.data.foreach_get("uv", uv)
            arrays.uvs.append(uv.reshape(-1, 2)[loops])
        else:
            arrays.uvs.append(None)

        # Material slots → global material indices; a slot without a material shades grey.
        materials = [slot.material for slot in evaluated.material_slots] or [None]
        slot_to_global = np.array([arrays.material_slot(m) for m in materials], dtype=np.int64)
        global_material = slot_to_global[np.clip(slots, 0, len(materials) - 1)]

        colors = _corner_colors(mesh, loops)
        uses_colors = np.array([arrays.materials[g].uses_colors for g in slot_to_global])
        if colors is not None:
            # Triangles whose material ignores the colour attribute multiply by white.
            colors = np.where(uses_colors[np.clip(slots, 0, len(materials) - 1)].repeat(3)[:, None],
                              colors, 1.0).astype(np.float32)
        arrays.colors.append(colors)

        normal_matrix = np.linalg.inv(matrix[:3, :3]).T
        normals = _corner_normals(mesh, loops).astype(np.float64) @ normal_matrix.T
        lengths = np.linalg.norm(normals, axis=1, keepdims=True)
        arrays.normals.append((normals / np.where(lengths > 0, lengths, 1.0)).astype(np.float32))

        arrays.vertices.append(world)
        arrays.triangles.append(tris.reshape(-1, 3) + arrays.vertex_count)
        arrays.material.append(global_material)
        arrays.object.append(np.full(count, len(arrays.object_names), dtype=np.int64))
        arrays.object_names.append(obj.name)
        arrays.vertex_count += len(world)
    finally:
        evaluated.to_mesh_clear()


def _stack_optional(parts: List[Optional[np.ndarray]], sizes: List[int], width: int, fill: float):
    """Concatenates per-object corner arrays; objects without one get `fill`; None if none has."""
    if all(p is None for p in parts):
        return None
    return np.concatenate([
        p if p is not None else np.full((n, width), fill, dtype=np.float32) for p, n in zip(parts, sizes)
    ])


def native_mesh_from_objects(objects: Iterable, depsgraph, world_offset: Sequence[float] = (0.0, 0.0, 0.0),
                             name: str = "Blender objects"):
    """One native Mesh of the given mesh objects as the depsgraph evaluates them, in world
    coordinates: world = world_offset + Blender position (the scene's frame offset, so
    that meshes line up with georeferenced scans and their probe sets)."""
    _native = native.load()
    arrays = _Arrays()
    for obj in objects:
        if obj.type != "MESH":
            raise MeshExportError(f"object '{obj.name}' is a {obj.type.lower()}, not a mesh")
        _add_object(arrays, obj, obj.evaluated_get(depsgraph), world_offset)
    if not arrays.triangles:
        names = ", ".join(f"'{o.name}'" for o in objects) or "none given"
        raise MeshExportError(f"no triangles to trace in the reference objects ({names}): they need faces")
    corners = [3 * len(t) for t in arrays.triangles]
    return _native.mesh_from_arrays(
        np.concatenate(arrays.vertices),
        np.concatenate(arrays.triangles),
        corner_uvs=_stack_optional(arrays.uvs, corners, 2, 0.0),
        corner_colors=_stack_optional(arrays.colors, corners, 3, 1.0),
        corner_normals=np.concatenate(arrays.normals),
        material=np.concatenate(arrays.material),
        object=np.concatenate(arrays.object),
        materials=[m.as_dict() for m in arrays.materials],
        object_names=arrays.object_names,
        name=name,
    )
