#!/usr/bin/env bash
# The benchmark suite: regenerates docs/benchmarks.md and docs/benchmarks/*.svg.
#
#   cmake --build build --target benchmarks        (or: tools/benchmarks/run.sh)
#
# For every scene in scenes/*.json (or $SCENES):
#  1. a reference (`chlorovdb reference`, seed 1000003, cached and resumed in $OUT) of
#     REF_SPP samples per pixel;
#  2. a pilot: every variant for BUDGET/8 CPU seconds against it; `chlorovdb_bench
#     reference-check` predicts each variant's own relMSE at BUDGET (∝ 1/time) and the
#     spp at which the reference's own relMSE term (from its standard-error layers) is at
#     most 10 % of the best variant's, on the total and fluorescence layers
#     (analysis/reference_convergence.h); the reference is extended (--resume) to that,
#     at most REF_SPP_MAX;
#  3. every estimator variant at EQUAL TIME (`chlorovdb converge --time-budgets`), scored
#     by efficiency = 1 / (own relMSE x CPU time), own relMSE = relMSE minus the
#     reference's own term; rows where relMSE does not measure the variant (the
#     reference's share over 10 %, or the worst 0.1 % of pixels holding over 20 % of it)
#     are marked ⚠; reference-check states, per layer, whether the reference met the
#     criterion against the variants as measured;
# then the cost-growth study (chlorovdb_bench cost-growth). Environment knobs:
#   BUDGET=3         CPU seconds of rendering per variant (also measured at 1/8, 1/4, 1/2 of it);
#                    CPU time (summed over threads), not wall time, so other load on a shared
#                    machine does not skew the comparison
#   REF_SPP=2048     samples per pixel each reference starts with (and the pilot is scored on)
#   REF_SPP_MAX=8192  cap of a reference's samples per pixel: what bounds a run (at 96x72 the
#                    default scene costs about 11 CPU-ms per spp, so a reference at the cap
#                    about 90 CPU-s, 45 s on 2 threads); a reference that reaches it without
#                    meeting the criterion is reported as not converged
#   RESOLUTION=96x72  image size of references and variants
#   THREADS=1        worker threads of the timed variants (one: no idle-thread spinning in the CPU time)
#   REF_THREADS=2    worker threads of the references
#   SCENES="scenes/a.json scenes/b.json"   scenes to run (default: scenes/*.json)
#   OUT=out/benchmarks  references and CSVs (not committed)
#   DOC=docs/benchmarks.md  the page written; its figures go to ${DOC%.md}/
#   COST_GROWTH=1    0 skips the cost-growth study; LARGE=1 adds its 512^3 grids
set -euo pipefail
cd "$(dirname "$0")/../.."

CHLOROVDB=${CHLOROVDB:-build/src/cli/chlorovdb}
CHLOROVDB_BENCH=${CHLOROVDB_BENCH:-build/src/analysis/chlorovdb_bench}
BUDGET=${BUDGET:-3}
REF_SPP=${REF_SPP:-2048}
REF_SPP_MAX=${REF_SPP_MAX:-8192}
RESOLUTION=${RESOLUTION:-96x72}
THREADS=${THREADS:-1}
REF_THREADS=${REF_THREADS:-2}
OUT=${OUT:-out/benchmarks}
COST_GROWTH=${COST_GROWTH:-1}
LARGE=${LARGE:-0}
REF_SEED=1000003  # the variants use seed 0: reference and estimate must not share samples
DOC=${DOC:-docs/benchmarks.md}
FIG=${DOC%.md}
FIG_LINK=$(basename "$FIG")  # figures are linked relative to the page
read -r -a scenes <<< "${SCENES:-$(ls scenes/*.json 2>/dev/null | tr '\n' ' ')}"

for tool in "$CHLOROVDB" "$CHLOROVDB_BENCH"; do
  [ -x "$tool" ] || { echo "run.sh: $tool not built (cmake --build build --target chlorovdb chlorovdb_bench)" >&2; exit 2; }
done
mkdir -p "$OUT" "$FIG"
budgets=$(awk -v b="$BUDGET" 'BEGIN { printf "%g,%g,%g,%g", b / 8, b / 4, b / 2, b }')
pilot_budget=${budgets%%,*}
started=$(date +%s)

