#!/usr/bin/env python3
"""What an adaptive loop costs against one uniform solve of about its final size
(docs/ADAPTIVITY.md, "What a loop costs"). For each family and problem: the wall time of
`knotwork adapt CASE --degree P --steps 200 --max-dofs N --no-output`, the same with the
default ParaView output, the loop's phases (the sums of adapt --json's per-step seconds), and
the wall time of `knotwork run` on a uniform tensor-product space of the same geometry and
exact solution with about the loop's final dofs (the default solver: fast diagonalization).
Each pair runs back to back, so that ratios are of one sitting. Prints Markdown on stdout.

    scripts/adaptive_cost.py [KNOTWORK] [--quick] [--family=SUFFIX] > table.md   # ~15 minutes here (PT: several)

--quick leaves PT-splines out; --family=thb (the case files' suffix, "" for knot segments) runs
one family only.
"""
import argparse
import json
import os
import subprocess
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
_parser.add_argument("knotwork", nargs="?", default=os.path.join(ROOT, "build", "app", "knotwork"),
                     help="the knotwork binary (default: build/app/knotwork)")
_parser.add_argument("--quick", action="store_true", help="leave PT-splines out")
_parser.add_argument("--family", default=None, metavar="SUFFIX",
                     help='one family only, by its case files\' suffix: thb, lr, pt, or "" for knot segments')
_args = _parser.parse_args()
KNOTWORK = _args.knotwork
QUICK = _args.quick
ONLY = _args.family
LSHAPE_U = "(x^2+y^2)^(1/3)*sin(2/3*(atan2(-y,-x)+pi))"
LAYER_U = "atan(60*(sqrt((x+0.1)^2+(y+0.1)^2)-0.7))"
# (problem, degree, max dofs, {family: case}, uniform geometry, exact solution)
FAMILIES = {"knot segments": "", "THB-splines": "_thb", "LR B-splines": "_lr", "PT-splines": "_pt"}
RUNS = [("L-shape", 3, 50000, "lshape_adaptive", "lshape", LSHAPE_U),
        ("L-shape", 2, 50000, "lshape_adaptive", "lshape", LSHAPE_U),
        ("interior layer", 2, 50000, "interior_layer", "rectangle", LAYER_U)]


def wall(args):
    start = time.perf_counter()
    out = subprocess.run([KNOTWORK] + args, check=True, capture_output=True, text=True).stdout
    return time.perf_counter() - start, out


def uniform_case(directory, geometry, exact, p, dofs):
    """A tensor case with about `dofs` functions: L-shape (2E+2p-1)(E+p), square (E+p)^2."""
    elements = 1
    count = (lambda e: (2 * e + 2 * p - 1) * (e + p)) if geometry == "lshape" else (lambda e: (e + p) ** 2)
    while count(elements + 1) <= dofs or abs(count(elements + 1) - dofs) < abs(count(elements) - dofs):
        elements += 1
    path = os.path.join(directory, f"uniform_{geometry}_{p}.toml")
    extra = 'corners = [[0, 0], [1, 1]]\n' if geometry == "rectangle" else ""
    with open(path, "w") as f:
        f.write(f'[geometry]\ntype = "{geometry}"\n{extra}[space]\ndegree = {p}\nelements = {elements}\n'
                f'[problem]\nexact = "{exact}"\n')
    return path, count(elements)


def main():
    print("| problem | p | family | steps | final dofs | loop s | with output s | output share | "
          "solve s | estimate s | refine s | uniform dofs | uniform s | loop / uniform |")
    print("|---" * 14 + "|")
    with tempfile.TemporaryDirectory() as tmp:
        for problem, p, max_dofs, stem, geometry, exact in RUNS:
            for family, suffix in FAMILIES.items():
                if QUICK and family == "PT-splines":
                    continue
                if ONLY is not None and suffix != ("_" + ONLY if ONLY else ""):
                    continue
                case = os.path.join(ROOT, "cases", stem + suffix + ".toml")
                common = [case, "--degree", str(p), "--steps", "200", "--max-dofs", str(max_dofs), "-q"]
                seconds, out = wall(["adapt"] + common + ["--no-output", "--json"])
                steps = json.loads(out)["steps"]
                with_output, _ = wall(["adapt"] + common + ["--out", os.path.join(tmp, "out")])
                phases = {k: sum(s[k] for s in steps) for k in ("seconds_solve", "seconds_estimate", "seconds_refine")}
                path, dofs = uniform_case(tmp, geometry, exact, p, steps[-1]["dofs"])
                uniform, _ = wall(["run", path, "--no-output", "-q"])
                print(f"| {problem} | {p} | {family} | {len(steps)} | {steps[-1]['dofs']} | {seconds:.2f} | "
                      f"{with_output:.2f} | {with_output / seconds - 1:+.0%} | {phases['seconds_solve']:.2f} | "
                      f"{phases['seconds_estimate']:.2f} | {phases['seconds_refine']:.2f} | {dofs} | {uniform:.2f} | "
                      f"{seconds / uniform:.1f} |", flush=True)


if __name__ == "__main__":
    main()
