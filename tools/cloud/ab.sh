#!/usr/bin/env bash
# Interleaved A/B of several chlorovdb builds on the cloud benchmark (docs/performance.md).
#
#   tools/cloud/ab.sh [--spp N] [--seeds "31 32 33"] [--out DIR] BINARY...
#
# For cloud.json and cloud_tau100.json, renders every seed with every binary in turn (one
# thread, so process CPU time is the render's and load from other jobs hits all builds
# alike), then prints per binary the median CPU time (user + sys, start-up included) and
# the noise MSE from the spread over the seeds (cloud_compare: the first seed's image
# serves as the "reference", the others as renders). Efficiency = 1 / (MSE x CPU time).
# Needs build/tools/cloud/cloud_compare and volumes/bench/cloud64_mirrored.vdb (bench.sh makes it).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
SPP=16
SEEDS="31 32 33"
OUT=/tmp/chlorovdb-ab
while [[ $# -gt 0 && $1 == --* ]]; do
  case "$1" in
    --spp) SPP="$2"; shift 2 ;;
    --seeds) SEEDS="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    *) echo "ab.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
[[ $# -ge 1 ]] || { sed -n '2,11p' "$0"; exit 2; }
COMPARE="$ROOT/build/tools/cloud/cloud_compare"
mkdir -p "$OUT"
for scene in cloud cloud_tau100; do
  for seed in $SEEDS; do
    for k in $(seq 1 $#); do
      bin="${!k}"
      /usr/bin/time -f "%U %S" -o "$OUT/$scene.$k.$seed.time" "$bin" render "$ROOT/scenes/bench/$scene.json" \
        --spp "$SPP" --seed "$seed" --threads 1 -o "$OUT/$scene.$k.$seed.exr" >/dev/null 2>&1
    done
  done
  for k in $(seq 1 $#); do
    cpu=$(cat "$OUT/$scene.$k".*.time | awk '{print $1 + $2}' | sort -n | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}')
    files=()
    for seed in $SEEDS; do files+=("$OUT/$scene.$k.$seed.exr"); done
    mse=$("$COMPARE" "${files[@]}" --ref-noise-mse 0 | awk '/noise_mse_ours/ {print $2}')
    echo "$scene ${!k} cpu_median_s=$cpu noise_mse=$mse"
  done
done
