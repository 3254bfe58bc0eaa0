#!/bin/sh
# The volumes' preconditioners side by side (docs/PERFORMANCE.md, "Multigrid on volumes"): one
# `knotwork run` per case, degree, element count and preconditioner, each in its own process
# (its peak RSS its own), printed as the table's Markdown rows. Run from the repository root
# after building; takes about 7 minutes on 2 cores.
#   bench/volume_preconditioners.sh [KNOTWORK_BINARY]
set -eu
knotwork=${1:-build/app/knotwork}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
run() {  # case degree elements preconditioner
  if /usr/bin/time -f "%M" -o "$out/rss" "$knotwork" run "cases/$1.toml" --degree "$2" --elements "$3" \
      --solver iterative --preconditioner "$4" --no-output --json > "$out/run.json" 2> "$out/err"; then
    /usr/bin/python3 - "$out" "$1" "$2" "$3" "$4" <<'PY'
import json, sys
out, case, p, n, name = sys.argv[1:]
d = json.load(open(out + "/run.json")); s = d["solver"]; t = d["timings"]
rss = int(open(out + "/rss").read().split()[-1]) / 1024
print(f"| {case} | {p} | {n} | {d['free_dofs']} | {name} | {s['matrix']} | {s['iterations']} | {d['l2_error']:.6e} | "
      f"{d['h1_error']:.6e} | {t['preconditioner']:.2f} | {t['iterations']:.2f} | {t['total_without_output']:.2f} | {rss:.0f} MB |")
PY
  else
    echo "| $1 | $2 | $3 | | $4 | $(grep -v '^knotwork \[' "$out/err" | head -1) |"
  fi
}
for case in cube thick_quarter_annulus; do
  for n in 16 32 64; do for pc in fast_diagonalization multigrid boomeramg; do run $case 2 $n $pc; done; done
  for pc in fast_diagonalization multigrid; do run $case 2 128 $pc; done
  for p in 3 4; do for n in 16 32; do for pc in fast_diagonalization multigrid boomeramg; do run $case $p $n $pc; done; done; done
  for pc in fast_diagonalization multigrid; do run $case 3 64 $pc; done
done
