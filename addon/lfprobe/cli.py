"""Headless batch entry of the Blender add-on: import scans, bake, add probes for views, render and
compare a saved scene.

    blender -b --python-exit-code 1 -P <add-on>/cli.py -- --open scene.blend import --scan FILE... [--grid-from EMPTY] --save-as OUT.blend
    blender -b --python-exit-code 1 -P <add-on>/cli.py -- --open scene.blend bake [--grid NAME] [--storage full|compact]
    blender -b --python-exit-code 1 -P <add-on>/cli.py -- --open scene.blend place (--views CAMERA... | --camera-path)
    blender -b --python-exit-code 1 -P <add-on>/cli.py -- --open scene.blend render [--camera NAME] --out IMG.exr
    blender -b --python-exit-code 1 -P <add-on>/cli.py -- --open scene.blend compare --reference OBJ... --out DIR

--open opens the .blend after the add-on is enabled, so Blender knows the render engine LFPROBE
while loading it; `blender -b scene.blend ... -P cli.py -- COMMAND` works as well, but Blender
then loads the file first and prints "Engine 'LFPROBE' not available" for a scene rendering with
it (unless the add-on is enabled in Blender's preferences). The add-on is used as it is enabled in Blender (legacy add-on or extension), or else imported
from the folder this file lies in (whose parent is put on sys.path) and enabled for this run
only. Exit status: 0 success, 2 bad input (the message says what and where), 1 other
failures, 130 cancelled. Run inside Blender only; the bpy-free command line is ./lfprobe.
"""

from __future__ import annotations

import importlib
import os
import sys

EXIT_FAILURE = 1


class AddOnNotEnabled(Exception):
    """The add-on could not be enabled, so none of its commands can run (exit status 1)."""


def _add_on_package():
    """The add-on's package, enabled: an already enabled copy, else the one holding this file."""
    import addon_utils
    import bpy

    for name in bpy.context.preferences.addons.keys():
        if name == "lfprobe" or name.endswith(".lfprobe"):
            return importlib.import_module(name)
    package_dir = os.path.dirname(os.path.abspath(__file__))
    parent = os.path.dirname(package_dir)
    if parent not in sys.path:
        sys.path.insert(0, parent)
    package_name = os.path.basename(package_dir)
    errors = []
    module = addon_utils.enable(package_name, default_set=False, handle_error=errors.append)
    if module is None:
        detail = f": {errors[0]}" if errors else ""
        raise AddOnNotEnabled(f"cannot enable the lfprobe add-on from {package_dir}{detail}")
    return module


def main(argv=None) -> int:
    """Enables the add-on and runs its batch command (lfprobe.blender.batch); the exit status."""
    try:
        package = _add_on_package()
        batch = importlib.import_module(f"{package.__name__}.blender.batch")
    except (AddOnNotEnabled, ImportError) as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return EXIT_FAILURE
    return batch.main(sys.argv if argv is None else argv)


if __name__ == "__main__":
    sys.stdout.flush()
    status = main()
    sys.stdout.flush()
    sys.stderr.flush()
    if status:
        sys.exit(status)