# variant label | extra flags. The baseline ("default") is the scene's own settings.
variants_for() {  # $1 scene file
  echo "default|"
  echo "transmittance=delta|--transmittance delta"
  echo "transmittance=ratio|--transmittance ratio"
  echo "transmittance=residual_ratio|--transmittance residual_ratio"
  if grep -Eq '"quantum_yield"[[:space:]]*:[[:space:]]*(0*\.[0-9]*[1-9]|[1-9])' "$1"; then
    echo "fluorescence=reference|--fluorescence reference"
    echo "fluorescence=direct|--fluorescence direct"
    echo "fluorescence=full|--fluorescence full"
    # Switches kept to measure two defaults (docs/fluorescence.md): the excitation
    # wavelength uniform over the excitation band instead of importance-sampled,
    # and the quantum yield as a roulette instead of a weight.
    echo "excitation=uniform|--set render.excitation_sampling=uniform"
    echo "Q=roulette|--set render.quantum_yield_mode=roulette"
    # Excitation from a photon grid traced before the first pass (consistent, biased
    # by its cells) instead of excitation rays; and, behind glass, the two older ways
    # for excitation rays to meet it (docs/fluorescence.md).
    echo "excitation_estimate=photons|--set render.excitation_estimate=photons"
    if grep -q '"dielectric"' "$1"; then
      echo "excitation_through_glass=block|--set render.excitation_through_glass=block"
      echo "excitation_through_glass=fresnel|--set render.excitation_through_glass=fresnel"
      # Photons with camera connections to area lights through glass: the pair that
      # gives both layers the Monte Carlo rate on the glass scenes (docs/fluorescence.md).
      echo "excitation_estimate=photons+direct=all|--set render.excitation_estimate=photons --set render.direct_light_through_glass=all"
      # The bounce connection (light a point, spot or area lamp sends off lit
      # surfaces into the glass) off, to measure what it buys.
      if grep -Eq '"type"[[:space:]]*:[[:space:]]*"(point|spot)"|"emission"[[:space:]]*:[[:space:]]*\{' "$1"; then
        echo "excitation_bounce=false|--set render.excitation_bounce=false"
      fi
    fi
  fi
  # Camera next-event estimation through glass to area lights too (not only delta lights).
  if grep -q '"dielectric"' "$1"; then
    echo "direct_light_through_glass=all|--set render.direct_light_through_glass=all"
  fi
  for n in 1 2 4 8 16; do echo "wavelengths=$n|--wavelengths $n"; done
  echo "camera_wavelengths=visible|--set render.camera_wavelengths=visible"
  echo "skips=off|--set render.skip_unneeded_work=false"
}


