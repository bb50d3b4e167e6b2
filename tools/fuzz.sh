#!/usr/bin/env bash
# Fuzz the scene loader, the spectrum CSV reader and the mesh / height-field
# loaders with voxelize behind them, with libFuzzer.
#
#   tools/fuzz.sh [--seconds N] [--target scene|csv|mesh|all] [--jobs J] [--keep-going] [--build-dir DIR] [--no-build]
#
# Configures a clang build with ASan + UBSan and -DCHLOROVDB_FUZZ=ON in DIR
# (default build-fuzz), builds only the fuzz targets, then runs each target for
# N seconds (default 60) from the seed corpora (fuzz/seeds/<target>, the earlier
# findings in fuzz/crashes/<target>, plus scenes/*.json for the scene target).
# New interesting inputs accumulate in DIR/fuzz/corpus/<target> and survive
# between runs. A crash, sanitizer report, unexpected exception or hang (> 10 s
# on one input) stops the target; its input is copied to fuzz/crashes/<target>/
# and the script exits non-zero.
# With --jobs J > 1 or --keep-going, libFuzzer's fork mode runs J workers (default 1)
# and keeps going past findings (each lands in the artifacts folder and fuzz/crashes/<target>/).
# The build folder is configured as `tools/sanitize.sh --fuzz` configures it, so
# either script can reuse the other's build.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=60
target=all
jobs=1
build_dir=build-fuzz
build=1
keep_going=0
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds=$2; shift 2 ;;
    --target) target=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --build-dir) build_dir=$2; shift 2 ;;
    --no-build) build=0; shift ;;
    --keep-going) keep_going=1; shift ;;
    -h|--help) sed -n '2,19p' "$0"; exit 0 ;;
    *) echo "fuzz.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done
case "$target" in
  all) targets=(scene csv mesh) ;;
  scene|csv|mesh) targets=("$target") ;;
  *) echo "fuzz.sh: --target must be scene, csv, mesh or all" >&2; exit 2 ;;
esac

cxx=$(command -v clang++ || command -v clang++-14 || true)
if [ -z "$cxx" ]; then
  echo "fuzz.sh: clang++ not found: apt-get install --no-install-recommends clang libclang-rt-dev" >&2
  exit 1
fi

if [ "$build" = 1 ]; then
  cmake -S . -B "$build_dir" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
    -DCHLOROVDB_SANITIZE=ON -DCHLOROVDB_FUZZ=ON -DCHLOROVDB_BUILD_TESTS=ON -DCHLOROVDB_BUILD_BENCHMARKS=OFF >/dev/null
  cmake --build "$build_dir" --parallel "$(nproc 2>/dev/null || echo 2)" --target "${targets[@]/#/fuzz_}"
fi

export CHLOROVDB_SPECTRA="$PWD/spectra"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1:suppressions=$PWD/fuzz/ubsan.supp}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan.supp}"
status=0
for t in "${targets[@]}"; do
  corpus="$build_dir/fuzz/corpus/$t"
  artifacts="$build_dir/fuzz/artifacts/$t/"
  mkdir -p "$corpus" "$artifacts" "fuzz/crashes/$t"
  seeds=("fuzz/seeds/$t" "fuzz/crashes/$t")
  [ "$t" = scene ] && seeds+=(scenes)
  fork=()
  if [ "$jobs" -gt 1 ] || [ "$keep_going" = 1 ]; then
    fork=(-fork="$jobs" -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1)
  fi
  echo "== fuzz_$t: ${seconds} s, corpus $corpus"
  before=$(ls "$artifacts" | wc -l)
  if ! "$build_dir/fuzz/fuzz_$t" -seed=1 -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
        -max_len=8192 -dict="fuzz/$t.dict" -artifact_prefix="$artifacts" -print_final_stats=1 "${fork[@]}" \
        "$corpus" "${seeds[@]}" 2> "$build_dir/fuzz/$t.log"; then
    status=1
  fi
  tail -n 12 "$build_dir/fuzz/$t.log"
  for f in "$artifacts"*; do
    [ -e "$f" ] || continue
    cp -n "$f" "fuzz/crashes/$t/$(basename "$f")"
  done
  after=$(ls "$artifacts" | wc -l)
  if [ "$after" -gt "$before" ]; then
    status=1
    echo "fuzz_$t: $((after - before)) new finding(s), copied to fuzz/crashes/$t/ (full log: $build_dir/fuzz/$t.log)"
  fi
done
exit $status
