#!/usr/bin/env bash
# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer (issue 7).
#
#   tools/sanitize.sh [--fuzz] [--build-dir DIR] [--jobs J] [--no-build] [ctest arguments...]
#
# Configures DIR with -DCHLOROVDB_SANITIZE=ON (tests on, benchmarks off, line
# tables so reports name file:line), builds it, and runs every test not labelled
# `long` but seven statistical ones (HEAVY_STATISTICAL below: their sample counts,
# not their code paths, make them slow; lighter tests run the same code under the
# sanitizers and the Release suite runs them in full). Any sanitizer report fails the run: each test aborts at
# its first report (halt_on_error), and every report, from test binaries and the
# child processes they start alike, is also written to DIR/sanitizer-reports/,
# so one in a process whose failure a test expected still fails the script.
# The script ends with the failing tests and the reports, and exits non-zero if
# there was either.
#
# Default: the system compiler (GCC), -O2 -g1, DIR = build-asan.
# --fuzz: clang with the libFuzzer targets too (-DCHLOROVDB_FUZZ=ON), -O1
#   -gline-tables-only, DIR = build-fuzz (the same configuration as tools/fuzz.sh,
#   so one build serves both); the tests then include the CI-sized fuzz runs
#   (label `fuzz`: the regression inputs of fuzz/crashes/ and a few seconds of
#   fuzzing per target). This is what CI runs (.ci/run).
# Extra arguments go to ctest, e.g. `tools/sanitize.sh -R Stress`.
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=
jobs=$(nproc 2>/dev/null || echo 2)
build=1
fuzz=0
ctest_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --fuzz) fuzz=1; shift ;;
    --build-dir) build_dir=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --no-build) build=0; shift ;;
    -h|--help) sed -n '2,23p' "$0"; exit 0 ;;
    *) ctest_args+=("$1"); shift ;;
  esac
done

config=(-G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCHLOROVDB_SANITIZE=ON
        -DCHLOROVDB_BUILD_TESTS=ON -DCHLOROVDB_BUILD_BENCHMARKS=OFF)
if [ "$fuzz" = 1 ]; then
  build_dir=${build_dir:-build-fuzz}
  cxx=$(command -v clang++ || command -v clang++-14 || true)
  if [ -z "$cxx" ]; then
    echo "sanitize.sh: --fuzz needs clang++: apt-get install --no-install-recommends clang libclang-rt-dev" >&2
    exit 1
  fi
  # Keep in step with tools/fuzz.sh, which builds the fuzz targets in the same folder.
  config+=(-DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" -DCHLOROVDB_FUZZ=ON)
else
  build_dir=${build_dir:-build-asan}
  config+=(-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1")
fi

t0=$(date +%s)
if [ "$build" = 1 ]; then
  cmake -S . -B "$build_dir" "${config[@]}" >/dev/null
  cmake --build "$build_dir" --parallel "$jobs"
fi
t1=$(date +%s)

reports_dir="$PWD/$build_dir/sanitizer-reports"
rm -rf "$reports_dir"
mkdir -p "$reports_dir"
# Both runtimes write their reports to $reports_dir/report.<pid> (ASan and UBSan
# share log_path in a combined build; give both the same one).
# detect_leaks: LeakSanitizer runs at exit of every test binary.
# halt_on_error: the first UBSan report aborts (UBSan checks are recoverable by default).
# The fuzz tests set their own options (fuzz/CMakeLists.txt) and fail by exit status.
log_path="log_path=$reports_dir/report"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1}:$log_path"
# Third-party suppressions (each with its upstream issue) live in fuzz/ubsan.supp.
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1:suppressions=$PWD/fuzz/ubsan.supp}:$log_path"
log="$build_dir/sanitize.log"
# About 640 of the suite's test-seconds under ASan on a 2-core machine (docs/robustness.md).
HEAVY_STATISTICAL='^(ReferenceConvergence\.OwnRelMseAgainstANoisyReferenceMatchesTheErrorAgainstTheExactImage|GlassExcitation\.FullThroughIndexMatchedGlassAgreesWithDirect|Transmittance\.TrackingIsUnbiasedInPiecewiseLinearFields|StoppingRule\.AchievedErrorIsWithinTheTarget|SpecularConnection\.PartitionCountsMirroredPathsOnce|BounceConnection\.AreaLightsFloorLightIsCountedOnceWithLessNoise|BounceConnection\.FarFloorLightIsCountedOnceWithLessNoise)$'
set +e
ctest --test-dir "$build_dir" --output-on-failure --parallel "$jobs" -LE long -E "$HEAVY_STATISTICAL" "${ctest_args[@]}" 2>&1 |
  tee "$log"
status=${PIPESTATUS[0]}
set -e
t2=$(date +%s)

echo
echo "== tools/sanitize.sh summary"
grep -E "tests passed|tests failed|Total Test time" "$log" || true
if [ "$status" -ne 0 ]; then
  echo "-- failing tests:"
  sed -n '/The following tests FAILED/,$p' "$log" | tail -n +2
  # A fuzz test's report sits in the middle of its long output, the part a CI log
  # drops: repeat the first report and the reproducer here, at the end.
  if grep -qE "ERROR: libFuzzer|ERROR: [A-Za-z]+Sanitizer|runtime error:" "$log"; then
    echo "-- first report in the failing output:"
    sed -n -E '/ERROR: libFuzzer|ERROR: [A-Za-z]+Sanitizer|runtime error:/,/^SUMMARY:/p' "$log" | head -n 50
    grep -E "^reproducer |^Base64: " -A1 "$log" | cut -c1-2100 | head -n 8 || true
  fi
fi
shopt -s nullglob
reports=("$reports_dir"/report.*)
if [ ${#reports[@]} -gt 0 ]; then
  status=1
  echo "-- ${#reports[@]} sanitizer report(s) in $reports_dir (distinct first lines, then each report):"
  grep -hE "ERROR: [A-Za-z]+Sanitizer|runtime error:" "${reports[@]}" | sed -E 's/^==[0-9]+==//' | sort | uniq -c || true
  for r in "${reports[@]}"; do
    echo "---- $r"
    head -n 60 "$r"
  done
fi
echo "-- build $((t1 - t0)) s, tests $((t2 - t1)) s (log: $log)"
exit "$status"
