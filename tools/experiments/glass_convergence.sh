#!/usr/bin/env bash
# Convergence rate and equal-time efficiency of the excitation-through-glass
# strategies (issue 23; docs/fluorescence.md, "Convergence through glass").
#
#   tools/experiments/glass_convergence.sh [SCENE.json]      (default scenes/default.json)
#
# 1. A reference with REF_VARIANT's settings (`chlorovdb reference`, REF_SPP, seed
#    1000003; cached in $OUT and resumed), whose own standard error is reported.
# 2. For every variant and every seed 1..SEEDS: one progressive `chlorovdb converge`
#    over spp 1, 2, 4, ..., SPP_MAX (CPU clock, THREADS threads).
# 3. `chlorovdb_bench slope`: per layer, the relMSE-vs-spp log-log slope fitted per
#    seed on relMSE minus the reference's own share (expected -1; the RMSE slope is
#    half of it, expected -0.5), its mean ± standard error over seeds, the RMSE slope
#    over the last 4 octaves of spp alone (the asymptotic rate, past the spp where a
#    heavy tail's rare paths first appear), and, at SPP_MAX,
#    relMSE × CPU time (lower is better; ratios of it are equal-time efficiency
#    ratios) and the share of the squared error held by the worst 0.1 % of pixels.
# Writes $OUT/<scene>/summary.md. Environment knobs:
#   VARIANTS="label|flags;label|flags"  (default: fresnel, block, connect, all `full`)
#   REF_VARIANT=connect   label whose flags render the reference (it must be unbiased)
#   RESOLUTION=32x24  REF_SPP=65536  SPP_MAX=1024  SEEDS=6  THREADS=1  REF_THREADS=$THREADS
#   OUT=out/glass_convergence  CHLOROVDB, CHLOROVDB_BENCH: the binaries
# Seeds: the fluorescence layer's mean relMSE is heavy-tailed (on default.json a few
# seeds' single samples set it: seeds 1-72 read 0.347, seeds 73-144 0.197, same code),
# so compare two codes over 144 seeds or more, and per seed (runs are cached per seed,
# so raising SEEDS adds only the new ones).
set -euo pipefail
cd "$(dirname "$0")/../.."

scene=${1:-scenes/default.json}
CHLOROVDB=${CHLOROVDB:-build/src/cli/chlorovdb}
CHLOROVDB_BENCH=${CHLOROVDB_BENCH:-build/src/analysis/chlorovdb_bench}
RESOLUTION=${RESOLUTION:-32x24}
REF_SPP=${REF_SPP:-65536}
SPP_MAX=${SPP_MAX:-1024}
SEEDS=${SEEDS:-6}
THREADS=${THREADS:-1}
REF_THREADS=${REF_THREADS:-$THREADS}
OUT=${OUT:-out/glass_convergence}
REF_VARIANT=${REF_VARIANT:-connect}
REF_SEED=1000003  # the variants use seeds 1..SEEDS: reference and estimates share no samples
VARIANTS=${VARIANTS:-"fresnel|--fluorescence full --set render.excitation_through_glass=fresnel;block|--fluorescence full --set render.excitation_through_glass=block;connect|--fluorescence full --set render.excitation_through_glass=connect"}

for tool in "$CHLOROVDB" "$CHLOROVDB_BENCH"; do
  [ -x "$tool" ] || { echo "glass_convergence.sh: $tool not built (cmake --build build --target chlorovdb chlorovdb_bench)" >&2; exit 2; }
done
[ -f "$scene" ] || { echo "glass_convergence.sh: no scene $scene" >&2; exit 2; }
name=$(basename "$scene" .json)
dir="$OUT/$name"
mkdir -p "$dir"
spp=1
for ((n = 2; n <= SPP_MAX; n *= 2)); do spp+=",$n"; done

declare -A flags_of
labels=()
IFS=';' read -r -a specs <<< "$VARIANTS"
for spec in "${specs[@]}"; do
  labels+=("${spec%%|*}")
  flags_of["${spec%%|*}"]="${spec#*|}"
done
[ -n "${flags_of[$REF_VARIANT]+x}" ] || { echo "glass_convergence.sh: REF_VARIANT $REF_VARIANT is not among the variants" >&2; exit 2; }

# Reference: cached, restarted when the scene or its settings change.
ref="$dir/reference.exr"
stamp="$(sha256sum "$scene" | cut -d' ' -f1) $RESOLUTION $REF_SPP ${flags_of[$REF_VARIANT]}"
if [ "$(cat "$dir/reference.stamp" 2>/dev/null)" != "$stamp" ]; then rm -f "$ref" "$ref.ckpt"; fi
eval "flags=(${flags_of[$REF_VARIANT]})"
"$CHLOROVDB" reference "$scene" -o "$ref" --spp "$REF_SPP" --resolution "$RESOLUTION" --seed "$REF_SEED" \
  --threads "$REF_THREADS" --checkpoint-every 60 --resume -q "${flags[@]}" 2> "$dir/reference.log"
# Rewritten only when the settings change: its time marks the runs that are still valid.
[ "$(cat "$dir/reference.stamp" 2>/dev/null)" = "$stamp" ] || echo "$stamp" > "$dir/reference.stamp"
ref_seconds=$(grep -o 'wall_time_s[^0-9]*[0-9.]*' <(oiiotool --info -v "$ref" 2>/dev/null) | grep -o '[0-9.]*$' || echo '?')

for label in "${labels[@]}"; do
  eval "flags=(${flags_of[$label]})"
  for ((seed = 1; seed <= SEEDS; ++seed)); do
    run="$dir/$label-seed$seed"
    run_stamp="$stamp | $spp $THREADS ${flags_of[$label]}"
    # Cached while the reference, the spp list and the flags are unchanged.
    [ "$(cat "$run.stamp" 2>/dev/null)" = "$run_stamp" ] && [ "$run.csv" -nt "$dir/reference.stamp" ] && continue
    "$CHLOROVDB" converge "$scene" --reference "$ref" --resolution "$RESOLUTION" --threads "$THREADS" \
      --seed "$seed" --spp "$spp" --clock cpu --label "$label" "${flags[@]}" -o "$run" > "$run.log" 2>&1
    echo "$run_stamp" > "$run.stamp"
  done
done

{
  printf '## %s\n\n' "$name"
  printf 'Reference: %s spp at %s, seed %s, settings of `%s` (%s), %s s wall on %s thread(s). Its own error:\n\n' \
    "$REF_SPP" "$RESOLUTION" "$REF_SEED" "$REF_VARIANT" "${flags_of[$REF_VARIANT]}" "$ref_seconds" "$REF_THREADS"
  grep '^own error' "$dir/reference.log" | sed 's/^/- /'
  printf '\nVariants: %s seeds each (1..%s), spp 1..%s, %s thread(s), CPU clock.\n' "$SEEDS" "$SEEDS" "$SPP_MAX" "$THREADS"
  for layer in fluorescence total; do
    printf '\n%s layer:\n\n' "$layer"
    files=()
    for label in "${labels[@]}"; do files+=("$dir/$label"-seed*.csv); done
    "$CHLOROVDB_BENCH" slope "${files[@]}" --layer "$layer" --baseline "${labels[0]}"
  done
} > "$dir/summary.md"
cat "$dir/summary.md"
