#!/usr/bin/env bash
# The demo, from a fresh clone on Debian 12: installs and builds what is missing (tools/setup.sh),
# builds the lab room scene if it is missing (Blender headless when Blender is installed, since
# it also writes blend/lab_room.blend; the bpy-free generator otherwise), then runs the report
# on it: four simulated scans of the room at the paper's density (0.1°, 21.6 M points; and at 1°),
# probe grids baked from them, views (640 pixels wide) at a probe,
# between probes, near a wall and along a walk rendered by tracing the probes and by Embree
# (ground truth), compared, and written to out/demo/report.html with the images under
# out/demo/images/. Progress and the time of every step go to the terminal.
# Environment: LFPROBE_DEMO_OUT (default out/demo), LFPROBE_DEMO_PRESET (default demo),
# LFPROBE_THREADS (default 0: every core), LFPROBE_REBUILD_SCENE=1 (rebuild the scene).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
out="${LFPROBE_DEMO_OUT:-$root/out/demo}"
preset="${LFPROBE_DEMO_PRESET:-demo}"
threads="${LFPROBE_THREADS:-0}"
scene_json="blend/lab_room/lab_room.scene.json"
demo_start=$(date +%s)
step_start=$demo_start

step_done() {  # prints how long the step took
  local now
  now=$(date +%s)
  echo "   ($1: $((now - step_start)) s)"
  step_start=$now
}

echo "== 1/4 build: tools/setup.sh (installs what is missing, builds the native core's Python module) =="
# The module is all the demo runs (./lfprobe and the add-on load it); tools/test.sh builds the rest.
LFPROBE_BUILD_TARGETS=_native bash tools/setup.sh
step_done "build"

echo "== 2/4 scene: the lab room (blend/lab_room/, blend/lab_room.blend) =="
mkdir -p "$out"
# Built when missing (or with LFPROBE_REBUILD_SCENE=1 after changing blend/scenes/): the
# generator is seeded, so a rebuild writes the same geometry and textures.
if [ "${LFPROBE_REBUILD_SCENE:-0}" = "1" ] || [ ! -f "$scene_json" ] || [ ! -f blend/lab_room.blend ]; then
  if command -v blender >/dev/null 2>&1; then
    echo "building blend/lab_room.blend and its OBJ, textures and scene file with Blender (headless)"
    log="$out/blender_scene_build.log"
    if ! blender -b --factory-startup --python-exit-code 1 -P blend/build_blend.py -- lab_room >"$log" 2>&1; then
      tail -n 20 "$log" >&2
      echo "demo: building the lab room in Blender failed (log: $log)" >&2
      exit 1
    fi
    grep '^blend ' "$log"
  else
    echo "building blend/lab_room/ with the bpy-free generator (Blender is not installed)"
    /usr/bin/python3 -m blend.scenes lab_room
  fi
else
  echo "up to date: $scene_json, blend/lab_room.blend"
fi
step_done "scene"

echo "== 3/4 report: scans, probe bakes, probe renders, ground truth, comparison (preset $preset) =="
./lfprobe report --scene "$scene_json" --out "$out" --preset "$preset" --threads "$threads"
step_done "report"

echo "== 4/4 Blender (headless): four scans imported into the lab room .blend, its probe grid baked,"
echo "   the view between probes traced by the add-on's engine and compared with ground truth =="
if command -v blender >/dev/null 2>&1; then
  bdir="$out/blender"
  mkdir -p "$bdir/scans"
  i=0
  # The scene file's four scanner positions, at the report's finest step (0.1°, 5.4 M points each).
  while read -r x y z; do
    i=$((i + 1))
    ./lfprobe scan --mesh blend/lab_room/lab_room.obj --at "$x" "$y" "$z" --step-deg 0.1 \
      --noise-mm 1 --out "$bdir/scans/scan_$i.xyz" --quiet
  done < <(/usr/bin/python3 -c "import json,sys; [print(*p) for p in json.load(open(sys.argv[1]))['scanners']]" "$scene_json")
  batch() { blender -b --factory-startup --python-exit-code 1 -P addon/lfprobe/cli.py -- --open "$1" "${@:2}" 2>&1 | grep '^lfprobe' || { echo "demo: the Blender step '$2' failed" >&2; exit 1; }; }
  batch blend/lab_room.blend import --scan "$bdir"/scans/scan_*.xyz --grid-from probe_grid \
    --resolution 1024 --save-as "$bdir/lab_room.blend"
  batch "$bdir/lab_room.blend" bake
  batch "$bdir/lab_room.blend" render --camera between_probes --out "$bdir/between_probes.exr"
  batch "$bdir/lab_room.blend" compare --reference-collection geometry --camera between_probes \
    --out "$bdir/compare"
else
  echo "skipped: Blender is not installed (apt-get install blender)"
fi
step_done "Blender"

echo
echo "demo finished in $(( $(date +%s) - demo_start )) s: open $out/report.html"
echo "(images in $out/images/, tables in $out/*.csv, data in $out/report.json;"
echo " the scene in Blender with its baked probes: blender $out/blender/lab_room.blend)"
