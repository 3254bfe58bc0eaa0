#!/usr/bin/env python3
"""Which marking needs the fewest dofs per error, family by family (docs/ADAPTIVITY.md,
"Marking"): Doerfler and the maximum strategy, on cells and on functions, theta = 0.5, on the
L-shape (p = 2 and 3) up to MAX_DOFS. For each run: the dofs needed to bring the H1-seminorm
error below each level (interpolated in log-log between steps), the steps and the seconds.
Prints Markdown on stdout.

    PYTHONPATH=build/python /usr/bin/python3 scripts/marking_study.py [MAX_DOFS] > table.md   # ~10 minutes at 20000
"""
import argparse
import math
import time

import knotwork

_parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
_parser.add_argument("max_dofs", nargs="?", type=int, default=20000, help="each loop's --max-dofs (default 20000)")
MAX_DOFS = _parser.parse_args().max_dofs
CASES = {"knot segments": "cases/lshape_adaptive.toml", "PT-splines": "cases/lshape_adaptive_pt.toml",
         "THB-splines": "cases/lshape_adaptive_thb.toml", "LR B-splines": "cases/lshape_adaptive_lr.toml"}
MARKINGS = [("dorfler", "cells"), ("dorfler", "functions"), ("maximum", "cells"), ("maximum", "functions")]
LEVELS = {2: [1e-2, 1e-3, 1e-4], 3: [1e-2, 1e-3, 1e-4, 1e-5]}


def dofs_at(steps, level):
    """Dofs where the error first falls to `level`, interpolated in log-log; None if never."""
    for a, b in zip(steps, steps[1:]):
        if b["h1_seminorm_error"] <= level < a["h1_seminorm_error"]:
            t = math.log(a["h1_seminorm_error"] / level) / math.log(a["h1_seminorm_error"] / b["h1_seminorm_error"])
            return math.exp(math.log(a["dofs"]) + t * math.log(b["dofs"] / a["dofs"]))
    return None


def main():
    for p in (2, 3):
        levels = LEVELS[p]
        print(f"\n### L-shape, p = {p}, theta = 0.5, up to {MAX_DOFS} dofs\n")
        print("| family | strategy | marked | " + " | ".join(f"dofs at {l:.0e}" for l in levels)
              + " | steps | final dofs | seconds |")
        print("|---" * (6 + len(levels)) + "|")
        for family, case in CASES.items():
            for strategy, marking in MARKINGS:
                start = time.perf_counter()
                try:
                    steps = list(knotwork.adapt(case, steps=200, degree=p, max_dofs=MAX_DOFS, theta=0.5,
                                                strategy=strategy, marking=marking))
                except knotwork.InputError as e:
                    print(f"| {family} | {strategy} | {marking} | " + " | ".join("" for _ in levels)
                          + f" | | | stopped: {str(e).split(': ', 1)[-1][:90]} |")
                    continue
                seconds = time.perf_counter() - start
                cells = [f"{d:.0f}" if d else "" for d in (dofs_at(steps, l) for l in levels)]
                print(f"| {family} | {strategy} | {marking} | " + " | ".join(cells)
                      + f" | {len(steps)} | {steps[-1]['dofs']} | {seconds:.1f} |", flush=True)


if __name__ == "__main__":
    main()
