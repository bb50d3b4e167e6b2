#!/bin/bash
# Renders the preview of every reference scene (scenes/*.json but default.json and bench/) with the
# project's own command, copies the PNGs to docs/gallery/ and writes docs/gallery.md with each image,
# its command line, sample count and the render time measured here.
#
#   tools/render_gallery.sh [--bin CHLOROVDB] [--threads N] [--md-only] [SCENE_NAME ...]
#
# --md-only rewrites docs/gallery.md from the recorded times (out/gallery/times.tsv) without rendering.
# Defaults: build-scenes/src/cli/chlorovdb (else build/src/cli/chlorovdb), 2 threads, every scene in
# the list below. Naming scenes re-renders only those and keeps the other entries of docs/gallery.md
# (rendered at older commits); the full run, with no names, is the one to publish.
# Meshes and volumes are regenerated first if missing (tools/make_meshes.py, tools/make_volumes.sh).
# EXRs go to out/gallery/ (not committed). Times: wall clock of the whole `chlorovdb render` process
# and its CPU time (user + sys); the machine's load average is recorded with them, since other work on
# the machine stretches the wall time (CPU time / threads is what an idle machine would take).
# Non-interactive; stops at the first failed render. A render's warnings (e.g. a grid's length unit)
# are repeated on stderr. The doc records the commit (marked -dirty with uncommitted changes).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

bin=""
threads=2
only=()
md_only=0
while [ $# -gt 0 ]; do
  case "$1" in
    --bin) bin=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --md-only) md_only=1; shift ;;
    -h|--help) sed -n '2,15p' "$0"; exit 0 ;;
    *) only+=("${1%.json}"); shift ;;
  esac
done
if [ -z "$bin" ]; then
  for b in build-scenes/src/cli/chlorovdb build/src/cli/chlorovdb; do
    if [ -x "$b" ]; then bin=$b; break; fi
  done
fi
[ -n "$bin" ] && [ -x "$bin" ] || { echo "render_gallery.sh: no chlorovdb binary; build one or pass --bin" >&2; exit 1; }

