#!/usr/bin/env bash
# The pbrt-v4 cloud benchmark (issue 9, docs/performance.md).
#
#   tools/cloud/bench.sh [--quick] [--build DIR] [--out DIR] [--threads N] [--seeds "1 2 3"]
#                        [--spp "16 64 256"] [--no-build] [--no-variants] [--chromatic-ref-spp N]
#                        [--chlorovdb BINARY]
#
# Full mode: renders scenes/bench/cloud.json at each spp with each seed (2 threads), and
# prints per spp the median render time, the median RMSE against pbrt-v4's 8192-spp reference
# (all 256x256x3 values), and the efficiency 1/(MSE x time) from those medians, next to
# pbrt-v4's figures. Two times: `wall` is the renderer's own render-loop wall time (EXR
# metadata wall_time_s, the figure the issue asks for); `cpu/T` is the process's user+sys CPU
# time minus start-up (scene load, measured once with a 1-spp 8x8 render) divided by the
# thread count: what the wall time would be on T idle cores. On a shared, loaded machine
# only the second is comparable between runs (and with pbrt-v4's figures, taken unloaded); then the tau~100 variant's cost per sample relative to tau~10, and the
# chromatic variant (no pbrt reference: RMSE against a high-spp self-reference, cached in OUT).
# --quick (< 1 min, what CTest runs): two 16-spp renders; checks that the scene still matches
# the reference (relative difference of the means within 0.5 %, RMSE within 1.1x of the noise
# the two renders measure plus the reference's) and that the image is not mirrored. Exit 1 on
# a mismatch, 77 (skip) when the shared reference is absent.
#
# The .vdb is made here from the shared field: gen_cloud.py (run unmodified with its output
# redirected to OUT, needs /usr/bin/python3 with numpy), else cloud_to_vdb --generate.
set -euo pipefail

# CHLOROVDB_ROOT: the source tree (default: this script's); lets a copy of the script run, so
# editing bench.sh while a benchmark runs cannot change the running instance.
ROOT="${CHLOROVDB_ROOT:-$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)}"
SHARED="${CHLOROVDB_SHARED:-$ROOT/../shared}/bench/cloud"
BUILD="$ROOT/build-bench"
OUT=""
THREADS=2
SEEDS="1 2 3"
SPPS="16 64 256"
QUICK=0
DO_BUILD=1
VARIANTS=1
CHROMA_REF_SPP=1024
CHLOROVDB=""

while [[ $# -gt 0 ]]; do
  case "$1" in
    --quick) QUICK=1 ;;
    --build) BUILD="$2"; shift ;;
    --out) OUT="$2"; shift ;;
    --threads) THREADS="$2"; shift ;;
    --seeds) SEEDS="$2"; shift ;;
    --spp) SPPS="$2"; shift ;;
    --no-build) DO_BUILD=0 ;;
    --no-variants) VARIANTS=0 ;;
    --chromatic-ref-spp) CHROMA_REF_SPP="$2"; shift ;;
    --chlorovdb) CHLOROVDB="$2"; shift ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) echo "bench.sh: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
OUT="${OUT:-$BUILD/cloud}"
mkdir -p "$OUT"
REF="$SHARED/pbrt_grid_tau10_ref8192.exr"
if [[ ! -f "$REF" ]]; then
  echo "bench.sh: no pbrt reference at $REF (set CHLOROVDB_SHARED): skipped" >&2
  exit 77
fi

if [[ $DO_BUILD == 1 ]]; then
  [[ -f "$BUILD/build.ninja" || -f "$BUILD/Makefile" ]] ||
    cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD" --parallel 2 --target chlorovdb cloud_to_vdb cloud_compare >/dev/null
fi
CHLOROVDB="${CHLOROVDB:-$BUILD/src/cli/chlorovdb}"
TO_VDB="$BUILD/tools/cloud/cloud_to_vdb"
COMPARE="$BUILD/tools/cloud/cloud_compare"
for b in "$CHLOROVDB" "$TO_VDB" "$COMPARE"; do
  [[ -x "$b" ]] || { echo "bench.sh: missing $b (build it, or drop --no-build)" >&2; exit 2; }
