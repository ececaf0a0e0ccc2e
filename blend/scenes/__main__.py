"""`python3 -m blend.scenes [lab_room|hard_scene|all] [--out DIR]` (from the repository root):
writes each scene's OBJ + MTL + textures/*.png and `<name>.scene.json` into DIR/<scene>/
(default: blend/<scene>/, beside the .blend files)."""

from __future__ import annotations

import argparse
import os
import sys

from . import SCENE_NAMES
from .output import write_scene

BLEND_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python3 -m blend.scenes", description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", nargs="?", default="all", choices=(*SCENE_NAMES, "all"))
    parser.add_argument("--out", default=BLEND_DIR, help="folder that receives one sub-folder per scene")
    args = parser.parse_args(argv)
    names = SCENE_NAMES if args.scene == "all" else (args.scene,)
    for name in names:
        try:
            info = write_scene(name, args.out)
        except OSError as error:
            print(f"scene {name}: cannot write into {args.out}: {error}", file=sys.stderr)
            return 1
        print(f"scene {name}: {info['triangles']} triangles, {info['textures']} textures, "
              f"{info['scene']} ({info['seconds']:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