# Scene | figure of the thesis (Chapter 5) | what the image shows.
scenes=$(cat <<'EOF'
glass_F2_0.02uM|Fig. 5.4|0.02 µM under F2: clear water in the beaker; no tint, no red.
glass_F2_1uM|Fig. 5.4|1 µM under F2: a pale yellow-green tint; no red.
glass_F2_5uM|Figs 5.4, 5.5 (left)|5 µM under F2: light green; no red glow (fluorescence is 1.5 % of the red channel in the liquid).
glass_F2_25uM|Fig. 5.4|25 µM under F2: dark blue-green, the darkest of the series; no red (fluorescence 7 % of the red channel).
glass_D65_5uM|Fig. 5.5 (right)|5 µM under D65: blue-green (cooler than under F2); no red glow although D65 reaches into the UV (fluorescence is 4 % of the red channel).
glass_UVB_5uM_Q0|Fig. 5.6 (left)|5 µM, Q = 0, UVB tube in a dark room: no red at all; the liquid only passes the tube's 546/578 nm mercury lines (green) — not the thesis's violet: the shipped ε absorbs the tube's 405/436 nm lines.
glass_UVB_5uM_Q0.23|Fig. 5.6 (right)|5 µM, Q = 0.23, same light: the solution glows red (fluorescence is 96 % of its red channel, which is 8 x its green).
spill_1uM_D65|Fig. 5.8 (top)|1 µM spill (4 mm deep) under D65: a barely visible tint (green/red +5 % over the floor): the thesis's concentration in a real puddle has almost no absorbance.
spill_1uM_UVB_D65|Fig. 5.8 (bottom)|1 µM spill, UVB + D65: the floor turns lavender from the tube's visible lines; the spill's fluorescence (about 4 % of red) is not visible.
spill_25uM_D65|Fig. 5.8 (top), 25 µM|The same puddle at 25 µM (1 µM over 10 cm): a transparent green pool.
spill_25uM_UVB_D65|Fig. 5.8 (bottom), 25 µM|25 µM, UVB + D65: one mixed olive / yellow-green hue over the whole pool (D65 green plus red fluorescence).
teapot_50uM_D65|Fig. 5.11 (top)|50 µM in a glass teapot, D65 spot only: deep blue-teal (chlorophyll a's 450–510 nm window over a 12 cm path); no red.
teapot_50uM_D65_UVB_aim0|Fig. 5.10 (1/4)|UVB spot aimed at the floor below it (violet-white patch, left); the vessel as with D65 alone.
teapot_50uM_D65_UVB_aim1|Fig. 5.10 (2/4)|UVB aim turned a third of the way: the patch moves towards the vessel.
teapot_50uM_D65_UVB_aim2|Figs 5.10 (3/4), 5.11 (bottom)|UVB slightly aimed at the vessel: a red glow where the beam enters the liquid beside the blue-teal body.
teapot_50uM_D65_UVB_aim3|Fig. 5.10 (4/4)|UVB aimed at the vessel: red on the liquid's top and the UV side, blue-teal elsewhere; the two colours coexist.
leaf_D65|leaf (beyond the thesis)|A leaf (in-vivo PROSPECT-D absorption, Q = 0.02, mesophyll scattering) in D65 sun and sky: green and translucent (green light in its shadow); no red.
leaf_UVB|leaf (beyond the thesis)|The leaf under the UVB light box: yellow-green from the tube's 546/578 nm lines, no red glow (no UV absorption in the in-vivo table, Q = 0.02).
EOF
)

want() {
  [ ${#only[@]} -eq 0 ] && return 0
  local s
  for s in "${only[@]}"; do [ "$s" = "$1" ] && return 0; done
  return 1
}

[ -f meshes/beaker_glass.obj ] || /usr/bin/python3 tools/make_meshes.py
[ -f volumes/spill_1uM.vdb ] && [ -f volumes/leaf_chl.vdb ] || tools/make_volumes.sh "$bin"
mkdir -p docs/gallery out/gallery
times=out/gallery/times.tsv   # scene, spp, resolution, wall s, cpu s, load average, mode, routes; kept between runs
touch "$times"
# A full run renders every scene at this commit: no times survive from an older one.
[ ${#only[@]} -eq 0 ] && [ "$md_only" = 0 ] && : > "$times"

while IFS='|' read -r name fig caption; do
  [ -n "$name" ] || continue
  want "$name" || continue
  [ "$md_only" = 0 ] || continue
  scene=scenes/$name.json
  [ -f "$scene" ] || { echo "missing $scene" >&2; exit 1; }
  load=$(cut -d' ' -f1 /proc/loadavg)
  start=$(date +%s.%N)
  /usr/bin/time -f "%U %S" -o out/gallery/cpu.txt \
    "$bin" render "$scene" -o "out/gallery/$name.exr" --threads "$threads" -q > "out/gallery/$name.log" 2>&1 ||
    { cat "out/gallery/$name.log" >&2; exit 1; }
  end=$(date +%s.%N)
  wall=$(echo "$start $end" | awk '{printf "%.1f", $2 - $1}')
  cpu=$(awk '{printf "%.1f", $1 + $2}' out/gallery/cpu.txt)
  grep '^warning:' "out/gallery/$name.log" | sed "s|^|$name: |" >&2 || true
  cp "out/gallery/$name.png" "docs/gallery/$name.png"
  meta=$(iinfo -v "out/gallery/$name.exr" 2>/dev/null || true)
  spp=$(echo "$meta" | sed -n 's/^ *chlorovdb:spp: *//p' | head -1)
  res=$(echo "$meta" | sed -n 's/^ *chlorovdb:full_resolution: *"\(.*\)"/\1/p' | head -1)
  mode=$(grep -o 'fluorescence: [a-z]*' "out/gallery/$name.log" | head -1 | cut -d' ' -f2 || true)
  nonfinite=$(echo "$meta" | sed -n 's/^ *chlorovdb:nonfinite_samples: *//p' | head -1)
  routes=$(echo "$meta" | sed -n 's/^ *chlorovdb:excitation_routes: *"\(.*\)"/\1/p' | head -1)
  [ "${nonfinite:-0}" = "0" ] || echo "$name: ${nonfinite} non-finite samples" >&2
  grep -v "^$name	" "$times" > "$times.new" || true
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "${spp:-?}" "${res:-?}" "$wall" "$cpu" "$load" "${mode:-none}" \
    "$routes" >> "$times.new"
  mv "$times.new" "$times"
  echo "$name: ${spp:-?} spp, ${res:-?}, ${wall} s wall, ${cpu} s CPU (load ${load})"
done <<< "$scenes"

# docs/gallery.md from the table of times (every scene of the list that has been rendered).
{
  echo "# Gallery: the reference scenes"
  echo
  echo "Previews of the scenes in \`scenes/\` that reproduce the reference image set of the thesis (Chapter 5,"
  echo "Figs 5.4–5.11), plus a leaf. Made by \`tools/render_gallery.sh\` with the project's own \`chlorovdb render\`"
  echo "(PNG preview: sRGB curve, the scene's \`exposure\`); each scene file's header comment gives its set-up and the"
  echo "physics behind its look. Meshes: \`tools/make_meshes.py\`; grids: \`tools/make_volumes.sh\`."
  echo
  echo "Times are measured by the script around the whole \`chlorovdb render\` process with $threads threads: wall"
  echo "clock, and CPU time (user + sys). The machine is shared, so the wall time depends on its load (1-minute"
  echo "load average given per image; with other work running, each render gets a fraction of the 2 cores); CPU time"
  echo "/ $threads is what an idle 2-core machine takes."
  echo
  commit=$(git rev-parse --short HEAD)
  git diff --quiet HEAD -- src scenes spectra volumes meshes 2>/dev/null || commit="$commit-dirty"
  total=$(awk -F'\t' '{w += $4; c += $5} END {printf "%.0f s wall, %.0f s CPU", w, c}' "$times")
  echo "Commit: \`$commit\`, binary: \`$bin\`, $(date -u '+%Y-%m-%d %H:%M UTC'). All renders: $total."
  echo
  while IFS='|' read -r name fig caption; do
    [ -n "$name" ] || continue
    row=$(grep "^$name	" "$times" || true)
    [ -n "$row" ] || continue
    IFS=$'\t' read -r _ spp res wall cpu load mode routes <<< "$row"
    echo "## $name — $fig"
    echo
    echo "![$name](gallery/$name.png)"
    echo
    echo "$caption"
    echo
    echo '```sh'
    echo "chlorovdb render scenes/$name.json -o out/gallery/$name.exr --threads $threads -q"
    echo '```'
    echo
    echo "$spp spp, ${res/x/ × } px, fluorescence \`$mode\`: **$wall s** wall (load $load), $cpu s CPU."
    echo
    if [ -n "$routes" ]; then
      echo "What excited the fluorescence (share of the mean / of the second moment; docs/fluorescence.md, \"Where the"
      echo "excitation comes from\"): $routes."
      echo
    fi
  done <<< "$scenes"
} > docs/gallery.md
echo "wrote docs/gallery.md"
