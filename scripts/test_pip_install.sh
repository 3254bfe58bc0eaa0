#!/usr/bin/env bash
# `pip install .` as a user does it, offline: into a scratch virtual environment that sees
# Debian's packages (numpy, scipy), with a build folder of its own that is deleted afterwards
# (the installed module must not need it). Then `import knotwork` from another folder: a solve,
# a PETSc solve (the PETSc module installed next to the core) and the assembled system; then
# `pip uninstall` must remove every file it installed. Run by CI (.ci/run); about a minute with
# a warm ccache.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
scratch="$(mktemp -d)"
# Inside the checkout, so that ccache's keys (relative to it) match the main build's.
build="$root/build/pip-test"
trap 'rm -rf "$scratch" "$build"' EXIT
/usr/bin/python3 -m venv --system-site-packages "$scratch/venv"
python="$scratch/venv/bin/python"
KNOTWORK_PIP_BUILD_DIR="$build" "$python" -m pip install --no-build-isolation --no-index --quiet "$root"
rm -rf "$build"
site="$("$python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
mkdir "$scratch/elsewhere"
cd "$scratch/elsewhere"
"$python" - "$root" "$site" <<'PY'
import pathlib
import sys

root, site = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
import knotwork

assert pathlib.Path(knotwork.__file__).parent == site / "knotwork", knotwork.__file__
case = root / "cases" / "quarter_annulus.toml"
direct = knotwork.run(case)
petsc = knotwork.run(case, solver="petsc")
assert petsc.solver["method"] == "petsc", petsc.solver
assert abs(petsc.l2_error - direct.l2_error) <= 1e-8 * direct.l2_error, (petsc.l2_error, direct.l2_error)
s = knotwork.system(case)
assert s.stiffness.shape[0] == direct.space.num_functions
print(f"pip install: knotwork {knotwork.__file__}: L2 error {direct.l2_error:.6e} (direct), "
      f"{petsc.l2_error:.6e} (PETSc), system of {s.stiffness.shape[0]} functions")
PY
"$python" -m pip uninstall --yes --quiet knotwork
if [[ -e "$site/knotwork" ]] && find "$site/knotwork" -type f ! -name '*.pyc' | grep -q .; then
  echo "pip uninstall left files in $site/knotwork:" >&2
  find "$site/knotwork" -type f >&2
  exit 1
fi
if "$python" -c 'import knotwork' 2>/dev/null; then
  echo "pip uninstall: knotwork still imports" >&2
  exit 1
fi
echo "pip install: installed, imported from another folder, uninstalled"
