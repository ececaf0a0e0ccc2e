#!/usr/bin/env bash
# Writes a fixed set of outputs of this checkout into OUT (default out/reference_outputs): a
# scan, mesh and scan bakes, probe renders in every mode and filter, splats, ground truth and
# the tiny report. Run it before and after a change that must not alter results, then
# `python3 tools/diff_outputs.py BEFORE AFTER` says what differs (timings aside).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
out="$(mkdir -p "${1:-out/reference_outputs}" && cd "${1:-out/reference_outputs}" && pwd)"
scene=blend/lab_room/lab_room.scene.json
mesh=blend/lab_room/lab_room.obj
q=(--quiet)
./lfprobe scan --mesh "$mesh" --at 2.0 1.5 1.4 --step-deg 2 --noise-mm 1 --out "$out/scan.xyz" "${q[@]}"
./lfprobe camera --position 2.4 1.2 1.5 --look-at 0 3 1.2 --res 96 64 --out "$out/view.json"
./lfprobe camera --position 2.0 1.5 1.4 --look-at 4 1 1.0 --res 96 64 --out "$out/at_probe.json"
./lfprobe bake --mesh "$mesh" --probe 2.0 1.5 1.4 --res 64 --out "$out/mesh_probe" "${q[@]}"
./lfprobe bake --scan "$out/scan.xyz" --scanner 2.0 1.5 1.4 --grid-min 1.5 1.0 1.0 \
  --grid-max 2.5 2.0 1.8 --counts 2 2 2 --res 64 --out "$out/scan_grid" --no-cache "${q[@]}"
./lfprobe render --probes "$out/mesh_probe" --camera "$out/at_probe.json" --out "$out/at_probe.exr" --spp 4 "${q[@]}"
for mode in auto nearest; do
  for filter in nearest bilinear; do
    ./lfprobe render --probes "$out/scan_grid" --camera "$out/view.json" --mode "$mode" \
      --filter "$filter" --out "$out/render_${mode}_${filter}.exr" "${q[@]}"
  done
done
./lfprobe render --probes "$out/scan_grid" --camera "$out/view.json" --blend 1 --spp 1 \
  --storage compact --out "$out/render_paper.exr" "${q[@]}"
./lfprobe splat --scan "$out/scan.xyz" --scanner 2.0 1.5 1.4 --camera "$out/view.json" \
  --out "$out/splat.exr" --no-cache "${q[@]}"
./lfprobe gt --mesh "$mesh" --camera "$out/view.json" --spp 4 --out "$out/gt.exr" "${q[@]}"
./lfprobe report --scene "$scene" --out "$out/report" --preset tiny --threads 0 >"$out/report.log" 2>&1
echo "reference outputs in $out"
