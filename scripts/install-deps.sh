#!/usr/bin/env bash
# Installs everything knotwork needs to build and test, from Debian 12 packages only.
# OpenBLAS matters: CHOLMOD supernodal spends its time in BLAS, and Debian's
# default reference BLAS is several times slower.
# Usage: scripts/install-deps.sh [--paraview]
#   --paraview   also install ParaView + Xvfb (only needed to render docs/ screenshots)
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config
  libeigen3-dev libsuitesparse-dev libopenblas-dev
  libvtk9-dev
  catch2 libtomlplusplus-dev libcli11-dev
  libmuparser-dev libginac-dev
  libbenchmark-dev
)
if [[ "${1:-}" == "--paraview" ]]; then
  packages+=(paraview xvfb xauth)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [[ ${#missing[@]} -eq 0 ]]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  exit 0
fi

sudo_cmd=()
[[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
echo "install-deps: installing ${missing[*]}"
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
