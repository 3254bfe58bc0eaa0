#!/usr/bin/python3
"""The assembled matrix on curved and multipatch cases, two binaries in one sitting.

Runs each case with the binary before and the binary after, alternating their order from
round to round, and prints the assembly phase (matrix, load, lifting) and the run without
output (min-max over the rounds), the assembly method, CG iterations and the errors. The
tables of docs/PERFORMANCE.md, "The matrix by sum factorization", come from it.

Example: bench/curved_assembly.py --before /tmp/old/build/app/knotwork --after build/app/knotwork
Timings on a shared machine are noisy: compare within one sitting, as ratios.
"""
import argparse
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CASES = os.path.join(ROOT, "cases")
CG_MULTIGRID = ["--solver", "iterative", "--preconditioner", "multigrid", "--matrix", "assembled"]
RUNS = [
    ("quarter annulus p=2 1024^2, CG+multigrid assembled", "quarter_annulus.toml", ["--degree", "2", "--elements", "1024"] + CG_MULTIGRID, 1),
    ("quarter annulus p=4 512^2, CG+multigrid assembled", "quarter_annulus.toml", ["--degree", "4", "--elements", "512"] + CG_MULTIGRID, 1),
    ("quarter annulus p=6 256^2, CG+multigrid assembled", "quarter_annulus.toml", ["--degree", "6", "--elements", "256"] + CG_MULTIGRID, 1),
    ("quarter annulus p=2 256^2, direct", "quarter_annulus.toml", ["--degree", "2", "--elements", "256", "--solver", "direct"], 1),
    ("plate with hole p=2 --elements 128, default", "multipatch_plate_with_hole.toml", ["--degree", "2", "--elements", "128"], 1),
    ("plus p=4 --elements 64, default", "multipatch_plus.toml", ["--degree", "4", "--elements", "64"], 1),
    ("quarter annulus p=2 1024^2, petsc, 2 processes", "quarter_annulus.toml", ["--degree", "2", "--elements", "1024", "--solver", "petsc"], 2),
]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--before", required=True, help="the knotwork binary before the change")
    parser.add_argument("--after", default=os.path.join(ROOT, "build", "app", "knotwork"), help="the binary after (default: build/app/knotwork)")
    parser.add_argument("--rounds", type=int, default=2, help="rounds per case, alternating the order (default 2)")
    args = parser.parse_args()
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMPI_MCA_btl="self,vader",
               OMPI_MCA_btl_vader_single_copy_mechanism="none")
    binaries = {"before": args.before, "after": args.after}
    for name, case, extra, processes in RUNS:
        results = {"before": [], "after": []}
        for r in range(args.rounds):
            for which in (["before", "after"] if r % 2 == 0 else ["after", "before"]):
                launch = ["mpirun", "-n", str(processes), "--oversubscribe"] if processes > 1 else []
                cmd = launch + [binaries[which], "run", "-q", "--no-output", "--json", os.path.join(CASES, case)] + extra
                out = subprocess.run(cmd, capture_output=True, text=True, env=env)
                if out.returncode != 0:
                    sys.exit(f"{which}: {' '.join(cmd)} failed: {out.stderr.strip()}")
                d = json.loads(out.stdout)
                results[which].append((d["timings"]["assembly"], d["timings"]["total_without_output"],
                                       d["solver"].get("assembly_method"), d["solver"].get("iterations"),
                                       d["l2_error"], d["h1_seminorm_error"]))
        print(name)
        for which in ("before", "after"):
            rows = results[which]
            a = [x[0] for x in rows]
            t = [x[1] for x in rows]
            print(f"  {which:6s} assembly {min(a):.3f}-{max(a):.3f} s, run {min(t):.3f}-{max(t):.3f} s, {rows[0][2]}, "
                  f"iterations {rows[0][3]}, L2 {rows[0][4]:.7e}, H1 {rows[0][5]:.7e}")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
