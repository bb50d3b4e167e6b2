#!/usr/bin/env bash
# Runs the test suite (not `long`, not `fuzz`) under shifted seeds, to find statistical tests
# that pass only by the luck of their fixed seeds (tests/test_seed.h). A sound 4-sigma check
# fails about once in 16 000 seeds; a test that fails on a few of a dozen is not sound.
#
#   tools/seed_sweep.sh [--from K] [--to K] [--build DIR] [ctest arguments...]
#
# Each offset K in [from, to] (default 1..12) is one ctest run with CHLOROVDB_TEST_SEED_OFFSET=K
# (about a minute on 2 cores for the whole suite; narrow it with -R or -L). Prints each offset's
# failures and, last, every test that failed with the offsets it failed on. Exit 1 if any did.
set -euo pipefail
cd "$(dirname "$0")/.."
from=1 to=12 build=build
args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --from) from="$2"; shift ;;
    --to) to="$2"; shift ;;
    --build) build="$2"; shift ;;
    -h|--help) sed -n '2,10p' "$0"; exit 0 ;;
    *) args+=("$1") ;;
  esac
  shift
done
declare -A failed_on=()  # "=()": set, so ${#failed_on[@]} works under set -u when nothing fails
for k in $(seq "$from" "$to"); do
  log="$(CHLOROVDB_TEST_SEED_OFFSET=$k ctest --test-dir "$build" --parallel "$(nproc)" -LE 'long|fuzz|bench' \
           ${args[@]+"${args[@]}"} 2>&1 || true)"
  fails="$(grep -E '^\s+[0-9]+ - .* \(Failed\)' <<<"$log" | sed -E 's/^\s+[0-9]+ - (.*) \(Failed\).*/\1/' || true)"
  echo "offset $k: $(grep -E 'tests passed' <<<"$log" || echo '?')"
  for t in $fails; do
    echo "  failed: $t"
    failed_on[$t]="${failed_on[$t]:-} $k"
  done
done
[[ ${#failed_on[@]} -eq 0 ]] && { echo "no test failed on offsets $from..$to"; exit 0; }
echo "tests that failed, with the offsets they failed on:"
for t in "${!failed_on[@]}"; do echo "  $t:${failed_on[$t]}"; done
exit 1
