"""The project's demo and test scenes, built without Blender.

Each scene module (lab_room, hard_scene) builds its geometry as triangle lists with UVs,
materials and procedurally generated base-colour textures (numpy, seeded: the same bytes on
every run) and describes its scanners, probe grid and views in the `<name>.scene.json`
contract. `python3 -m blend.scenes` writes OBJ + MTL + PNG textures + scene JSON;
blend/build_blend.py turns the same data into .blend files inside Blender.
"""

SCENE_NAMES = ("lab_room", "hard_scene")


def build_scene(name: str):
    """(MeshBuilder, scene description dict) of the named scene."""
    if name == "lab_room":
        from . import lab_room

        return lab_room.build()
    if name == "hard_scene":
        from . import hard_scene

        return hard_scene.build()
    raise ValueError(f"unknown scene '{name}': expected one of {', '.join(SCENE_NAMES)}")
