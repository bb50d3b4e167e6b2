#!/usr/bin/env bash
# The README's two commands:
#   ./quickstart.sh render [SCENE.json] [extra render options]   install, build, render
#   ./quickstart.sh test                                          install, build, run the tests
#   ./quickstart.sh python                                        install pybind11 & co, build and test the Python module
# Both install missing Debian packages, configure and build Release in build/.
set -euo pipefail
cd "$(dirname "$0")"

jobs=$(nproc 2>/dev/null || echo 2)
build() {
  tools/install-deps.sh
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build --parallel "$jobs"
}

case "${1:-}" in
  render)
    shift
    scene=scenes/default.json
    if [ $# -gt 0 ] && [[ "$1" != -* ]]; then scene=$1; shift; fi
    build
    mkdir -p out
    name=$(basename "$scene" .json)
    ./build/src/cli/chlorovdb render "$scene" -o "out/$name.exr" "$@"
    ;;
  test)
    shift
    build
    # Long convergence and benchmark runs carry the label "long" and run with
    # `ctest -L long`; the default suite is the CI-sized one.
    ctest --test-dir build --output-on-failure --parallel "$jobs" -LE long "$@"
    ;;
  python)
    # The Python module (docs/python.md) in build/python: its packages, then the
    # module and its test. Use it with PYTHONPATH=build/python /usr/bin/python3.
    tools/install-deps.sh python
    cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCHLOROVDB_PYTHON=ON >/dev/null
    cmake --build build --parallel "$jobs" --target chlorovdb_python
    ctest --test-dir build --output-on-failure -L python
    ;;
  *)
    echo "usage: ./quickstart.sh render [SCENE.json] [options] | ./quickstart.sh test | ./quickstart.sh python" >&2
    exit 2
    ;;
esac
