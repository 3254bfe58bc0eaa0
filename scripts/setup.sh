#!/usr/bin/env bash
# One command from a fresh Debian 12 machine to a solved benchmark case:
# installs the Debian packages, builds knotwork in Release, and solves the unit-square
# case, writing ParaView files to results/square_sinsin/.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
cd "$root"
./build/app/knotwork run cases/square_sinsin.toml
PYTHONPATH="$root/build/python" /usr/bin/python3 -c \
  'import knotwork; print("Python:", knotwork.run("cases/square_sinsin.toml"))'
echo
echo "Open results/square_sinsin/solution.vtu in ParaView (exact Bezier cells)."
echo "From Python: export PYTHONPATH=$root/build/python (docs/PYTHON.md)."
