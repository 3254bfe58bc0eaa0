#!/usr/bin/env bash
# Renders a knotwork .vtu to PNG with ParaView's own reader and renderer, headless.
# Usage: scripts/render_paraview.sh FILE.vtu OUT.png [field] [--cell-data] [--log] [--lines X.vtp] [--camera x,y,z] [--no-edges]
# Needs: scripts/install-deps.sh --paraview
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
modules="$root/.paraview-python/usr/lib/python3/dist-packages"
if [[ ! -d "$modules/paraview" ]]; then
  echo "render_paraview: ParaView is not set up; run scripts/install-deps.sh --paraview" >&2
  exit 2
fi
export PYTHONPATH="$modules${PYTHONPATH:+:$PYTHONPATH}"
exec xvfb-run -a pvbatch "$root/scripts/render_paraview.py" "$@"
