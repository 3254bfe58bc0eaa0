#!/bin/sh
# The linear solvers of adaptive THB loops side by side (docs/ADAPTIVITY.md, "Multigrid over
# the steps"): one `knotwork adapt` per case, degree and solver, each in its own process (its
# peak RSS its own), printed as the table's Markdown rows: steps, final dofs and H1 error, the
# whole loop's wall time, the linear solves' seconds summed over the steps (CHOLMOD's analysis,
# factorization and solve, or the preconditioner's set-up and CG) and the last step's, and CG's
# iterations at the last step. Run from the repository root after building; about 6 minutes.
#   bench/adaptive_solvers.sh [KNOTWORK_BINARY]
set -eu
knotwork=${1:-build/app/knotwork}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
run() {  # case degree max_dofs solver
  case $4 in
    direct) solver="--solver direct" ;;
    *) solver="--solver iterative --preconditioner $4" ;;
  esac
  start=$(date +%s.%N)
  # shellcheck disable=SC2086
  /usr/bin/time -f "%M" -o "$out/rss" "$knotwork" adapt "cases/$1.toml" --degree "$2" --steps 200 --max-dofs "$3" \
    $solver --no-output --json -q > "$out/adapt.json"
  end=$(date +%s.%N)
  /usr/bin/python3 - "$out" "$1" "$2" "$4" "$start" "$end" <<'PY'
import json, sys
out, case, p, name, start, end = sys.argv[1:]
steps = json.load(open(out + "/adapt.json"))["steps"]
linear = lambda s: sum(s["solve_phases"][k] for k in ("analysis", "factorization", "solve", "preconditioner", "iterations"))
rss = int(open(out + "/rss").read().split()[-1]) / 1024
last = steps[-1]
print(f"| {case} | {p} | {name} | {len(steps)} | {last['dofs']} | {last['h1_seminorm_error']:.4e} | "
      f"{float(end) - float(start):.2f} | {sum(linear(s) for s in steps):.2f} | {linear(last):.2f} | "
      f"{last['iterations']} | {rss:.0f} MB |")
PY
}
echo "| case | p | solver | steps | final dofs | H1 error | loop s | linear s | last step's linear s | last CG its | peak RSS |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for solver in direct multigrid boomeramg; do run lshape_adaptive_thb 3 50000 $solver; done
for solver in direct multigrid; do run lshape_adaptive_thb 2 50000 $solver; done
for solver in direct multigrid; do run interior_layer_thb 2 50000 $solver; done
for solver in direct multigrid; do run interior_layer_thb 2 400000 $solver; done
for solver in direct multigrid boomeramg; do run fichera_adaptive_thb 2 100000 $solver; done
