#!/usr/bin/python3
"""CG iterations and solve times of the tensor family's preconditioners, in h and in p.

Runs `knotwork run CASE --degree P --elements E --solver iterative --preconditioner NAME
--no-output --json` for multigrid, fast_diagonalization and boomeramg, and prints one
markdown table: iterations, and preconditioner setup + iterations in seconds (the solve),
"(no matrix)" where CG applied K without one ([solver] matrix = "auto" chooses).
With --multipatch, the shipped cases of several patches (plus, ring, L-shape) and of seven glued
cubes (Fichera), elements per patch side, with a last column for CHOLMOD (`--solver direct`:
analysis + factorization + solve).
Timings are of one run on a shared machine: compare within one sitting (docs/SOLVERS.md).

    scripts/preconditioner_table.py [--knotwork build/app/knotwork] [--quick] [--multipatch]
"""
import argparse
import json
import subprocess
import sys

PRECONDITIONERS = ["multigrid", "fast_diagonalization", "boomeramg"]


def run(knotwork, case, p, e, pc):
    solver = ["--solver", "direct"] if pc == "direct" else ["--solver", "iterative", "--preconditioner", pc]
    cmd = [knotwork, "run", case, "--degree", str(p), "--elements", str(e)] + solver + ["--no-output", "--json", "-q"]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: {out.stderr.strip()}")
    d = json.loads(out.stdout)
    t = d["timings"]
    if pc == "direct":
        return d["dofs"], "—", t["analysis"] + t["factorization"] + t["solve"], d["h1_error"], ""
    return d["dofs"], d["solver"]["iterations"], t["preconditioner"] + t["iterations"], d["h1_error"], d["solver"].get("matrix", "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--knotwork", default="build/app/knotwork")
    ap.add_argument("--quick", action="store_true", help="small sizes only (a check that the script runs)")
    ap.add_argument("--multipatch", action="store_true", help="the shipped cases of several patches, and CHOLMOD")
    a = ap.parse_args()
    rows = []
    preconditioners = PRECONDITIONERS + (["direct"] if a.multipatch else [])
    if a.multipatch:
        in_h = [16, 64] if a.quick else [16, 32, 64, 128, 256, 512]
        in_p = [2, 3] if a.quick else [2, 3, 4, 5, 6]
        cases = ["cases/multipatch_plus.toml", "cases/multipatch_ring.toml", "cases/multipatch_lshape.toml",
                 "cases/fichera_patches.toml"]
        p_size = 16 if a.quick else 64
    else:
        in_h = [64, 256] if a.quick else [64, 256, 1024, 2048, 4096]
        in_p = [2, 3] if a.quick else [2, 3, 4, 5, 6]
        cases = ["cases/square_sinsin.toml", "cases/quarter_annulus.toml", "cases/lshape.toml"]
        p_size = 64 if a.quick else 256
    for case in cases:
        # (The L-shape patch has two spans: 4096 per span would be 33.6M dofs.)
        sizes = [e for e in in_h if not (case.endswith("/lshape.toml") and e > 2048)]
        degrees, size = in_p, p_size
        if case.endswith("fichera_patches.toml"):  # seven glued cubes: elements per cube side
            sizes, degrees, size = ([4, 8] if a.quick else [8, 16, 32]), ([2, 3] if a.quick else [2, 3, 4]), (8 if a.quick else 16)
        configs = [(2, e) for e in sizes] + [(p, size) for p in degrees if p != 2]
        for p, e in configs:
            cells = []
            for pc in preconditioners:
                # BoomerAMG beyond 1M dofs takes minutes, and the per-patch fast diagonalization
                # (no coarse space) needs more than CG's 1 000 iterations on the plus beyond 32
                # elements per side: not run.
                volumes = case.endswith("fichera_patches.toml")  # (no per-volume fast diagonalization)
                if (pc == "boomeramg" and e > (256 if a.multipatch else 1024)) or (
                        a.multipatch and pc == "fast_diagonalization" and (e > 32 or p > 2 or volumes)):
                    cells.append("—")
                    continue
                dofs, it, sec, h1, matrix = run(a.knotwork, case, p, e, pc)
                cells.append(f"{it}, {sec:.3g}" if pc != "direct" else f"{sec:.3g}")
                if matrix == "matrix_free":
                    cells[-1] += " (no matrix)"
            rows.append(f"| `{case.split('/')[-1]}` | {p} | {e}{'' if a.multipatch else '²'} | {dofs:,} | " + " | ".join(cells) + " |")
            print(rows[-1], flush=True)
    print()
    print("| case | p | elements | dofs | " +
          " | ".join(f"{pc}: CG, s" if pc != "direct" else "CHOLMOD, s" for pc in preconditioners) + " |")
    print("|---|---|---|---|" + "---|" * len(preconditioners))
    print("\n".join(rows))


if __name__ == "__main__":
    main()
