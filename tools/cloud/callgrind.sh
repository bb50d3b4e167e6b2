#!/usr/bin/env bash
# Render-loop instruction counts of the cloud benchmark (issue 9, docs/performance.md): callgrind
# runs of a 64x64, 16-spp, one-thread render of tau~10 and tau~100, each minus the same binary's
# 1x1, 1-spp start-up. Instruction counts do not drift with the machine's load, so they compare
# builds where wall time cannot; a change of the random-number stream moves them by about 1 %.
#
#   tools/cloud/callgrind.sh [BINARY] [--seed N] [--keep DIR]
#
# Needs valgrind (apt-get install valgrind) and the benchmark's grid (tools/cloud/bench.sh --quick
# writes it). Valgrind 3.19 (Debian 12) cannot decode rdtscp, which libhwy (an OpenImageIO
# dependency, via JPEG XL) runs in a static initialiser on AMD hosts: the render dies with
# SIGILL before main. A preloaded stand-in for that one timer function, built here, avoids it;
# nothing the renderer does calls it.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BIN="$ROOT/build/src/cli/chlorovdb"
SEED=7
KEEP=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seed) SEED="$2"; shift ;;
    --keep) KEEP="$2"; shift ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    *) BIN="$1" ;;
  esac
  shift
done
command -v valgrind >/dev/null || { echo "callgrind.sh: needs valgrind (apt-get install valgrind)" >&2; exit 2; }
[[ -x "$BIN" ]] || { echo "callgrind.sh: no binary $BIN" >&2; exit 2; }
[[ -f "$ROOT/volumes/bench/cloud64_mirrored.vdb" ]] ||
  { echo "callgrind.sh: no cloud grid: run tools/cloud/bench.sh --quick first" >&2; exit 2; }
WORK="${KEEP:-$(mktemp -d)}"
mkdir -p "$WORK"
[[ -n "$KEEP" ]] || trap 'rm -rf "$WORK"' EXIT

echo 'namespace hwy { namespace platform { double TimerResolution() { return 1e-9; } } }' >"$WORK/hwy_timer.cpp"
c++ -O2 -shared -fPIC "$WORK/hwy_timer.cpp" -o "$WORK/hwy_timer.so"

# instructions NAME SCENE SPP RESOLUTION: prints the run's total instruction count
instructions() {
  LD_PRELOAD="$WORK/hwy_timer.so" valgrind --tool=callgrind --callgrind-out-file="$WORK/$1.callgrind" \
    "$BIN" render "$ROOT/scenes/bench/$2" -o "$WORK/$1.exr" --spp "$3" --seed "$SEED" --threads 1 \
    --resolution "$4" -q >/dev/null 2>"$WORK/$1.log"
  local n
  n="$(grep -o 'refs: *[0-9,]*' "$WORK/$1.log" | tr -dc 0-9)"
  [[ -n "$n" ]] || { echo "callgrind.sh: $1 failed, see $WORK/$1.log" >&2; exit 1; }
  echo "$n"
}
s10="$(instructions startup10 cloud.json 1 1x1)"
s100="$(instructions startup100 cloud_tau100.json 1 1x1)"
r10="$(instructions tau10 cloud.json 16 64x64)"
r100="$(instructions tau100 cloud_tau100.json 16 64x64)"
awk -v a="$r10" -v b="$s10" -v c="$r100" -v d="$s100" 'BEGIN {
  x = (a - b) / 1e6; y = (c - d) / 1e6
  printf "render-loop instructions, 64x64 x 16 spp, 1 thread: tau~10 %.0f M, tau~100 %.0f M, ratio %.3f\n", x, y, y / x }'
[[ -z "$KEEP" ]] || echo "callgrind profiles in $WORK (callgrind_annotate $WORK/tau100.callgrind)"
