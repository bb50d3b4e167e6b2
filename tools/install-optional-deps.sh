#!/usr/bin/env bash
# Debian packages for the optional builds, which the normal build never needs:
#   mpi     libopenmpi-dev openmpi-bin        (-DCHLOROVDB_MPI=ON, docs/distributed.md)
#   python  pybind11-dev python3-dev python3-numpy   (-DCHLOROVDB_PYTHON=ON, docs/python.md)
#   fuzz    clang libclang-rt-dev             (fuzz targets and the sanitizer build, docs/robustness.md)
#
#   tools/install-optional-deps.sh mpi python fuzz
#
# Installs only what is missing; needs root or password-less sudo then.
set -euo pipefail

packages=()
for group in "$@"; do
  case "$group" in
    mpi) packages+=(libopenmpi-dev openmpi-bin) ;;
    python) packages+=(pybind11-dev python3-dev python3-numpy) ;;
    fuzz) packages+=(clang libclang-rt-dev) ;;
    *) echo "install-optional-deps.sh: unknown group '$group' (mpi, python, fuzz)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "chlorovdb: installing missing Debian packages ($*): ${missing[*]}"
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
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
