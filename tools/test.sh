#!/usr/bin/env bash
# Every test: installs and builds what is missing (tools/setup.sh, with -Werror), checks the
# C++ sources' formatting, runs the GoogleTest suite, builds and runs it again under
# AddressSanitizer + UndefinedBehaviorSanitizer, runs every fuzz harness for seconds, then the
# pytest suite of the bpy-free Python.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
# The shared test data (docs/DESIGN.md: ../shared/data beside the checkout). A clone made elsewhere
# from a local checkout (git clone /path/to/checkout) finds it beside the checkout it came from.
if [ -z "${LFPROBE_SHARED_DATA:-}" ]; then
  LFPROBE_SHARED_DATA="$root/../shared/data"
  origin="$(git -C "$root" remote get-url origin 2>/dev/null || true)"
  if [ ! -d "$LFPROBE_SHARED_DATA" ] && [ -n "$origin" ] && [ -d "$origin/../shared/data" ]; then
    LFPROBE_SHARED_DATA="$(cd "$origin/../shared/data" && pwd)"
  fi
fi
if [ ! -d "$LFPROBE_SHARED_DATA/scans" ] || [ ! -d "$LFPROBE_SHARED_DATA/meshes" ]; then
  echo "tools/test.sh: the shared test data is not at $LFPROBE_SHARED_DATA (expected scans/ and" \
    "meshes/ there, the project's ../shared/data): set LFPROBE_SHARED_DATA to its folder" >&2
  exit 2
fi
export LFPROBE_SHARED_DATA
echo "test data: $LFPROBE_SHARED_DATA"

echo "== build (Release, -Werror) =="
LFPROBE_WERROR=1 bash tools/setup.sh

echo "== C++ formatting (clang-format, the repository's .clang-format) =="
git ls-files -z '*.cpp' '*.hpp' | xargs -0 clang-format --dry-run --Werror

echo "== the core's sources as one unit (names in anonymous namespaces; GCC and Clang) =="
# The build compiles the core eight sources to a unit (CMakeLists.txt: LFPROBE_UNITY_BUILD), so
# a name in one source's anonymous namespace must not be another's, and which sources share a
# unit changes whenever a source is added. All of them in one unit, for syntax only (about 15 s),
# finds such a clash before a new source moves it into a batch. Clang, with the build's warnings
# as errors, finds in the same pass what only the fuzzing build (clang) would otherwise meet
# twenty minutes later: C++ Clang refuses where GCC accepts (a structured binding captured by a
# lambda, in Clang 14), and warnings only Clang gives.
one_unit="$(mktemp --suffix=.cpp)"
for source in native/src/*.cpp; do echo "#include \"$PWD/$source\""; done > "$one_unit"
unit_flags=(-std=c++20 -fsyntax-only -DGLM_FORCE_XYZW_ONLY -DIMATH_HALF_NO_LOOKUP_TABLE
  -DLFPROBE_VERSION='"check"' -Inative/include -Inative/src -I/usr/include/stb
  -isystem /usr/include/OpenEXR -isystem /usr/include/Imath)
g++ "${unit_flags[@]}" "$one_unit"
clang++ "${unit_flags[@]}" -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion \
  -Werror "$one_unit"
rm -f "$one_unit"

echo "== native tests =="
(cd build && ctest --output-on-failure -j"$(nproc)")

echo "== native tests under AddressSanitizer + UndefinedBehaviorSanitizer =="
# -O1 -g1: what the sanitizers' documentation recommends (line tables for the reports), and half
# the compile time of -O2 -g.
# The same build makes a sanitized Python module, in a copy of the add-on's folder of its own
# (build-asan/addon), so that the Release module in addon/ is never replaced.
asan_addon="$root/build-asan/addon"
mkdir -p "$asan_addon/lfprobe"
find "$asan_addon/lfprobe" -mindepth 1 -not -name '_native*.so' -delete
tar -C addon --exclude='_native*.so' --exclude=__pycache__ -cf - lfprobe | tar -C "$asan_addon" -xf -
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DLFPROBE_SANITIZE=ON \
  -DLFPROBE_PYTHON=ON -DPython_EXECUTABLE=/usr/bin/python3 -DLFPROBE_MODULE_DIR="$asan_addon/lfprobe" \
  -DLFPROBE_WERROR=ON >/dev/null
cmake --build build-asan -j"$(nproc)" --target lfprobe_tests _native
ASAN_OPTIONS="detect_leaks=1:abort_on_error=1" UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
  ./build-asan/lfprobe_tests --gtest_brief=1

echo "== the Python module and the command line under AddressSanitizer + UndefinedBehaviorSanitizer =="
# The bindings (jobs, cancellation, numpy conversion, error translation) and every CLI path the
# pytest files below drive, run against the sanitized module: the interpreter is not
# instrumented, so the runtime is preloaded; CPython's own allocations live until exit by design,
# so leaks are not reported; libstdc++ is preloaded with it, so that the runtime finds the
# __cxa_throw it intercepts. Tests that start Dask workers, Open3D or Blender stay in the Release
# run below.
asan_env=(LFPROBE_ADDON_DIR="$asan_addon" PYTHONPATH="$asan_addon:$root/build/pydeps"
  LD_PRELOAD="$(gcc -print-file-name=libasan.so):$(gcc -print-file-name=libstdc++.so)"
  ASAN_OPTIONS="detect_leaks=0:abort_on_error=1" UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1")
env "${asan_env[@]}" /usr/bin/python3 -c "
import lfprobe._native as m, sys
sys.exit(0 if m.__file__.startswith('$asan_addon') else 'not the sanitized module: ' + m.__file__)"
env "${asan_env[@]}" /usr/bin/python3 -m pytest -q -p no:cacheprovider \
  tests/python/test_native_api.py tests/python/test_cli.py tests/python/test_render_cli.py \
  tests/python/test_mesh_cli.py tests/python/test_place_cli.py tests/python/test_storage_cli.py \
  tests/python/test_missing_inputs.py tests/python/test_rejected_inputs.py tests/python/test_interrupts.py \
  tests/python/test_trace_hints.py tests/python/test_scan_formats.py tests/python/test_adaptive.py \
  tests/python/test_hard_scene.py

echo "== fuzzing: a short run of every libFuzzer harness (clang, ASan + UBSan) =="
# Seconds each, from the seeds (tools/fuzz.sh runs them for long; its help says how).
bash tools/fuzz.sh --seconds 4 --jobs 2 --fresh-corpus

echo "== Python tests (no Blender) =="
# Independent implementations the metrics are checked against, kept out of the system Python.
pydeps="$root/build/pydeps"
if ! PYTHONPATH="$pydeps" /usr/bin/python3 -c "import flip_evaluator" 2>/dev/null; then
  /usr/bin/python3 -m pip install -q --disable-pip-version-check --no-deps --target "$pydeps" \
    "flip-evaluator==1.7"
fi
PYTHONPATH="$root/addon:$pydeps" /usr/bin/python3 -m pytest -q tests/python

echo "== Blender add-on tests (Blender 3.4.1, the bpy wheel, a window under Xvfb) =="
bash tools/blender_tests.sh
