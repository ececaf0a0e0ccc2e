#!/usr/bin/env bash
# The demo: builds what is missing, then runs the scan → probe pipeline on the real pump-room
# laser scan from ../shared/data and prints what the probe set holds and where it is.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
data="${LFPROBE_SHARED_DATA:-$root/../shared/data}"
out="$root/out/demo"
bash tools/setup.sh
mkdir -p "$out"
echo "== bake: pump-room scan (155,201 points), a probe at the scanner and a 3×3×2 grid in the room =="
./lfprobe bake --scan "$data/scans/pumpA_xyzrgb.xyz" --scanner 0 0 0 \
  --probe 0 0 0 --res 1024 --out "$out/pump_at_scanner" --cache "$out/cache"
./lfprobe bake --scan "$data/scans/pumpA_xyzrgb.xyz" --scanner 0 0 0 \
  --grid-min -2 -4 -0.5 --grid-max 0.5 -1.5 0.5 --counts 3 3 2 --res 512 \
  --out "$out/pump_grid" --cache "$out/cache"
echo "== what the probe sets hold =="
./lfprobe info "$out/pump_at_scanner"
./lfprobe info "$out/pump_grid" --json > "$out/pump_grid_info.json"
./lfprobe info "$out/pump_grid"
echo
echo "probe sets: $out/pump_at_scanner and $out/pump_grid (manifest.json + one EXR per probe);"
echo "open a probe_*.exr in Blender's Image Editor to see its radiance, distance (Z) and normals."
