#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs the Debian 12 packages nurbsfront needs to build, test and benchmark.
# Idempotent: installs only what is missing. Works as root, or through sudo.
#   --cgal  also CGAL (libcgal-dev, GPL) for the optional bench_cgal comparison
#           (cmake -DNURBSFRONT_BUILD_CGAL_BENCH=ON); nothing else needs it.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libopenmesh-dev libeigen3-dev libcli11-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev
)
for arg in "$@"; do
  case "$arg" in
    --cgal) packages+=(libcgal-dev) ;;
    *) echo "install-deps: unknown option $arg (known: --cgal)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

if [ "$(id -u)" -eq 0 ]; then
  SUDO=()
elif command -v sudo >/dev/null 2>&1; then
  SUDO=(sudo)
else
  echo "install-deps: need root or sudo to install: ${missing[*]}" >&2
  exit 1
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${SUDO[@]}" apt-get update -qq
"${SUDO[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
