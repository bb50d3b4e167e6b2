#!/usr/bin/env bash
# Fluorescence behind curved / smooth-shaded mesh glass: `full` mode with
# excitation_through_glass = block, connect and fresnel on the beaker
# (glass_UVB_5uM_Q0.23, area lamp) and the teapot (teapot_50uM_D65_UVB_aim2,
# spot lights), small images, one thread, several seeds.
#
#   tools/experiments/glass_connect_scenes.sh        (env: SEEDS=16 SPP=256 RES=24x18 BIN=build/src/cli/chlorovdb)
#
# Per scene and variant: the image mean of fluorescence R over seeds (± σ of the
# mean over seeds), the per-pixel variance of one image (the variance across
# seeds, averaged over pixels), the render time from the renderer's own "done"
# line, and variance × time; then connect − block paired by seed.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=${BIN:-build/src/cli/chlorovdb}
seeds=${SEEDS:-16} spp=${SPP:-256} res=${RES:-24x18}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for scene in scenes/glass_UVB_5uM_Q0.23.json scenes/teapot_50uM_D65_UVB_aim2.json; do
  name=$(basename "$scene" .json)
  for mode in block connect fresnel; do
    for seed in $(seq 1 "$seeds"); do
      line=$("$bin" render "$scene" --resolution "$res" --spp "$spp" --threads 1 --seed "$seed" -q --fluorescence full \
               --set render.excitation_through_glass="$mode" -o "$out/img.exr" 2>&1 | grep '^done')
      oiiotool "$out/img.exr" --ch fluorescence.R -o "$out/f.exr"
      { echo "time $(sed -E 's/.* in ([0-9.]+) s.*/\1/' <<<"$line")"; oiiotool --dumpdata "$out/f.exr"; } \
        > "$out/${name}_${mode}_${seed}.txt"
    done
  done
done
python3 - "$out" "$seeds" "$spp" "$res" <<'PY'
import glob, math, os, re, sys
out, seeds, spp, res = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
def load(path):
    t, px = 0.0, []
    for line in open(path):
        if line.startswith("time"): t = float(line.split()[1])
        m = re.search(r"Pixel \(\d+, \d+\): ([-0-9.eE+naif]+)", line)
        if m: px.append(float(m.group(1)))
    return t, px
print(f"{res}, {spp} spp, {seeds} seeds, 1 thread, fluorescence R")
for name in ("glass_UVB_5uM_Q0.23", "teapot_50uM_D65_UVB_aim2"):
    means = {}
    for mode in ("block", "connect", "fresnel"):
        runs = [load(os.path.join(out, f"{name}_{mode}_{s}.txt")) for s in range(1, seeds + 1)]
        m = [sum(px) / len(px) for _, px in runs]
        means[mode] = m
        mu = sum(m) / seeds
        sd = math.sqrt(sum((v - mu) ** 2 for v in m) / (seeds - 1) / seeds)
        npx = len(runs[0][1])
        var = 0.0
        for i in range(npx):
            col = [px[i] for _, px in runs]
            c = sum(col) / seeds
            var += sum((v - c) ** 2 for v in col) / (seeds - 1)
        var /= npx
        t = sum(r[0] for r in runs) / seeds
        print(f"{name} {mode:8s} mean {mu:.5g} ± {sd:.2g}  per-pixel variance {var:.4g}  time {t:.3f} s  variance×time {var * t:.4g}")
    d = [c - b for c, b in zip(means["connect"], means["block"])]
    dm = sum(d) / seeds
    ds = math.sqrt(sum((v - dm) ** 2 for v in d) / (seeds - 1) / seeds)
    print(f"{name} connect − block paired: {dm:+.4g} ± {ds:.2g} ({100 * dm / (sum(means['block']) / seeds):+.1f} %, {dm / ds if ds > 0 else 0:.1f}σ)")
PY
