"""The EXRs lfprobe renders open in Blender as multilayer images with their passes (Blender 3.4
dropped the analysis channels when they were named status, probe, steps, object: "unknown
channel token"). A probe trace (`./lfprobe render`) and a ground truth (`./lfprobe gt`) of the
box room, 16×12, are loaded with bpy.data.images.load; Blender lists their passes, and each
pass, read back through the compositor, equals the native reader's plane bit for bit."""

from __future__ import annotations

import os

import bpy
import numpy as np

import helpers
import probe_scene
from exr_channels import read_exr_channels

SIZE = (16, 12)


def _write_room_obj(path: str) -> str:
    """The box room as an OBJ of 6 quads (the ground truth's mesh)."""
    lo, hi = helpers.BOX_ROOM_MIN, helpers.BOX_ROOM_MAX
    corners = [(x, y, z) for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
    faces = [(1, 3, 4, 2), (5, 6, 8, 7), (1, 2, 6, 5), (3, 7, 8, 4), (1, 5, 7, 3), (2, 4, 8, 6)]
    with open(path, "w", encoding="utf-8") as stream:
        stream.writelines(f"v {x} {y} {z}\n" for x, y, z in corners)
        stream.writelines("f " + " ".join(map(str, face)) + "\n" for face in faces)
    return path


def _rendered_exrs(folder: str) -> dict:
    """{"render": probe trace EXR, "gt": ground truth EXR} of one camera, by the bpy-free CLI."""
    camera = os.path.join(folder, "camera.json")
    for args in (
        ("camera", "--position", *probe_scene.CAMERA_POSITION, "--look-at", *probe_scene.CAMERA_TARGET,
         "--res", *SIZE, "--lens", 20, "--out", camera),
        ("render", "--probes", probe_scene.baked_probe_set(), "--camera", camera,
         "--out", os.path.join(folder, "render.exr"), "--quiet"),
        ("gt", "--mesh", _write_room_obj(os.path.join(folder, "room.obj")), "--camera", camera,
         "--out", os.path.join(folder, "gt.exr"), "--quiet"),
    ):
        result = probe_scene.lfprobe_cli(*args)
        assert result.returncode == 0, f"lfprobe {args[0]}: {result.stdout}{result.stderr}"
    return {"render": os.path.join(folder, "render.exr"), "gt": os.path.join(folder, "gt.exr")}


def _compositor():
    """(node tree, the node whose first input the scene's render writes): the scene's
    compositor, which Blender 5.0 keeps in a node group and 3.4 in the scene."""
    scene = bpy.context.scene
    if hasattr(scene, "compositing_node_group"):
        tree = bpy.data.node_groups.new("Read passes", "CompositorNodeTree")
        tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
        scene.compositing_node_group = tree
        return tree, tree.nodes.new("NodeGroupOutput")
    scene.use_nodes = True
    tree = scene.node_tree
    tree.nodes.clear()
    return tree, tree.nodes.new("CompositorNodeComposite")


def _pass_through_compositor(tree, sink, socket, path: str) -> dict:
    """Renders the compositor with `socket` as its output into an uncompressed float EXR at
    `path`; that file's channels."""
    for link in list(sink.inputs[0].links):
        tree.links.remove(link)
    tree.links.new(socket, sink.inputs[0])
    scene = bpy.context.scene
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGBA"
    settings.color_depth = "32"
    settings.exr_codec = "NONE"
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return read_exr_channels(path)


def test_rendered_exrs_open_in_blender_with_their_passes():
    folder = helpers.tmp_dir()
    native = helpers.addon("core.native").load()
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = SIZE
    scene.render.resolution_percentage = 100
    tree, sink = _compositor()
    for kind, path in _rendered_exrs(folder).items():
        expected = native.read_image(path)
        assert expected["rgba"].shape[:2] == SIZE[::-1], kind
        assert (expected["status"] == 1).all(), f"{kind}: the view should hit the room's walls everywhere"
        image = bpy.data.images.load(path)
        node = tree.nodes.new("CompositorNodeImage")
        node.image = image  # loads the file and lists its passes as the node's outputs
        # Blender's API gives a multilayer image no size or pixels of its own (image.size is
        # (0, 0) for Blender's own multilayer renders too): its passes hold them.
        assert image.type == "MULTILAYER", (kind, image.type)
        passes = {"Combined", "Depth", "N", "status", "probe", "steps"} | ({"object"} if kind == "gt" else set())
        outputs = {socket.name for socket in node.outputs}
        assert passes <= outputs, f"{kind}: Blender lists the passes {sorted(outputs)}, not {sorted(passes)}"
        # Every pass as Blender read it, pixel for pixel (the render size is the image's; a pass
        # Blender did not read comes out as zeros).
        planes = {"Depth": expected["depth"], "status": expected["status"], "probe": expected["probe"],
                  "steps": expected["steps"]}
        if kind == "gt":  # read_image has no object plane; the file's channel as OpenEXR reads it
            planes["object"] = dict(native.read_exr_channels(path)[0])["object.X"]
            assert (planes["object"] == 0).all(), "the ground truth sees the room, object 0"
        for name, plane in planes.items():
            read = _pass_through_compositor(tree, sink, node.outputs[name], os.path.join(folder, f"{kind}_{name}.exr"))
            assert read["R"].shape == plane.shape, (kind, name, read["R"].shape)
            assert np.array_equal(read["R"], plane.astype(np.float32)), (kind, name)
        for name, plane in (("Combined", expected["rgba"]), ("N", expected["normal"])):
            read = _pass_through_compositor(tree, sink, node.outputs[name], os.path.join(folder, f"{kind}_{name}.exr"))
            for index in range(plane.shape[-1]):
                assert np.array_equal(read["RGBA"[index]], plane[..., index]), (kind, name, index)
        tree.nodes.remove(node)
