#!/usr/bin/env bash
# Installs what lfprobe needs on Debian 12 (only what is missing) and builds the native core:
# the library, the Python module addon/lfprobe/_native*.so and the GoogleTest suite.
# Environment: LFPROBE_BUILD_DIR (default build/), LFPROBE_WERROR=1 for -Werror,
# LFPROBE_BUILD_TARGETS (default: every target; the demo builds only the Python module, _native,
# which is what ./lfprobe and the add-on load: the GoogleTest suite is two fifths of a build).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

packages=(
  cmake ninja-build g++ python3-dev python3-numpy python3-pytest
  pybind11-dev libembree-dev libopenexr-dev libglm-dev libtbb-dev
  nlohmann-json3-dev libfast-float-dev libgtest-dev libstb-dev libxxhash-dev libdeflate-dev
  python3-scipy python3-skimage python3-pip python3-matplotlib python3-open3d python3-distributed blender xvfb
  xauth xdotool clang-format clang libclang-rt-14-dev llvm
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "lfprobe setup: installing ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# E57 and LAS/LAZ import (optional: without them the other formats work and those files are
# refused with a message saying to run this).
bash "$root/tools/scan_deps.sh" || echo "lfprobe setup: could not install the E57/LAS libraries (tools/scan_deps.sh); E57 and LAS/LAZ import stays off" >&2

build="${LFPROBE_BUILD_DIR:-$root/build}"
werror=OFF
[ "${LFPROBE_WERROR:-0}" = "1" ] && werror=ON
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DPython_EXECUTABLE=/usr/bin/python3 -DLFPROBE_WERROR="$werror" >/dev/null
targets=()
for target in ${LFPROBE_BUILD_TARGETS:-}; do
  targets+=(--target "$target")
done
cmake --build "$build" -j"$(nproc)" "${targets[@]}"
