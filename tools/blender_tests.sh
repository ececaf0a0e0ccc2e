#!/usr/bin/env bash
# The add-on's tests inside Blender, on both versions it supports:
#   Debian's Blender 3.4.1 (the add-on as a legacy add-on, bl_info) and
#   the newest bpy wheel for Python 3.11, bpy 5.0.1 (the add-on as an extension, blender_manifest.toml).
# and the interactive paths (modal import and bake, Esc, overlay and panel drawing) in a
# Blender 3.4.1 window under Xvfb (the wheel has no windows).
# Usage: bash tools/blender_tests.sh [test name substrings]   (e.g. test_import bake; the
# window checks run only without names)
set -u
cd "$(dirname "$0")/.."

BPY_VERSION=5.0.1
BPY_DIR=build/bpy-wheel

if ! command -v blender >/dev/null; then
    echo "blender_tests: Debian's blender is not installed (apt-get install blender)" >&2
    exit 1
fi
if [ ! -f "$BPY_DIR/bpy-$BPY_VERSION.dist-info/METADATA" ]; then
    # --no-deps: bpy asks for numpy >= 1.26, but the native module is built against Debian's
    # numpy 1.24, which bpy's own use of numpy works with (the tests below show it).
    /usr/bin/python3 -m pip install --quiet --no-deps --target "$BPY_DIR" "bpy==$BPY_VERSION" || {
        echo "blender_tests: could not install the bpy $BPY_VERSION wheel into $BPY_DIR" >&2
        exit 1
    }
fi

if [ $# -eq 0 ] && ! command -v xvfb-run >/dev/null; then
    echo "blender_tests: xvfb-run is not installed (apt-get install xvfb xauth)" >&2
    exit 1
fi

status=0
echo "== Blender $(blender --version 2>/dev/null | head -n 1 | cut -d' ' -f2) (legacy add-on)"
blender -b --factory-startup --python-exit-code 1 -P tests/blender/run.py -- "$@" || status=1
echo "== bpy $BPY_VERSION wheel (extension)"
PYTHONPATH="$BPY_DIR" /usr/bin/python3 tests/blender/run.py "$@" || status=1
if [ $# -eq 0 ]; then
    echo "== Blender 3.4.1 window under Xvfb (modal operators, drawing)"
    log="$(mktemp)"
    xvfb-run -a -s "-screen 0 1280x800x24" \
        blender --factory-startup --enable-event-simulate -P tests/blender/run_ui.py 2>&1 | tee "$log"
    # A failed check sets the exit status; an error inside a draw() only prints a traceback.
    if [ "${PIPESTATUS[0]}" -ne 0 ] || grep -q "Traceback" "$log"; then
        echo "blender_tests: the window checks failed" >&2
        status=1
    fi
    rm -f "$log"
    echo "== Blender 3.4.1 window under Xvfb: Esc at F12, a real key press (xdotool)"
    if ! command -v xdotool >/dev/null; then
        echo "blender_tests: xdotool is not installed (apt-get install xdotool)" >&2
        status=1
    elif ! xvfb-run -a -s "-screen 0 1280x800x24" \
        blender --factory-startup -P tests/blender/run_f12_esc.py; then
        echo "blender_tests: Esc did not stop F12 in time" >&2
        status=1
    fi
fi
exit $status
