"""Packaging: the add-on enables and disables cleanly (twice), bl_info and the extension
manifest agree, the native module is found inside the package, and a missing or foreign
native module is reported plainly."""

import os
import shutil
import sys
import tomllib

import bpy

import helpers


def _registered() -> dict:
    return {
        "import operator": hasattr(bpy.ops.import_scene, "lfprobe_scan") and "lfprobe_scan" in dir(bpy.ops.import_scene),
        "grid operators": "lfprobe_grid_add" in dir(bpy.ops.object),
        "bake operator": "lfprobe_bake" in dir(bpy.ops.object),
        "scan properties": hasattr(bpy.types.Object, "lfprobe_scan"),
        "grid properties": hasattr(bpy.types.Object, "lfprobe_grid"),
        "grid panel": hasattr(bpy.types, "LFPROBE_PT_grid"),
    }


def test_enable_disable_twice():
    overlay = helpers.addon("blender.ui.overlay")
    for round_ in range(2):
        state = _registered()
        assert all(state.values()), f"round {round_}: not registered: {state}"
        assert overlay.is_drawing()
        helpers.disable_addon()
        state = _registered()
        assert not any(state.values()), f"round {round_}: left registered after disabling: {state}"
        assert not overlay.is_drawing()
        assert helpers.addon_module_name() not in bpy.context.preferences.addons
        helpers.enable_addon()
    # Still usable after the cycles: a grid can be added.
    assert bpy.ops.object.lfprobe_grid_add() == {"FINISHED"}
    assert bpy.context.active_object.lfprobe_grid.is_grid


def _bl_info() -> dict:
    # Read from the source: Blender 4.2+ drops bl_info from a module loaded as an extension.
    import ast

    with open(os.path.join(helpers.ADDON_DIR, "__init__.py"), encoding="utf-8") as stream:
        tree = ast.parse(stream.read())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "bl_info" for t in node.targets):
            return ast.literal_eval(node.value)
    raise AssertionError("lfprobe/__init__.py has no bl_info")


def test_bl_info_and_manifest_agree():
    bl_info = _bl_info()
    with open(os.path.join(helpers.ADDON_DIR, "blender_manifest.toml"), "rb") as stream:
        manifest = tomllib.load(stream)
    for key in ("schema_version", "id", "version", "name", "tagline", "maintainer", "type",
                "blender_version_min", "license"):
        assert key in manifest, f"blender_manifest.toml lacks {key}"
    assert manifest["id"] == "lfprobe"
    assert manifest["type"] == "add-on"
    assert manifest["version"] == ".".join(map(str, bl_info["version"]))
    assert bl_info["blender"] <= (3, 4, 1)
    assert tuple(map(int, manifest["blender_version_min"].split("."))) >= (4, 2, 0)


def test_manifest_passes_blenders_extension_validator():
    if not helpers.uses_extensions():
        raise helpers.Skip("Blender 3.4 has no extension platform")
    import subprocess

    validator = os.path.join(bpy.utils.system_resource("SCRIPTS"), "addons_core", "bl_pkg", "cli", "blender_ext.py")
    assert os.path.isfile(validator), validator
    python = sys.executable if os.path.basename(sys.executable).startswith("python") else "/usr/bin/python3"
    result = subprocess.run([python, validator, "validate", helpers.ADDON_DIR], capture_output=True, text=True)
    assert result.returncode == 0 and "Success" in result.stdout, result.stdout + result.stderr


def test_native_module_lives_in_the_package():
    name = helpers.addon_module_name()
    _native = helpers.addon("core.native").load()
    assert _native.__name__ == f"{name}._native", _native.__name__
    assert os.path.dirname(_native.__file__) == os.path.realpath(helpers.ADDON_DIR) or \
        os.path.samefile(os.path.dirname(_native.__file__), helpers.ADDON_DIR)
    if helpers.uses_extensions():
        # An extension must not need (or create) a top-level "lfprobe" package.
        assert "lfprobe" not in sys.modules


def test_missing_or_foreign_native_module_is_explained():
    # A copy of the package without its native module, under another name.
    root = helpers.tmp_dir()
    package = os.path.join(root, "lfprobe_without_native")
    shutil.copytree(os.path.join(helpers.ADDON_DIR, "core"), os.path.join(package, "core"),
                    ignore=shutil.ignore_patterns("__pycache__"))
    open(os.path.join(package, "__init__.py"), "w").close()
    sys.path.insert(0, root)
    try:
        import lfprobe_without_native.core.native as loader

        try:
            loader.load()
        except loader.NativeModuleError as error:
            message = str(error)
        else:
            raise AssertionError("load() found a native module that is not there")
        assert "not built" in message and package in message and "tools/setup.sh" in message, message

        # A module built for another Python (its suffix names that Python).
        open(os.path.join(package, "_native.cpython-310-x86_64-linux-gnu.so"), "wb").close()
        try:
            loader.load()
        except loader.NativeModuleError as error:
            message = str(error)
        else:
            raise AssertionError("load() accepted a module built for Python 3.10")
        assert "built for another Python" in message and "cpython-310" in message, message
        assert f"{sys.version_info.major}.{sys.version_info.minor}" in message, message
    finally:
        sys.path.remove(root)
        for key in [k for k in sys.modules if k.startswith("lfprobe_without_native")]:
            del sys.modules[key]
