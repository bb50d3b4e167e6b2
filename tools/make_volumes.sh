#!/bin/sh
# Regenerates the concentration grids in volumes/ that the reference scenes use, from the procedural
# inputs in meshes/ (made by tools/make_meshes.py). Deterministic: same inputs, same grids.
#
#   tools/make_volumes.sh [CHLOROVDB]     # default: build-scenes/src/cli/chlorovdb, else build/src/cli/chlorovdb
#
# Every grid records its own command line in its "provenance" metadata (`chlorovdb info FILE.vdb`).
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
bin=${1:-}
if [ -z "$bin" ]; then
  for b in build-scenes/src/cli/chlorovdb build/src/cli/chlorovdb; do
    if [ -x "$b" ]; then bin=$b; break; fi
  done
fi
[ -n "$bin" ] && [ -x "$bin" ] || { echo "make_volumes.sh: no chlorovdb binary (build it, or pass its path)" >&2; exit 1; }
[ -f meshes/spill_height.txt ] && [ -f meshes/leaf.obj ] || /usr/bin/python3 tools/make_meshes.py
mkdir -p volumes

# A puddle (spills, Figs 5.7-5.8): the height field's 161 x 111 samples, 2 mm apart, give the local
# depth as a fraction of 4 mm; 1 µM throughout; voxels 2 mm across and 0.25 mm deep (16 through the
# deepest point); centred on the origin, on the floor y = 0 (metres).
"$bin" voxelize meshes/spill_height.txt -o volumes/spill_1uM.vdb --mode spill \
  --cell-size 0.002 --depth 0.004 --voxel-size 0.002,0.00025,0.002 \
  --concentration 1 --unit uM --grid-name chlorophyll --translate -0.16,0,-0.11

# A leaf blade (leaf_*.json): a 0.2 mm shell around the generated blade (cm, hence --scale 0.01), lifted
# 2 cm; voxels 0.3 mm across the blade and 50 µm through it (the blade lies roughly in the xz plane);
# 2238 µM = 40 µg/cm² of chlorophyll over 0.2 mm (see scenes/leaf_D65.json).
"$bin" voxelize meshes/leaf.obj -o volumes/leaf_chl.vdb --mode shell --thickness 0.0002 \
  --voxel-size 0.0003,0.00005,0.0003 --scale 0.01 --translate 0,0.02,0 \
  --concentration 2238 --unit uM --grid-name chlorophyll
