#!/bin/sh
# Regenerates every render regression reference (tests/regression/data/*.ref): one per scene in
# scenes/*.json (not scenes/bench/: its grid is not shipped), rendered by regression_render --write (64 batches of 16 spp
# at 32 px across, fixed seeds). The only source of that data: rerun after any change that is meant
# to change images (an estimator, a default, a shipped spectrum), and commit the result.
#
#   tools/make_regression_refs.sh [BUILD_DIR] [SCENE.json ...]    # default: build, every scene
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
build=${1:-build}
[ $# -gt 0 ] && shift
cmake --build "$build" --target regression_render >/dev/null
bin=$build/tests/regression/regression_render
mkdir -p tests/regression/data
if [ $# -eq 0 ]; then set -- scenes/*.json; fi
export CHLOROVDB_SPECTRA="$root/spectra"
start=$(date +%s)
for scene in "$@"; do
  name=$(echo "${scene#scenes/}" | sed 's|/|__|g; s|\.json$||')
  "$bin" --write "tests/regression/data/$name.ref" "$scene"
done
echo "make_regression_refs.sh: $# references in $(( $(date +%s) - start )) s"
