"""Runs the add-on's Blender tests (tests/blender/test_*.py, functions test_*() without
arguments), each in factory settings with the add-on freshly enabled.

    blender -b --factory-startup --python-exit-code 1 -P tests/blender/run.py -- [name substrings]
    python3 tests/blender/run.py [name substrings]      # with the bpy wheel importable

A test is selected when any substring occurs in "file::function". Prints PASS/FAIL (with the
traceback) per test, SKIP for a test that raises helpers.Skip (it does not apply to this
Blender), and exits non-zero when any fails."""

import glob
import importlib
import os
import sys
import time
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
INSIDE_BLENDER = "bpy" in sys.modules  # run by blender -P (else by python3 with the bpy wheel)


def _arguments() -> list:
    if "--" in sys.argv:
        return sys.argv[sys.argv.index("--") + 1 :]
    return [] if INSIDE_BLENDER else sys.argv[1:]  # Blender's own arguments are not ours


def _collect(filters: list) -> list:
    tests = []
    for path in sorted(glob.glob(os.path.join(HERE, "test_*.py"))):
        module_name = os.path.splitext(os.path.basename(path))[0]
        module = importlib.import_module(module_name)
        for name, function in vars(module).items():
            if name.startswith("test_") and callable(function):
                label = f"{module_name}::{name}"
                if not filters or any(f in label for f in filters):
                    tests.append((label, function))
    return tests


def _reset(helpers) -> None:
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    helpers.enable_addon()


def main() -> int:
    sys.path.insert(0, HERE)  # the test modules and helpers
    import bpy

    import helpers

    filters = _arguments()
    tests = _collect(filters)
    print(f"lfprobe Blender tests: Blender {bpy.app.version_string}, "
          f"add-on as {'extension' if helpers.uses_extensions() else 'legacy add-on'}, {len(tests)} tests")
    if not tests:
        print(f"no test matches {filters}")
        return 1
    failures, skipped = [], 0
    for label, function in tests:
        start = time.monotonic()
        try:
            _reset(helpers)
            function()
        except helpers.Skip as reason:
            skipped += 1
            print(f"SKIP {label}: {reason}")
        except Exception:
            failures.append(label)
            print(f"FAIL {label} ({time.monotonic() - start:.1f} s)")
            traceback.print_exc()
        else:
            print(f"PASS {label} ({time.monotonic() - start:.1f} s)")
        sys.stdout.flush()
    try:
        helpers.disable_addon()
    except Exception:
        traceback.print_exc()
        failures.append("disabling the add-on at the end")
    print(f"{len(tests) - len(failures) - skipped} passed, {len(failures)} failed, {skipped} skipped")
    for label in failures:
        print(f"  failed: {label}")
    return 1 if failures else 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    sys.exit(code)
