#!/usr/bin/env bash
# Strong and weak scaling of method = "petsc" (docs/SCALING.md): the unit-square benchmark
# (u = sin(pi x) sin(pi y)) under mpirun on this machine, one JSON line per run on stdout and a
# table on stderr. Times are the slowest rank's per phase. Run on a quiet machine.
# Usage: scripts/scaling.sh [strong|weak|log] (default: strong and weak)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
knotwork="${KNOTWORK:-$root/build/app/knotwork}"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader \
       OMPI_MCA_btl_vader_single_copy_mechanism=none
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT

# case DEGREE ELEMENTS PRECONDITIONER: a case file for the benchmark problem.
case_file() {
  local f="$scratch/square_p$1_n$2_$3.toml"
  cat > "$f" <<TOML
[geometry]
type = "rectangle"
[space]
degree = $1
elements = $2
[problem]
exact = "sin(pi*x)*sin(pi*y)"
[solver]
method = "petsc"
preconditioner = "$3"
TOML
  echo "$f"
}

# run RANKS DEGREE ELEMENTS PRECONDITIONER [PETSC OPTIONS]
run() {
  local ranks=$1 p=$2 n=$3 pc=$4 options="${5:-}"
  local f; f="$(case_file "$p" "$n" "$pc")"
  local args=(run "$f" --json -q --no-output)
  [[ -n "$options" ]] && args+=(--petsc-options "$options")
  local json
  json="$(/usr/bin/time -f "%M" -o "$scratch/rss" mpirun -n "$ranks" --oversubscribe "$knotwork" "${args[@]}")"
  local rss; rss="$(tail -1 "$scratch/rss")"
  echo "$json" | /usr/bin/python3 -c "
import json, sys
j = json.load(sys.stdin); t = j['timings']; s = j['solver']
label = s['preconditioner'] if s['pc'] in ('hypre', 'shell') else s['pc'] + ' ' + s.get('factor_package', '')
row = {'ranks': j['ranks'], 'degree': $p, 'elements': $n, 'dofs': j['dofs'], 'preconditioner': label,
       'pc': s['pc'], 'iterations': s['iterations'], 'setup': t['setup'], 'assembly': t['assembly'],
       'pc_setup': t['preconditioner'], 'solve': t['iterations'], 'errors': t['errors'],
       'total': t['total_without_output'], 'l2_error': j['l2_error'], 'max_rss_mb_one_rank': $rss / 1024}
print(json.dumps(row))
print('%5d %2d %5d %9d %-22s %4d %7.2f %7.2f %7.2f %7.2f %7.2f %8.2f %7.0f %.6e' % (row['ranks'], $p, $n, row['dofs'],
      row['preconditioner'], row['iterations'], row['setup'], row['assembly'], row['pc_setup'], row['solve'],
      row['errors'], row['total'], row['max_rss_mb_one_rank'], row['l2_error']), file=sys.stderr)
"
}

header() {
  echo "ranks  p     n      dofs preconditioner        its   setup  assemb pcsetup   solve  errors    total  rss MB  L2 error" >&2
}

mode="${1:-all}"
if [[ "$mode" == strong || "$mode" == all ]]; then
  echo "# strong scaling: the same problem on 1 and 2 ranks" >&2
  header
  for spec in "2 1022" "4 1000"; do
    read -r p n <<< "$spec"
    for pc in boomeramg fast_diagonalization; do
      for ranks in 1 2; do run "$ranks" "$p" "$n" "$pc"; done
    done
  done
  echo "# MUMPS (distributed Cholesky) at a quarter of the size" >&2
  header
  for ranks in 1 2; do run "$ranks" 2 510 boomeramg "-ksp_type preonly -pc_type cholesky -pc_factor_mat_solver_type mumps"; done
fi
if [[ "$mode" == weak || "$mode" == all ]]; then
  echo "# weak scaling: about 262k dofs per rank (4 ranks oversubscribe the 2 cores)" >&2
  header
  for spec in "1 510" "2 722" "4 1022"; do
    read -r ranks n <<< "$spec"
    run "$ranks" 2 "$n" boomeramg
  done
fi
if [[ "$mode" == log ]]; then
  f="$(case_file 2 1022 boomeramg)"
  mpirun -n 2 "$knotwork" run "$f" -q --no-output --petsc-options "-log_view"
fi