done

# --- The grid: the shared field, mirrored in x (see scenes/bench/cloud.json). ---
VDB="$ROOT/volumes/bench/cloud64_mirrored.vdb"
RAW="$OUT/field/cloud64_density_f32_xfastest.raw"
mkdir -p "$OUT/field" "$(dirname "$VDB")"
if [[ ! -f "$RAW" ]]; then
  if /usr/bin/python3 -c 'import numpy' 2>/dev/null && [[ -f "$SHARED/gen_cloud.py" ]]; then
    # gen_cloud.py writes beside itself: run it unmodified as if it lived in OUT/field.
    /usr/bin/python3 -c '
import sys, os
src, out = sys.argv[1], os.path.abspath(sys.argv[2])
f = os.path.join(out, "gen_cloud.py")
exec(compile(open(src).read(), f, "exec"), {"__file__": f, "__name__": "__main__"})
' "$SHARED/gen_cloud.py" "$OUT/field" >/dev/null
  else
    echo "bench.sh: no numpy for gen_cloud.py: regenerating the field with cloud_to_vdb --generate" >&2
    "$TO_VDB" --generate "$OUT/field/unused.vdb" --raw-out "$RAW" >/dev/null
  fi
fi
if [[ ! -f "$VDB" || "$RAW" -nt "$VDB" || "$TO_VDB" -nt "$VDB" ]]; then
  "$TO_VDB" "$RAW" "$VDB" --mirror-x >/dev/null
fi

# key VALUE from cloud_compare's output
get() { awk -v k="$1" '$1 == k { print $2 }' <<<"$2"; }
# The last render's CPU time without start-up, per thread: its wall time on idle cores.
cpu_per_thread() { awk -v c="$CPU_S" -v s="$STARTUP" -v n="$THREADS" 'BEGIN { print (c - s) / n }'; }
median() { tr ' ' '\n' <<<"$*" | grep -v '^$' | sort -g | awk '{ a[NR] = $1 } END { print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2 }'; }

# render SCENE SPP SEED OUTFILE [extra options]: sets CPU_S to the process's user+sys seconds.
render() {
  local scene="$1" spp="$2" seed="$3" out="$4" t
  shift 4
  t="$( { TIMEFORMAT='%U %S'; time "$CHLOROVDB" render "$scene" -o "$out" --spp "$spp" --seed "$seed" \
            --threads "$THREADS" -q "$@" >/dev/null 2>&1; } 2>&1 )"
  CPU_S="$(awk '{ print $1 + $2 }' <<<"$t")"
}

if [[ $QUICK == 1 ]]; then
  render "$ROOT/scenes/bench/cloud.json" 16 101 "$OUT/quick_a.exr"
  render "$ROOT/scenes/bench/cloud.json" 16 102 "$OUT/quick_b.exr"
  render "$ROOT/scenes/bench/cloud_furnace.json" 32 103 "$OUT/quick_furnace.exr" --resolution 64x64
  F="$("$COMPARE" --furnace 0.30157,0.23736,0.22770 "$OUT/quick_furnace.exr")"
  R="$("$COMPARE" "$REF" "$OUT/quick_a.exr" "$OUT/quick_b.exr")"
  echo "$R"
  echo "$F"
  # At 2 x 16 spp the image mean's noise is ~0.03 %, so 0.5 % is ~15 sigma; the RMSE bound
  # catches local bias that cancels in the mean (noise_mse_ours is measured from the two renders).
  awk -v rel="$(get rel_diff_means "$R")" -v rmse="$(get rmse "$R")" -v exp_="$(get expected_rmse "$R")" \
      -v mir="$(get rmse_mirrored "$R")" -v ex="$(get excess_mse "$R")" -v exs="$(get excess_mse_sigma "$R")" \
      -v fc="$(get furnace_centre "$F")" -v fs="$(get furnace_centre_sigma "$F")" 'BEGIN {
    ok = 1
    d = fc - 1; if (d < 0) d = -d
    if (d > 4 * fs + 0.005) { print "FAIL: the white furnace is off by " (fc - 1) * 100 " % in the centre"; ok = 0 }
    if (rel < -0.005 || rel > 0.005) { print "FAIL: the mean differs from pbrt-v4 by " rel * 100 " %"; ok = 0 }
    if (rmse > 1.1 * exp_) { print "FAIL: RMSE " rmse " > 1.1 x the noise-only " exp_; ok = 0 }
    if (ex > 4 * exs) { print "FAIL: MSE exceeds the noise by " ex " (> 4 sigma = " 4 * exs ")"; ok = 0 }
    if (!(rmse < mir)) { print "FAIL: the mirrored image matches better (orientation)"; ok = 0 }
    if (ok) print "OK: 2 x 16 spp match pbrt-v4 within noise, and the white furnace holds"
    exit ok ? 0 : 1 }'
  exit $?
