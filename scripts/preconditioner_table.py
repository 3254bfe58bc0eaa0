#!/usr/bin/python3
"""CG iterations and solve times of the tensor family's preconditioners, in h and in p.

Runs `knotwork run CASE --degree P --elements E --solver iterative --preconditioner NAME
--no-output --json` for multigrid, fast_diagonalization and boomeramg, and prints one
markdown table: iterations, and preconditioner setup + iterations in seconds (the solve),
"(no matrix)" where CG applied K without one ([solver] matrix = "auto" chooses).
Timings are of one run on a shared machine: compare within one sitting (docs/SOLVERS.md).

    scripts/preconditioner_table.py [--knotwork build/app/knotwork] [--quick]
"""
import argparse
import json
import subprocess
import sys

PRECONDITIONERS = ["multigrid", "fast_diagonalization", "boomeramg"]


def run(knotwork, case, p, e, pc):
    cmd = [knotwork, "run", case, "--degree", str(p), "--elements", str(e), "--solver", "iterative",
           "--preconditioner", pc, "--no-output", "--json", "-q"]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: {out.stderr.strip()}")
    d = json.loads(out.stdout)
    t = d["timings"]
    return d["dofs"], d["solver"]["iterations"], t["preconditioner"] + t["iterations"], d["h1_error"], d["solver"].get("matrix", "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--knotwork", default="build/app/knotwork")
    ap.add_argument("--quick", action="store_true", help="small sizes only (a check that the script runs)")
    a = ap.parse_args()
    rows = []
    in_h = [64, 256] if a.quick else [64, 256, 1024, 2048, 4096]
    in_p = [2, 3] if a.quick else [2, 3, 4, 5, 6]
    for case in ["cases/square_sinsin.toml", "cases/quarter_annulus.toml", "cases/lshape.toml"]:
        # (The L-shape has two spans: 4096 per span would be 33.6M dofs.)
        sizes = [e for e in in_h if not (case.endswith("lshape.toml") and e > 2048)]
        configs = [(2, e) for e in sizes] + [(p, 64 if a.quick else 256) for p in in_p if p != 2]
        for p, e in configs:
            cells = []
            for pc in PRECONDITIONERS:
                if pc == "boomeramg" and e > 1024:
                    cells.append("—")
                    continue
                dofs, it, sec, h1, matrix = run(a.knotwork, case, p, e, pc)
                cells.append(f"{it}, {sec:.3g}" + (" (no matrix)" if matrix == "matrix_free" else ""))
            rows.append(f"| `{case.split('/')[-1]}` | {p} | {e}² | {dofs:,} | " + " | ".join(cells) + " |")
            print(rows[-1], flush=True)
    print()
    print("| case | p | elements | dofs | " + " | ".join(f"{pc}: CG, s" for pc in PRECONDITIONERS) + " |")
    print("|---|---|---|---|" + "---|" * len(PRECONDITIONERS))
    print("\n".join(rows))


if __name__ == "__main__":
    main()
