#!/usr/bin/env bash
# Installs everything knotwork needs to build and test, from Debian 12 packages only.
# OpenBLAS matters: CHOLMOD supernodal spends its time in BLAS, and Debian's
# default reference BLAS is several times slower. petsc-dev brings hypre (the BoomerAMG
# preconditioner), MUMPS and OpenMPI; openmpi-bin's mpirun starts method = "petsc" on several
# processes (and the tests that check it); time measures scripts/scaling.sh's memory.
# libboost-dev: only Boost.Geometry's R-tree (header-only), the knot segments' support index.
# libspectra-dev: Lanczos (header-only) for the condition estimates of run --condition.
# Usage: scripts/install-deps.sh [--paraview] [--sanitize]
#   --sanitize   also install clang 14 with its sanitizer and libFuzzer runtimes and LLVM's
#                OpenMP (scripts/sanitize.sh, scripts/fuzz.sh; docs/RELIABILITY.md).
#   --paraview   also install ParaView + Xvfb (only needed to render docs/ screenshots).
#                Debian 12's python3-paraview conflicts with python3-vtk9, which libvtk9-dev
#                needs, so its files are unpacked into .paraview-python/ (used only by
#                scripts/render_paraview.sh) instead of being installed.
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config
  libeigen3-dev libsuitesparse-dev libopenblas-dev
  libvtk9-dev python3-vtk9
  catch2 libtomlplusplus-dev libcli11-dev nlohmann-json3-dev libpugixml-dev
  libginac-dev libgmp-dev libboost-dev
  libbenchmark-dev libspectra-dev
  pybind11-dev python3-dev python3-numpy python3-scipy python3-matplotlib python3-pytest
  python3-pip python3-setuptools python3-wheel python3-venv
  petsc-dev openmpi-bin time
)
with_paraview=0
for arg in "$@"; do
  case "$arg" in
    --paraview) with_paraview=1; packages+=(paraview xvfb xauth) ;;
    --sanitize) packages+=(clang-14 libclang-rt-14-dev libomp-14-dev) ;;
    *) echo "install-deps: unknown option '$arg' (--paraview, --sanitize)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
sudo_cmd=()
[[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
if dpkg-query -W -f='${Status}' python3-paraview 2>/dev/null | grep -q "install ok installed"; then
  echo "install-deps: python3-paraview is installed and conflicts with libvtk9-dev (via python3-vtk9);" >&2
  echo "install-deps: remove it (apt-get remove python3-paraview): --paraview sets ParaView up without it" >&2
  exit 1
fi
if [[ ${#missing[@]} -eq 0 ]]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
else
  echo "install-deps: installing ${missing[*]}"
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

if [[ $with_paraview -eq 1 ]]; then
  root="$(cd "$(dirname "$0")/.." && pwd)"
  target="$root/.paraview-python"
  if [[ ! -d "$target/usr/lib/python3/dist-packages/paraview" ]]; then
    tmp="$(mktemp -d)"
    (cd "$tmp" && apt-get download python3-paraview >/dev/null 2>&1)
    mkdir -p "$target"
    dpkg-deb -x "$tmp"/python3-paraview_*.deb "$target"
    rm -rf "$tmp"
    echo "install-deps: ParaView's Python modules unpacked into $target"
  fi
fi