fi

render "$ROOT/scenes/bench/cloud.json" 1 0 "$OUT/startup.exr" --resolution 8x8
STARTUP="$CPU_S"
echo "# cloud benchmark: $THREADS threads, seeds {$SEEDS}, medians; $(date -u +%FT%TZ); $CHLOROVDB"
if [[ "$CHLOROVDB" == "$BUILD/src/cli/chlorovdb" ]]; then
  echo "# source: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?')$(git -C "$ROOT" diff --quiet HEAD -- src 2>/dev/null || echo ' + uncommitted src/ changes')"
else
  echo "# source: whatever built $CHLOROVDB (given with --chlorovdb)"
fi
echo "# load average before: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores; start-up CPU ${STARTUP} s (subtracted from cpu)"
printf '%-5s %8s %8s %8s %10s %10s | %s\n' spp wall_s cpu/T_s rmse eff_wall eff_cpu 'pbrt-v4: time rmse efficiency'
declare -A PBRT=([16]="2.10 0.0531" [64]="8.20 0.0266" [256]="32.9 0.01349")
for spp in $SPPS; do
  times="" cpus="" rmses=""
  for seed in $SEEDS; do
    f="$OUT/cloud_${spp}spp_seed${seed}.exr"
    render "$ROOT/scenes/bench/cloud.json" "$spp" "$seed" "$f"
    R="$("$COMPARE" "$REF" "$f")"
    times+=" $(get time_s "$R")"
    cpus+=" $(cpu_per_thread)"
    rmses+=" $(get rmse "$R")"
  done
  t="$(median $times)"; c="$(median $cpus)"; r="$(median $rmses)"
  p="${PBRT[$spp]:-}"
  awk -v spp="$spp" -v t="$t" -v c="$c" -v r="$r" -v p="$p" 'BEGIN {
    split(p, q, " "); pe = (q[1] > 0) ? sprintf("%.2f %.4f %.0f/s", q[1], q[2], 1 / (q[2] * q[2] * q[1])) : "-"
    printf "%-5s %8.2f %8.2f %8.4f %8.0f/s %8.0f/s | %s\n", spp, t, c, r, 1 / (r * r * t), 1 / (r * r * c), pe }'
done
echo "# load average after: $(cut -d' ' -f1-3 /proc/loadavg); target: >= 330/s (2x pbrt-v4's 165/s)"

[[ $VARIANTS == 1 ]] || exit 0

