#!/usr/bin/env bash
# clang and its runtimes (libFuzzer, ASan, UBSan), only for the fuzz targets and
# the sanitizer build CI runs (tools/sanitize.sh --fuzz, tools/fuzz.sh; docs/robustness.md).
# The normal build never needs them. Installs only what is missing; needs root or sudo then.
set -euo pipefail

packages=(clang libclang-rt-dev)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "chlorovdb: installing missing Debian packages for the fuzz and sanitizer build: ${missing[*]}"
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
