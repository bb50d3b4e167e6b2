#!/usr/bin/env bash
# Installs the Debian 12 packages chlorovdb builds with, only if any is missing.
# Needs root (or sudo) when something must be installed; says so clearly otherwise.
#
#   tools/install-deps.sh [mpi] [python] [fuzz]
#
# The optional builds' packages come only when their group is named:
#   mpi     libopenmpi-dev openmpi-bin                 (-DCHLOROVDB_MPI=ON, docs/distributed.md)
#   python  pybind11-dev python3-dev python3-numpy     (-DCHLOROVDB_PYTHON=ON, docs/python.md)
#   fuzz    clang libclang-rt-dev                      (fuzz targets, sanitizer build: docs/robustness.md)
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libopenvdb-dev libnanovdb-dev libembree-dev libopenimageio-dev openimageio-tools
  libopenexr-dev libimath-dev libtbb-dev libboost-dev libboost-iostreams-dev
  libassimp-dev nlohmann-json3-dev libcli11-dev libfmt-dev libgtest-dev libbenchmark-dev
)
for group in "$@"; do
  case "$group" in
    mpi) packages+=(libopenmpi-dev openmpi-bin) ;;
    python) packages+=(pybind11-dev python3-dev python3-numpy) ;;
    fuzz) packages+=(clang libclang-rt-dev) ;;
    *) echo "install-deps.sh: unknown group '$group' (mpi, python, fuzz)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "chlorovdb: installing missing Debian packages: ${missing[*]}"
if [ "$(id -u)" -eq 0 ]; then
  sudo=()
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
  sudo=(sudo)
else
  echo "chlorovdb: these packages are missing and installing them needs root:" >&2
  echo "  sudo apt-get install --no-install-recommends ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
# --no-install-recommends: recommends only pull GPU drivers and media frameworks.
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