# --- tau ~ 100: cost per sample relative to tau ~ 10 (pbrt-v4: 1.3-1.5x). ---
# The two scenes alternate, seed by seed, so a burst of load from elsewhere hits both
# (reusing the tau~10 rows above once gave 1.47x where interleaved runs give 1.7x).
spp100="$(awk '{ print $NF }' <<<"$SPPS")"
[[ "$spp100" -gt 64 ]] && spp100=64
cpus10="" cpus100="" walls10="" walls100=""
for seed in $SEEDS; do
  f="$OUT/cloud_${spp100}spp_seed${seed}_pair.exr"
  render "$ROOT/scenes/bench/cloud.json" "$spp100" "$seed" "$f"
  cpus10+=" $(cpu_per_thread)"
  walls10+=" $(get time_s "$("$COMPARE" "$REF" "$f")")"
  f="$OUT/cloud_tau100_${spp100}spp_seed${seed}.exr"
  render "$ROOT/scenes/bench/cloud_tau100.json" "$spp100" "$seed" "$f"
  cpus100+=" $(cpu_per_thread)"
  walls100+=" $(get time_s "$("$COMPARE" "$f" "$f")")"
done
# Also the added cost per sample in seconds, against what 1.3-1.5x adds to pbrt-v4's cost
# per sample at tau~10 (its 256-spp row): a ratio alone rewards a slow tau~10
# (docs/performance.md, session 8, "Reading the bound").
awk -v a="$(median $cpus100)" -v b="$(median $cpus10)" -v c="$(median $walls100)" -v d="$(median $walls10)" -v s="$spp100" \
    -v p="${PBRT[256]}" 'BEGIN {
  printf "tau~100 at %d spp (interleaved with tau~10): cpu/T %.2f s vs %.2f s: %.2fx; wall %.2f s vs %.2f s: %.2fx the cost per sample (pbrt-v4: 1.3-1.5x)\n", s, a, b, a / b, c, d, c / d
  split(p, q, " "); per_sample = q[1] / 256
  printf "tau~100 adds per sample: cpu/T +%.4f s, wall +%.4f s (pbrt-v4: +%.3f to +%.3f s)\n", (a - b) / s, (c - d) / s, 0.3 * per_sample, 0.5 * per_sample }'

# --- Chromatic variant: sigma_a steep in wavelength; self-reference. ---
CREF="$OUT/cloud_chromatic_ref${CHROMA_REF_SPP}.exr"
if [[ ! -f "$CREF" ]]; then
  echo "# chromatic self-reference: $CHROMA_REF_SPP spp (once, cached in $CREF)"
  render "$ROOT/scenes/bench/cloud_chromatic.json" "$CHROMA_REF_SPP" 9999 "$CREF"
fi
echo "# chromatic variant vs its own ${CHROMA_REF_SPP}-spp reference; eff_cpu* removes that reference's"
echo "# noise, estimated as the first row's MSE x its spp / ${CHROMA_REF_SPP}"
printf '%-5s %8s %8s %8s %10s %10s %10s\n' spp wall_s cpu/T_s rmse eff_wall eff_cpu 'eff_cpu*'
REFNOISE=""
for spp in $SPPS; do
  times="" cpus="" rmses=""
  for seed in $SEEDS; do
    f="$OUT/cloud_chromatic_${spp}spp_seed${seed}.exr"
    render "$ROOT/scenes/bench/cloud_chromatic.json" "$spp" "$seed" "$f"
    R="$("$COMPARE" "$CREF" "$f" --ref-noise-mse 0)"
    times+=" $(get time_s "$R")"
    cpus+=" $(cpu_per_thread)"
    rmses+=" $(get rmse "$R")"
  done
  r="$(median $rmses)"
  [[ -n "$REFNOISE" ]] || REFNOISE="$(awk -v r="$r" -v s="$spp" -v n="$CHROMA_REF_SPP" 'BEGIN { print r * r * s / n }')"
  awk -v spp="$spp" -v t="$(median $times)" -v c="$(median $cpus)" -v r="$r" -v z="$REFNOISE" 'BEGIN {
    m = r * r - z; e = (m > 0) ? sprintf("%8.0f/s", 1 / (m * c)) : "       -"
    printf "%-5s %8.2f %8.2f %8.4f %8.0f/s %8.0f/s %s\n", spp, t, c, r, 1 / (r * r * t), 1 / (r * r * c), e }'
done
