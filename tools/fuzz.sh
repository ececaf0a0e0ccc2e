#!/usr/bin/env bash
# The libFuzzer harnesses of tests/fuzz, built with clang under AddressSanitizer and
# UndefinedBehaviorSanitizer (float-cast-overflow included) in build-fuzz/, run on a corpus kept
# in build-fuzz/corpus/<harness> (seeded from tests/fuzz's seed script and ../shared/data).
#
#   bash tools/fuzz.sh [--seconds N | --runs N] [--jobs J] [--fresh-corpus] [HARNESS ...]
#
# --seconds N: each harness runs N seconds (default 60); --runs N: N executions each instead.
# --jobs J: J harnesses at a time (default 1). --fresh-corpus: start from the seeds in a
# temporary corpus, leaving build-fuzz/corpus as it is (the test suite's short runs).
# HARNESS: text_scan, ply, obj_mtl, camera, manifest, scan_cache, prepared_cloud, spatial_cloud
# (default: all).
# A crash stops its harness and leaves the input in build-fuzz/crashes/; the command then exits 1.
# Each run's figures are printed and appended to build-fuzz/fuzz_runs.csv, whose totals per
# harness are printed at the end.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

seconds=60
runs=""
jobs=1
fresh=0
harnesses=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    --fresh-corpus) fresh=1; shift ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    -*) echo "tools/fuzz.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) harnesses+=("$1"); shift ;;
  esac
done
all=(text_scan ply obj_mtl camera manifest scan_cache prepared_cloud spatial_cloud)
[ ${#harnesses[@]} -gt 0 ] || harnesses=("${all[@]}")
for h in "${harnesses[@]}"; do
  [ -f "tests/fuzz/${h}_fuzzer.cpp" ] || { echo "tools/fuzz.sh: no harness $h (tests/fuzz/${h}_fuzzer.cpp)" >&2; exit 2; }
done
shared="${LFPROBE_SHARED_DATA:-$root/../shared/data}"

command -v clang++ >/dev/null || { echo "tools/fuzz.sh: clang++ is missing; run bash tools/setup.sh" >&2; exit 2; }
build=build-fuzz
# -O1 -g1: what libFuzzer's and the sanitizers' documentation recommend.
cmake -S . -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DLFPROBE_SANITIZE=ON -DLFPROBE_FUZZ=ON \
  -DLFPROBE_PYTHON=OFF -DLFPROBE_TESTS=OFF -DLFPROBE_WERROR=ON >/dev/null
targets=()
for h in "${harnesses[@]}"; do targets+=("${h}_fuzzer"); done
cmake --build "$build" -j"$(nproc)" --target "${targets[@]}"

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
seeds="$work/seeds"
/usr/bin/python3 tools/fuzz_seeds.py "$shared" "$seeds"
mkdir -p "$build/crashes"
[ -f "$build/fuzz_runs.csv" ] || echo "date,harness,executions,seconds,corpus_inputs,result" >"$build/fuzz_runs.csv"

run_one() {
  local h="$1" corpus log
  if [ "$fresh" = 1 ]; then corpus="$work/corpus/$h"; else corpus="$build/corpus/$h"; fi
  mkdir -p "$corpus"
  log="$work/$h.log"
  local limit=(-max_total_time="$seconds")
  [ -n "$runs" ] && limit=(-runs="$runs")
  local result=ok started
  started="$(date +%s)"
  # The limits make a runaway allocation or a hang a finding instead of a stalled machine.
  # malloc_context_size=0: no stack is recorded per allocation (a tenth of the time of a run);
  # replaying a saved input (build-fuzz/<harness>_fuzzer FILE) reports with full stacks.
  local status=0
  ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:malloc_context_size=0" \
  UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
    "$build/${h}_fuzzer" "${limit[@]}" -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=30 \
    -print_final_stats=1 -artifact_prefix="$build/crashes/${h}-" "$corpus" "$seeds/${h}_fuzzer" \
    >"$log" 2>&1 || status=$?
  # 72: libFuzzer's exit on Ctrl-C (SIGINT), which stops a run without a finding.
  case "$status" in 0) ;; 72) result=interrupted ;; *) result=crash ;; esac
  local execs secs inputs
  # After a crash libFuzzer prints no final stats: the last status line has the count.
  execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)"
  [ -n "$execs" ] || execs="$(sed -n 's/^#\([0-9]*\).*/\1/p' "$log" | tail -1)"
  secs=$(( $(date +%s) - started ))
  inputs="$(find "$corpus" -type f | wc -l)"
  echo "$(date -u +%FT%TZ),$h,${execs:-0},${secs:-0},$inputs,$result" >>"$build/fuzz_runs.csv"
  if [ "$result" != crash ]; then
    printf '%-11s %10s executions in %5ss (%s/s), corpus %s inputs\n' "$h" "${execs:-?}" \
      "${secs:-?}" "$(( ${execs:-0} / (${secs:-1} > 0 ? ${secs:-1} : 1) ))" "$inputs"
  else
    cp "$log" "$build/crashes/$h.log"
    echo "$h: CRASH (input and log saved in $build/crashes/); the end of its log:" >&2
    grep -v '^#' "$log" | tail -40 >&2
    return 1
  fi
}

failed=0
pids=()
for h in "${harnesses[@]}"; do
  run_one "$h" &
  pids+=($!)
  if [ ${#pids[@]} -ge "$jobs" ]; then
    wait "${pids[0]}" || failed=1
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || failed=1; done

echo "totals over every run recorded in $build/fuzz_runs.csv:"
awk -F, 'NR > 1 { e[$2] += $3; s[$2] += $4 } END { for (h in e) printf "  %-11s %12d executions in %7d s\n", h, e[h], s[h] }' \
  "$build/fuzz_runs.csv" | sort
exit "$failed"
