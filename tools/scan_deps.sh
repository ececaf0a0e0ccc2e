#!/usr/bin/env bash
# Installs the Python libraries lfprobe reads E57 and LAS/LAZ scans with (pye57, which wraps
# libE57Format, with pyquaternion, which it imports; laspy with the lazrs LAZ backend) into
# build/pydeps, pinned, only when missing. lfprobe looks there itself (core/scan_formats.py),
# so ./lfprobe, pytest and Blender (3.4 and the bpy wheel, both on the system Python 3.11) all
# find them without touching the system Python. --no-deps: they need only numpy, which Debian's
# python3-numpy provides (the native module is built against it).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
pydeps="${LFPROBE_PYDEPS_DIR:-$root/build/pydeps}"
python="${LFPROBE_PYTHON:-/usr/bin/python3}"
wanted=("pye57==0.4.19" "pyquaternion==0.9.9" "laspy==2.7.0" "lazrs==0.8.2")
if PYTHONPATH="$pydeps" "$python" - "${wanted[@]}" <<'PY' 2>/dev/null; then
import importlib.metadata as metadata, sys
for pin in sys.argv[1:]:
    name, version = pin.split("==")
    if metadata.version(name) != version:
        sys.exit(1)
PY
  exit 0
fi
echo "lfprobe scan formats: installing ${wanted[*]} into $pydeps"
"$python" -m pip install -q --disable-pip-version-check --no-deps --upgrade --target "$pydeps" "${wanted[@]}"
