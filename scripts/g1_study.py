#!/usr/bin/env python3
"""The G1 convergence studies (a dated record in docs/records/, summarized in docs/G1_POISSON.md, "Results"), regenerated: every shipped G1 case with
its default (analysis-suitable) gluing data over 4 levels, the earlier data for comparison,
and on every planar case the C0 multipatch space of the same degree on the same mesh, compared
with the G1 space at equal dofs (the H1 errors interpolated log-log in the dofs), with the
default Dirichlet method of planar G1 cases (Nitsche's) and with the L2 projection. Prints
Markdown on stdout.

    scripts/g1_study.py [KNOTWORK]        # default build/app/knotwork; about 2 minutes here
"""
import argparse
import json
import math
import os
import re
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
_parser.add_argument("knotwork", nargs="?", default=os.path.join(ROOT, "build", "app", "knotwork"),
                     help="the knotwork binary (default: build/app/knotwork)")
KNOTWORK = _parser.parse_args().knotwork
PLANAR = ["g1_three_quads", "g1_pentagon", "g1_mixed_valences", "g1_valences_6_8", "g1_lshape"]
SURFACES = ["g1_sphere_xy", "g1_sphere_harmonic", "g1_sphere_dodecahedron", "g1_sphere_prism", "g1_sphere_antiprism",
            "g1_torus"]
EARLIER = {"g1_three_quads": 'gluing = "symmetric_c1"', "g1_mixed_valences": 'gluing = "regular_fans"',
           "g1_sphere_xy": 'gluing = "symmetric"', "g1_sphere_harmonic": 'gluing = "symmetric"',
           "g1_sphere_prism": 'gluing = "symmetric_c1"'}
# Levels of the earlier data where 4 cannot be built (none since the floating-point null vectors
# are refined: the prism sphere's symmetric_c1 basis was numerically dependent at 3 subdivisions).
EARLIER_LEVELS = {}


def variant(case, scratch, space_lines, problem_lines=""):
    """The case with its mesh path made absolute, `space_lines` replacing its gluing and
    `problem_lines` added to its [problem]."""
    text = open(os.path.join(ROOT, "cases", case + ".toml")).read()
    text = re.sub(r'mesh = "meshes/', 'mesh = "' + os.path.join(ROOT, "cases", "meshes") + "/", text)
    text = re.sub(r'^gluing = .*$', "", text, flags=re.M)
    text = text.replace("[space]\n", "[space]\n" + space_lines + "\n", 1)
    text = text.replace("[problem]\n", "[problem]\n" + problem_lines + "\n", 1)
    path = os.path.join(scratch, f"{case}_{abs(hash(space_lines + problem_lines))}.toml")
    open(path, "w").write(text)
    return path


def converge(path, scratch, levels=4):
    done = subprocess.run([KNOTWORK, "converge", path, "--levels", str(levels), "--json", "-q", "--out",
                           os.path.join(scratch, "out")], capture_output=True, text=True, check=True)
    return json.loads(done.stdout)["levels"]


def table(title, rows):
    print(f"\n**{title}**\n")
    print("| level | faces | dofs | h | L2 error | rate | H1-seminorm error | rate | C1 jump |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        rate = lambda k: "–" if r[k] is None else f"{r[k]:.2f}"
        print(f"| {r['level']} | {r['faces']} | {r['dofs']} | {r['h']:.4f} | {r['l2_error']:.3e} | {rate('l2_rate')} | "
              f"{r['h1_seminorm_error']:.3e} | {rate('h1_rate')} | {r['c1_jump']:.1e} |")


def at_dofs(rows, n):
    """log-log interpolation of the H1-seminorm error in the dofs (extrapolated at the ends)."""
    pts = [(math.log(r["dofs"]), math.log(r["h1_seminorm_error"])) for r in rows]
    x = math.log(n)
    i = max(0, min(len(pts) - 2, sum(1 for p in pts if p[0] <= x) - 1))
    (x0, y0), (x1, y1) = pts[i], pts[i + 1]
    return math.exp(y0 + (y1 - y0) * (x - x0) / (x1 - x0)), not (pts[0][0] <= x <= pts[-1][0])


def main():
    largest_jump = 0
    with tempfile.TemporaryDirectory() as scratch:
        for case in PLANAR + SURFACES:
            rows = converge(variant(case, scratch, 'gluing = "analysis_suitable"'), scratch)
            largest_jump = max([largest_jump] + [r["c1_jump"] for r in rows])
            table(f"{case}: analysis_suitable (the default)", rows)
            if case in EARLIER:
                table(f"{case}: {EARLIER[case]} (earlier)",
                      converge(variant(case, scratch, EARLIER[case]), scratch, EARLIER_LEVELS.get(case, 4)))
            if case in PLANAR:
                c0 = converge(variant(case, scratch, 'smoothness = "c0"'), scratch)
                print(f"\n{case}, H1-seminorm error at equal dofs (C0: the same degree and mesh; both with "
                      "Nitsche's method, the default):\n")
                print("| dofs (G1) | G1 | C0 at those dofs | C0 / G1 |")
                print("|---|---|---|---|")
                for r in rows:
                    e, outside = at_dofs(c0, r["dofs"])
                    print(f"| {r['dofs']} | {r['h1_seminorm_error']:.3e} | {e:.3e}{' (extrapolated)' if outside else ''} | "
                          f"{e / r['h1_seminorm_error']:.2f} |")
                print("\nThe other way round, at the C0 space's dofs (G1 interpolated): C0 / G1 = " + ", ".join(
                    f"{c['h1_seminorm_error'] / g:.3f}{' (extrapolated)' if outside else ''} at {c['dofs']}"
                    for c in c0 for g, outside in [at_dofs(rows, c["dofs"])]) + ".")
                projection = 'dirichlet_method = "projection"'
                g1p = converge(variant(case, scratch, 'gluing = "analysis_suitable"', projection), scratch)
                c0p = converge(variant(case, scratch, 'smoothness = "c0"', projection), scratch)
                print("\nWith the L2-projected Dirichlet data (`dirichlet_method = \"projection\"`, both spaces): "
                      "G1 H1 error " + ", ".join(f"{r['h1_seminorm_error']:.3e}" for r in g1p) + "; C0 / G1 at G1's dofs " +
                      ", ".join(f"{at_dofs(c0p, r['dofs'])[0] / r['h1_seminorm_error']:.2f}" for r in g1p) + ".")
    print(f"\nLargest C1 jump over every level of every case: {largest_jump:.1e}")


if __name__ == "__main__":
    main()