tables=""
uvb_lines=""
reference_rows=""
for scene in "${scenes[@]}"; do
  name=$(basename "$scene" .json)
  dir="$OUT/$name"
  mkdir -p "$dir"
  echo "== $name" >&2

  # Reference: cached across runs (its spp in reference.spp), restarted when the scene
  # or the settings change, extended (--resume) when a run needs more samples.
  ref="$dir/reference.exr"
  stamp="$(sha256sum "$scene" | cut -d' ' -f1) $RESOLUTION $REF_SEED"
  if [ "$(cat "$dir/reference.stamp" 2>/dev/null)" != "$stamp" ]; then rm -f "$ref" "$ref.ckpt" "$dir/reference.spp"; fi
  render_reference() {  # $1 spp
    "$CHLOROVDB" reference "$scene" -o "$ref" --spp "$1" --resolution "$RESOLUTION" \
      --seed "$REF_SEED" --threads "$REF_THREADS" --checkpoint-every 30 --resume -q 2>> "$dir/reference.log"
    echo "$stamp" > "$dir/reference.stamp"
    echo "$1" > "$dir/reference.spp"
  }
  ref_spp=$(cat "$dir/reference.spp" 2>/dev/null || echo 0)
  [ "$ref_spp" -ge "$REF_SPP" ] || { ref_spp=$REF_SPP; render_reference "$ref_spp"; }

  converge_variants() {  # $1 folder, $2 budgets; fills csvs, notes
    csvs=()
    notes=""
    mkdir -p "$1"
    while IFS='|' read -r label flags; do
      csv="$1/${label//[=]/-}"
      # shellcheck disable=SC2086
      if "$CHLOROVDB" converge "$scene" --reference "$ref" --resolution "$RESOLUTION" \
           --threads "$THREADS" --spp 1 --clock cpu --time-budgets "$2" --label "$label" $flags -o "$csv" \
           > "$csv.log" 2>&1; then
        csvs+=("$csv.csv")
      else
        notes+="| $label | $(grep -m1 'error' "$csv.log" | sed 's/|/\\|/g') |"$'\n'
      fi
    done < <(variants_for "$scene")
  }
  # Pilot at BUDGET/8: how many samples the reference needs (the largest over the layers).
  converge_variants "$dir/pilot" "$pilot_budget"
  if [ ${#csvs[@]} -gt 0 ]; then
    needed=$("$CHLOROVDB_BENCH" reference-check "${csvs[@]}" --reference "$ref" --budget "$BUDGET" --max-spp "$REF_SPP_MAX" |
      awk -v n="$ref_spp" '$8 > n { n = $8 } END { print n }')
    if [ "$needed" -gt "$ref_spp" ]; then
      echo "   reference: $ref_spp -> $needed spp" >&2
      ref_spp=$needed
      render_reference "$ref_spp"
    fi
  fi
  converge_variants "$dir" "$budgets"

  # The criterion against the variants as measured at BUDGET, per layer (reference-check's fields).
  ref_lines=""
  [ ${#csvs[@]} -eq 0 ] || ref_lines=$("$CHLOROVDB_BENCH" reference-check "${csvs[@]}" --reference "$ref")
  while read -r layer spp ref_rel rms_rel best_label best_own share _ met; do
    [ -n "$layer" ] || continue
    reference_rows+=$(awk -v sc="$name" -v l="$layer" -v spp="$spp" -v rr="$ref_rel" -v rs="$rms_rel" -v b="$best_label" \
      -v bo="$best_own" -v sh="$share" -v m="$met" -v cap="$REF_SPP_MAX" 'BEGIN {
        verdict = m == "yes" ? "yes" : (spp + 0 >= cap + 0 ? "**no** (at the cap) ⚠" : "**no** ⚠")
        printf "| %s | %s | %d | %.2g %% | %.3e | %s (%.3e) | %s | %s |\n", sc, l, spp, 100 * rs, rr, b, bo,
               sh == "inf" ? "≥ 100 %" : sprintf("%.1f %%", 100 * sh), verdict }')$'\n'
  done <<< "$ref_lines"

  group() {  # $1 title, $2 regex on labels, $3 figure name, $4 layers (first one plotted)
    local files=() layer
    for f in "${csvs[@]}"; do
      l=$(basename "$f" .csv)
      [[ "$l" == default || "$l" =~ $2 ]] && files+=("$f")
    done
    [ ${#files[@]} -gt 1 ] || return 0
    read -r -a layers <<< "${4:-total}"
    "$CHLOROVDB_BENCH" plot "${files[@]}" --layer "${layers[0]}" --title "$name, $1" \
      --time-label "render CPU time (s)" -o "$FIG/$name-$3.svg"
    printf '\n**%s** ([plot](benchmarks/%s-%s.svg))\n' "$1" "$name" "$3"
    for layer in "${layers[@]}"; do
      printf '\n%s layer:\n\n' "$layer"
      "$CHLOROVDB_BENCH" table "${files[@]}" --layer "$layer" --baseline default
    done
  }
  section=$(
    printf '\n### %s\n\n' "$name"
    printf 'Reference: %s spp at %s (seed %s); its own error and whether it met the criterion: [References](#references).\n' \
      "$ref_spp" "$RESOLUTION" "$REF_SEED"
    printf 'Equal time: %s s per variant (also measured at %s s).\n' "$BUDGET" "$budgets"
    group "transmittance estimator (shadow and excitation rays)" '^transmittance' transmittance
    group "fluorescence estimator" '^(fluorescence|excitation|Q)' fluorescence "fluorescence total"
    group "camera paths through glass to area lights" '^direct_light' direct_light "total fluorescence"
    group "wavelengths per path" '^wavelengths' wavelengths
    group "camera wavelengths: the scene's mixture (default) or the eye's density" '^camera_wavelengths' camera_wavelengths "total fluorescence"
    group "skipping unneeded work" '^skips' skips
    [ -z "$notes" ] || printf '\nNot run:\n\n| variant | why |\n| --- | --- |\n%s' "$notes"
  )
  tables+="$section"$'\n'

  # Closing note: on scenes lit by a UVB lamp, our best fluorescence estimator against the thesis's.
  if grep -q '"UVB' "$scene" && [ -f "$dir/fluorescence-reference.csv" ]; then
    fl=("$dir"/fluorescence-*.csv "$dir/default.csv")
    read -r best gain best_bias ref_bias < <("$CHLOROVDB_BENCH" best "${fl[@]}" --layer fluorescence \
      --baseline fluorescence=reference --among default fluorescence=direct fluorescence=full)
    read -r _ gain_full full_bias _ < <("$CHLOROVDB_BENCH" best "${fl[@]}" --layer fluorescence \
      --baseline fluorescence=reference --among default)
    uvb_lines+="- **$name** (fluorescence layer, $BUDGET CPU-s, 1/(own relMSE·time)): our most efficient estimator, $best,
  is **${gain}×** as efficient as the reference estimator (docs/physics.md §5); our default (auto) is ${gain_full}×.
  Mean bias against the reference image: $best ${best_bias} %, default ${full_bias} %, reference estimator ${ref_bias} %."$'\n'
  fi
done

cost=""
if [ "$COST_GROWTH" = 1 ]; then
  large=()
  [ "$LARGE" = 1 ] && large=(--large)
  "$CHLOROVDB_BENCH" cost-growth -o "$OUT/cost_growth" --threads "$THREADS" "${large[@]}" > /dev/null
  cp "$OUT/cost_growth/cost_growth.svg" "$FIG/cost_growth.svg"
  cost=$(cat "$OUT/cost_growth/cost_growth.md")
fi

elapsed=$(( $(date +%s) - started ))
{
  cat <<EOF
# Benchmarks: estimator efficiency at equal time, and cost growth

Generated by \`tools/benchmarks/run.sh\` (\`cmake --build build --target benchmarks\`) on
$(date -u +%Y-%m-%d) in ${elapsed} s ($(nproc) cores shared with other jobs; variants on ${THREADS} thread,
references on ${REF_THREADS}). Do not edit by hand: rerun the command.

## Method

Each scene in \`scenes/\` gets a reference (\`chlorovdb reference\`, seed ${REF_SEED}, the scene's own
unbiased settings) and then every variant renders for the same CPU time, on one thread, with
seed 0 (\`chlorovdb converge --clock cpu --time-budgets\`). Time is the process CPU time of the
rendering: the machine may be shared with other jobs, and CPU time is what other load distorts
least. relMSE = mean (x − r)² / (r² + 0.01·mean(r)²) over all pixels and channels of a layer
(linear RGB). Metrics and the plots' −1/2 guide: [convergence.md](convergence.md).

**Converged references.** The measured relMSE is the variant's own (its variance plus its
squared bias) plus the reference's own variance term, mean se_r² / (r² + 0.01·mean(r)²) from
the reference's standard-error layers (its *own relMSE term*). A reference counts as converged
on a layer when that term is at most 10 % of the smallest own relMSE among the scene's variants
at the full budget (analysis/reference_convergence.h): it then changes no variant's error by
more than 10 %, before the correction below. Each reference starts at ${REF_SPP} spp; a pilot
(every variant for ${pilot_budget} CPU-s) predicts each variant's own relMSE at ${BUDGET} s as ∝ 1/time
(for a biased or heavy-tailed variant, whose relMSE falls more slowly, this asks for more
reference than needed), and the reference is extended to the spp its term ∝ 1/spp needs for
the criterion, at most ${REF_SPP_MAX} spp (the bound of the run). [References](#references)
gives, per scene and layer, the spp reached, the reference's own error and whether it met the
criterion against the variants as finally measured.

**Efficiency = 1 / (own relMSE × time)**, own relMSE = measured relMSE − the reference's own
term; higher is better; "vs default" is its ratio to the scene's own settings. The subtraction
is the right estimator here: reference and variant use different seeds (independent) and the
reference is unbiased, so E[(x − r)²] = E[(x − μ)²] + Var(r) with E[se_r²] = Var(r) (μ the exact
image); for relMSE, whose weights 1/(r² + ε) use the noisy r, it holds to first order in the
reference's relative error (test \`ReferenceConvergence.OwnRelMseAgainstANoisyReferenceMatchesTheErrorAgainstTheExactImage\`).
Without it, a reference's term common to all variants would pull their efficiencies together.
1 / (MSE × time) (also with the reference's term removed) is given too, but do not rank by it on
the glass scenes: a reference's few unconverged pixels (fireflies: rare, very bright samples)
alone can set every variant's MSE, while relMSE bounds what each such pixel contributes.

**Warnings (⚠).** Per row, *ref. share* is the reference's own term as a share of the measured
relMSE, and *worst 0.1 % px* the share of the relMSE sum (and of the squared-error sum) held by
the worst 0.1 % of pixels (about 1–2 % for Gaussian noise). A row is marked ⚠, and named in a
sentence under its table, where the reference's share is over 10 % or the worst 0.1 % of pixels
hold over 20 % of relMSE: there a few pixels (or the reference) set the error, one seed's
relMSE is not a measurement of the estimator's, and the ranking of that row is not trustworthy.
A reference that did not meet the criterion is marked ⚠ in [References](#references).
**Noise of the measurement**: where a scene already uses 8 wavelengths, \`wavelengths=8\`
repeats \`default\` exactly (same samples), so their difference is the timing noise alone.

The **mean bias** column is the mean of (estimate − reference) over the image relative to the
reference's mean, both clamped at the reference's 99.9th percentile (so the reference's fireflies
do not set it): within noise of 0 for an unbiased estimator, −100 % for a variant that renders
nothing of that layer. At a few hundred samples a heavy-tailed estimator (rare, bright samples)
also shows a negative mean bias: it has not yet drawn the rare samples that the reference
holds. The fluorescence estimators are compared on the fluorescence layer (the total
layer is dominated by light that never fluoresced, the same for all of them).

Variants: transmittance estimator of shadow and excitation rays (delta / ratio / residual ratio,
\`--transmittance\`); fluorescence estimator (\`--fluorescence reference\`, the thesis's, vs ours:
\`direct\`, \`full\`; \`default\` is \`auto\`), and two design choices of ours undone one at a
time on top of \`default\`: the excitation wavelength drawn uniformly over the excitation band
instead of ∝ light × ε × λ′ (\`excitation=uniform\`, \`--set render.excitation_sampling=uniform\`)
and the quantum yield as a roulette instead of a weight (\`Q=roulette\`,
\`--set render.quantum_yield_mode=roulette\`), both unbiased (docs/fluorescence.md; the thesis's
estimator always does both, so these two show what each choice buys on its own); excitation read
from a photon grid traced before the first pass instead of excitation rays
(\`excitation_estimate=photons\`: consistent, biased by the grid's cells; its pre-pass is part of
its time) and, in scenes with glass, the excitation rays stopped at glass
(\`excitation_through_glass=block\`) or crossing it straight weighted by Fresnel transmission
(\`excitation_through_glass=fresnel\`, an approximation) instead of solving for the refracted
paths; in scenes with glass, camera paths connected through it to area lights too
(\`direct_light_through_glass=all\`, by the straight line's solve) and that with photons
(\`excitation_estimate=photons+direct=all\`); where glass meets point, spot or area lamps, the bounce
connection off (\`excitation_bounce=false\`: the light the lamps send off lit surfaces into the
glass left to continuations alone); wavelengths per
path (\`--wavelengths\`); the camera's wavelengths drawn from the eye's density alone instead of the
scene's mixture of it with the lights' spectra and the pigments' re-emission
(\`camera_wavelengths=visible\`, \`--set render.camera_wavelengths=visible\`); and the renderer's skips of unneeded work
(\`--set render.skip_unneeded_work=false\`). A variant that fails to run is listed under "Not run"
with its error.

## Results

### References

Per scene and layer: the reference's samples per pixel, its RMS standard error relative to its
mean, its own relMSE term, the variant with the smallest own relMSE at ${BUDGET} s (and that
relMSE), the reference's term as a share of it, and whether that share is at most 10 % (the
criterion; at most ${REF_SPP_MAX} spp).

| scene | layer | spp | RMS std. error / mean | own relMSE term | best variant (own relMSE) | share | converged |
| --- | --- | ---: | ---: | ---: | --- | ---: | --- |
${reference_rows}
${tables}
## Our estimators against the thesis's, on the scenes lit by UVB

How to read these ratios: the thesis's estimator triggers emission by absorption at the
emitted wavelength (docs/physics.md §5.1), where chlorophyll hardly absorbs, so on these scenes it
renders almost no fluorescence (its mean bias is the last figure of each line). Its relMSE is
then its squared relative bias, about 1, and does not fall with time; an unbiased estimator's
falls as 1/time, so these equal-time ratios grow in proportion to the budget. Below 1, our
estimator is still noisier at this budget than rendering nothing (heavy tails of \`full\` in
glass: docs/fluorescence.md). Where the fluorescence table marks these rows ⚠, so are these ratios.
${uvb_lines:-No scene lit by a UVB lamp with a fluorescent pigment was benchmarked.}

## Cost growth

CPU time per camera sample (summed over threads; 32×32 image, 4 wavelengths, max depth 64) in a 1 m cube of a grey
medium whose density pattern spans 0.2–1 (so majorants are loose), lit by a distant light and
an environment. Optical depth τ = σ_t across the cube where density = 1; k is the fitted
exponent over τ ≥ 10. Grid size at τ = 10 (albedo 0.9), dense and sparse (a ball holding 11 %
of the voxels). Figure: [cost_growth.svg](${FIG_LINK}/cost_growth.svg).

${cost:-Not run (COST_GROWTH=0).}
EOF
} > "$DOC"
echo "wrote $DOC and $FIG/*.svg in ${elapsed} s" >&2
