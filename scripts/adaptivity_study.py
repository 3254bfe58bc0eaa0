#!/usr/bin/env python3
"""The adaptivity study (a dated record in docs/records/, summarized in docs/ADAPTIVITY.md), regenerated: the four local refinements (knot segments, PT-splines,
THB-splines, LR B-splines) behind the same residual estimator, Doerfler marking and direct
solve, on the L-shape (p = 2, 3) and the interior layer (p = 2): DOFs against the H1 error,
the dofs each family needs per error level, time per step against a uniform solve of the same
size, and for LR whether any step was dependent; then the choice of the THB grading and of the
LR refinement strategy. Prints Markdown on stdout and writes docs/adaptivity_*.png.

    scripts/adaptivity_study.py [KNOTWORK] > docs/records/adaptivity-$(date +%F).md   # about 30 minutes here
"""
import argparse
import json
import math
import os
import platform
import re
import subprocess
import tempfile
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
_parser.add_argument("knotwork", nargs="?", default=os.path.join(ROOT, "build", "app", "knotwork"),
                     help="the knotwork binary (default: build/app/knotwork)")
KNOTWORK = _parser.parse_args().knotwork
FAMILIES = ["knot_segments", "pt", "thb", "lr"]
LABEL = {"knot_segments": "knot segments", "pt": "PT-splines", "thb": "THB-splines", "lr": "LR B-splines"}
# (title, file stem, case per family, degree, max dofs per family, uniform geometry extent)
PROBLEMS = [
    ("L-shape, u = r^(2/3) sin(2 theta/3), p = 2", "lshape_p2",
     {"knot_segments": "lshape_adaptive", "pt": "lshape_adaptive_pt", "thb": "lshape_adaptive_thb",
      "lr": "lshape_adaptive_lr"}, 2, {"knot_segments": 50000, "pt": 50000, "thb": 50000, "lr": 50000}),
    ("L-shape, p = 3", "lshape_p3",
     {"knot_segments": "lshape_adaptive", "pt": "lshape_adaptive_pt", "thb": "lshape_adaptive_thb",
      "lr": "lshape_adaptive_lr"}, 3, {"knot_segments": 50000, "pt": 50000, "thb": 50000, "lr": 50000}),
    ("Interior layer, u = atan(60 (|x - c| - 0.7)), p = 2", "interior_layer_p2",
     {"knot_segments": "interior_layer", "pt": "interior_layer_pt", "thb": "interior_layer_thb",
      "lr": "interior_layer_lr"}, 2, {"knot_segments": 50000, "pt": 50000, "thb": 50000, "lr": 50000}),
]


DEFAULTS = """
The defaults follow. THB: class 2, which the convergence theory of adaptive THB methods
assumes; the grading changes the dofs for a given error by a few percent either way here.
LR: structured mesh. Minimal span reaches a smaller error at p = 2, but at p = 3 it produced
linearly dependent B-splines (refused above), and full span falls below the optimal rate at
both degrees. Marking: cells. Marking functions gave THB-splines a larger error at about the
same dofs (2.5e-5 against 1.4e-5 at p = 2, 3.9e-7 against 2.2e-7 at p = 3); for LR B-splines
it was slightly better (3.2e-5 at 51 673 dofs against 3.5e-5 at 50 143 at p = 2; 5.7e-7 at
59 336 against 5.9e-7 at 66 151 at p = 3), which makes it worth `--marking functions` there.
"""


def run_json(args):
    done = subprocess.run([KNOTWORK] + args + ["--json", "-q"], capture_output=True, text=True)
    if done.returncode != 0:
        return {"error": done.stderr.strip().splitlines()[-1] if done.stderr.strip() else "failed"}
    return json.loads(done.stdout)


def adapt(case_path, degree, max_dofs):
    t = time.time()
    out = run_json(["adapt", case_path, "--degree", str(degree), "--steps", "200", "--max-dofs", str(max_dofs),
                    "--no-output"])
    out["wall"] = time.time() - t
    return out


def uniform_solve(thb_case, degree, dofs, lshape):
    """A uniform tensor-product B-spline space of about `dofs` functions through the same
    pipeline (family thb before any refinement, direct solve): its `run` time."""
    if lshape:  # 2 knot spans along u with a C0 fold: (2E + 2p - 1)(E + p) functions
        e = max(1, round((-(4 * degree - 1) + math.sqrt((4 * degree - 1) ** 2 - 8 * (
            (2 * degree - 1) * degree - dofs))) / 4))
    else:  # one knot span: (E + p)^2
        e = max(1, round(math.sqrt(dofs) - degree))
    r = run_json(["run", thb_case, "--degree", str(degree), "--elements", str(e), "--no-output"])
    return r["dofs"], r["timings"]["total_without_output"]


def loglog_dofs_at(steps, error):
    """Dofs at which the H1 error (log-log interpolated between steps) first reaches `error`."""
    for a, b in zip(steps, steps[1:]):
        ea, eb = a["h1_seminorm_error"], b["h1_seminorm_error"]
        if ea >= error >= eb and ea > eb:
            s = (math.log(ea) - math.log(error)) / (math.log(ea) - math.log(eb))
            return math.exp(math.log(a["dofs"]) + s * (math.log(b["dofs"]) - math.log(a["dofs"])))
    if steps and steps[0]["h1_seminorm_error"] <= error:
        return float(steps[0]["dofs"])
    return None


def loglog_error_at(steps, dofs):
    """H1 error at `dofs`, log-log interpolated between the steps (None outside them)."""
    for a, b in zip(steps, steps[1:]):
        if a["dofs"] <= dofs <= b["dofs"] and b["dofs"] > a["dofs"]:
            t = (math.log(dofs) - math.log(a["dofs"])) / (math.log(b["dofs"]) - math.log(a["dofs"]))
            return math.exp((1 - t) * math.log(a["h1_seminorm_error"]) + t * math.log(b["h1_seminorm_error"]))
    return None


def fitted_rate(steps):
    tail = [s for s in steps[len(steps) // 2:] if s["h1_seminorm_error"] > 0]
    if len(tail) < 2:
        return float("nan")
    xs = [math.log(s["dofs"]) for s in tail]
    ys = [-math.log(s["h1_seminorm_error"]) for s in tail]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def variant(stem, scratch, replace, section="adapt"):
    text = open(os.path.join(ROOT, "cases", stem + ".toml")).read()
    for key, value in replace.items():
        if re.search(r"^" + key + r" = ", text, flags=re.M):
            text = re.sub(r"^" + key + r" = .*$", f"{key} = {value}", text, flags=re.M)
        else:  # keys the case does not set go into `section`
            assert f"[{section}]\n" in text, (stem, section)
            text = text.replace(f"[{section}]\n", f"[{section}]\n{key} = {value}\n", 1)
    path = os.path.join(scratch, f"{stem}_{abs(hash(str(replace)))}.toml")
    open(path, "w").write(text)
    return path


def main():
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    print("# Adaptive refinement: four families on equal terms\n")
    print(f"Generated by `scripts/adaptivity_study.py` ({time.strftime('%Y-%m-%d', time.gmtime())}, knotwork "
          f"{commit}, {os.cpu_count()} cores, {platform.machine()}; every run one after the other).\n")
    print("""`knotwork adapt CASE` repeats: solve (direct, CHOLMOD); residual indicator per cell
eta_K^2 = h_K^2 ||f + Laplace u_h||^2_K + 1/2 sum_E h_E ||[grad u_h]||^2_E (plus, on boundary
sides, h_E ||g - du_h/dn||^2_E where Neumann and h_E^-1 ||g - u_h||^2_E where Dirichlet by
Nitsche's method; docs/MATH.md §4); Doerfler marking
(the fewest cells holding theta = 0.5 of the sum of eta_K^2); the family refines the marked
cells. Everything but the last step is the same code for every family. What a family does with
a marked cell:

| family | `[space] family` | refinement of a marked cell |
|---|---|---|
| knot segments | `knot_segments` | halved by a knot segment across its longer side, extended where Weller's semi-regularity needs it (`[space] extension = "galloping"`) |
| PT-splines | `pt` | halved the same way; the PT-splines of the new T-mesh built and certified from scratch |
| THB-splines | `thb` | halved in both directions (a quadtree); graded to stay T-admissible of class 2 |
| LR B-splines | `lr` | every B-spline living on it refined by halving all its knot intervals (structured mesh); meshlines reaching the boundary extended to keep traces independent |

"rate" is the least-squares slope of -log(H1 error) against log(dofs) over the last half of
the steps (optimal: p/2). "uniform s" is the time of `knotwork run` on a uniform tensor-product
B-spline space of the same degree and about the same number of dofs through the same pipeline
(family thb before any refinement: the same assembly, direct solve and error norms), measured
in the same sitting; "ratio" = whole adaptive run / that uniform solve. PT-splines build and
certify the whole space every step (its dimension by smoothing cofactors, independence by
peeling the LR B-splines; docs/PT_SPLINES.md), which their ratio shows. "marked / extended":
cells marked over the run, and what the
family added beyond them (knot segments: segments lengthened to stay semi-regular; THB: cells
halved by the grading; LR: meshlines lengthened at the boundary; PT: none).
""")
    scratch = tempfile.mkdtemp()
    summary = []
    findings = []  # (problem, family, dofs against THB, error level)
    extensions = []  # (problem, family, cells marked, what the family added)
    for title, stem, cases, degree, caps in PROBLEMS:
        results = {}
        for fam in FAMILIES:
            path = os.path.join(ROOT, "cases", cases[fam] + ".toml")
            results[fam] = adapt(path, degree, caps[fam])
        # Uniform refinement of the same problem (THB before any refinement: tensor-product B-splines).
        uniform = run_json(["converge", os.path.join(ROOT, "cases", cases["thb"] + ".toml"), "--degree", str(degree),
                            "--levels", "7", "--out", os.path.join(scratch, stem + "_uniform")])
        uniform_steps = [{"dofs": l["dofs"], "h1_seminorm_error": l["h1_seminorm_error"]} for l in uniform["levels"]]
        print(f"## {title}\n")
        print("| family | command | steps | dofs | H1 error | rate | marked / extended | seconds | last step s | "
              "uniform s (dofs) | ratio |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        for fam in FAMILIES:
            r = results[fam]
            cmd = f"`knotwork adapt cases/{cases[fam]}.toml --degree {degree} --steps 200 --max-dofs {caps[fam]}`"
            if "error" in r:
                print(f"| {LABEL[fam]} | {cmd} | failed: {r['error']} |||||||")
                continue
            steps = r["steps"]
            last = steps[-1]
            total = sum(s["seconds"] for s in steps)
            udofs, usec = uniform_solve(os.path.join(ROOT, "cases", cases["thb"] + ".toml"), degree, last["dofs"],
                                        stem.startswith("lshape"))
            marked = sum(s["marked"] for s in steps)
            extended = sum(s["extended_segments"] for s in steps)
            extensions.append((title, fam, marked, extended))
            print(f"| {LABEL[fam]} | {cmd} | {len(steps)} | {last['dofs']} | {last['h1_seminorm_error']:.3e} | "
                  f"{fitted_rate(steps):.2f} | {marked} / {extended} | {total:.1f} | {last['seconds']:.2f} | "
                  f"{usec:.2f} ({udofs}) | {total / usec:.0f} |")
            summary.append((title, fam, last["dofs"], fitted_rate(steps), total, usec))
        # Dofs per error level.
        finals = [results[f]["steps"][-1]["h1_seminorm_error"] for f in FAMILIES if "steps" in results[f]]
        firsts = [results[f]["steps"][0]["h1_seminorm_error"] for f in FAMILIES if "steps" in results[f]]
        hi, lo = min(firsts), min(finals)
        levels = [m * 10.0 ** k for k in range(math.floor(math.log10(hi)), math.floor(math.log10(lo)) - 1, -1)
                  for m in (3, 1) if lo <= m * 10.0 ** k < hi]
        print("\nDofs needed to reach an H1 error (log-log interpolated between steps; in brackets: against "
              "THB):\n")
        print("| H1 error | " + " | ".join(LABEL[f] for f in FAMILIES) + " | uniform |")
        print("|---|" + "---|" * (len(FAMILIES) + 1))
        for level in levels:
            thb = loglog_dofs_at(results["thb"].get("steps", []), level)
            cells = []
            for fam in FAMILIES:
                d = loglog_dofs_at(results[fam].get("steps", []), level)
                if d is None:
                    cells.append("–")
                elif fam == "thb" or thb is None:
                    cells.append(f"{d:.0f}")
                else:
                    cells.append(f"{d:.0f} ({d / thb:.2f})")
            for fam in FAMILIES:
                d = loglog_dofs_at(results[fam].get("steps", []), level)
                if fam != "thb" and d is not None and thb is not None:
                    findings.append((title, fam, d / thb, level))
            u = loglog_dofs_at(uniform_steps, level)
            cells.append("–" if u is None else f"{u:.0f}" + ("" if thb is None else f" ({u / thb:.1f})"))
            print(f"| {level:.0e} | " + " | ".join(cells) + " |")
        print(f"\nUniform: `knotwork converge cases/{cases['thb']}.toml --degree {degree} --levels 7` (tensor-product "
              f"B-splines, elements doubled per level): {', '.join(str(l['dofs']) for l in uniform_steps)} dofs, "
              f"H1 error {uniform_steps[-1]['h1_seminorm_error']:.2e} at the finest.")
        lr = results["lr"].get("steps", [])
        print(f"\nLR: every one of the {len(lr)} spaces was checked for linear dependence "
              f"(overloaded B-splines, then the rank of each group): "
              f"{'none dependent' if 'steps' in results['lr'] else 'the run stopped'}.\n")
        # The figure.
        plt.figure(figsize=(6, 4.5))
        for fam in FAMILIES:
            if "steps" in results[fam]:
                s = results[fam]["steps"]
                plt.loglog([x["dofs"] for x in s], [x["h1_seminorm_error"] for x in s], "o-", ms=3, label=LABEL[fam])
        d0 = results["thb"]["steps"][0]["dofs"]
        e0 = results["thb"]["steps"][0]["h1_seminorm_error"]
        plt.loglog([x["dofs"] for x in uniform_steps], [x["h1_seminorm_error"] for x in uniform_steps], "s:", ms=3,
                   color="gray", label="uniform")
        xs = [d0, results["thb"]["steps"][-1]["dofs"]]
        plt.loglog(xs, [e0 * (x / d0) ** (-degree / 2) for x in xs], "k--", lw=0.8, label=f"N^(-{degree}/2)")
        plt.xlabel("dofs")
        plt.ylabel("H1-seminorm error")
        plt.title(title, fontsize=9)
        plt.legend(fontsize=8)
        plt.grid(True, which="both", lw=0.3)
        plt.tight_layout()
        png = f"adaptivity_{stem}.png"
        plt.savefig(os.path.join(ROOT, "docs", png), dpi=110)
        plt.close()
        print(f"![{title}](../{png})\n")  # the record lives in docs/records/
        # Per-step tables.
        for fam in FAMILIES:
            if "steps" not in results[fam]:
                continue
            print(f"<details><summary>{LABEL[fam]}: every step</summary>\n")
            print("| step | dofs | cells | H1 error | seconds (solve / estimate / refine) |")
            print("|---|---|---|---|---|")
            for s in results[fam]["steps"]:
                print(f"| {s['step']} | {s['dofs']} | {s['cells']} | {s['h1_seminorm_error']:.3e} | {s['seconds']:.2f} "
                      f"({s['seconds_solve']:.2f} / {s['seconds_estimate']:.2f} / {s['seconds_refine']:.2f}) |")
            print("\n</details>\n")

    # What the tables say, computed from them.
    print("## Against THB, error level by error level\n")
    print("The issue this study answers asks that knot segments and PT-splines need no more dofs than THB "
          "(the usual choice) at every error level, and that where one does, the reason be given.\n")
    print("| problem | family | most dofs against THB | at H1 error | levels above THB / compared |")
    print("|---|---|---|---|---|")
    for title, _, _, _, _ in PROBLEMS:
        for fam in ("knot_segments", "pt", "lr"):
            rows = [f for f in findings if f[0] == title and f[1] == fam]
            if not rows:
                continue
            worst = max(rows, key=lambda f: f[2])
            above = sum(1 for f in rows if f[2] > 1.0)
            print(f"| {title.split(',')[0]}{', p = 3' if 'p = 3' in title else ''} | {LABEL[fam]} | {worst[2]:.2f} | "
                  f"{worst[3]:.0e} | {above} / {len(rows)} |")
    ext = [(t, f, m, e) for (t, f, m, e) in extensions if f == "knot_segments"]
    lr_ratios = [f[2] for f in findings if f[1] == "lr"]
    print("\nWhy. **PT-splines** need fewer dofs than THB at all but the first levels (the table above): a marked "
          "cell is "
          "halved in one direction (two children, where THB makes four), so a marking adds about half the "
          "functions, and the PT space is the whole spline space of its T-mesh (its dimension is the "
          "brute-force count, docs/PT_SPLINES.md), where THB-splines span a subspace of the splines on theirs. "
          "**Knot segments** halve cells the same way but need more dofs than THB from the middle levels on: "
          "to stay semi-regular, Weller's collections lengthen segments beyond the marked cell ("
          + "; ".join(f"{t.split(',')[0]}{', p = 3' if 'p = 3' in t else ''}: {e} extensions for {m} marked cells"
                      for (t, f, m, e) in ext)
          + "), and every lengthened segment adds B-splines along cells the estimator did not mark; "
          "PT-splines on the same kind of T-mesh add none. **LR B-splines** (structured mesh) need "
          f"{min(lr_ratios):.1f}-{max(lr_ratios):.1f} times THB's dofs: a marked cell refines every B-spline living "
          "on it over its whole support, "
          "(p+1)^2 cells around it. Minimal-span LR refinement adds fewer (see below) but produced linearly "
          "dependent B-splines at p = 3.\n")

    # The defaults, by measurement.
    print("## Choosing the defaults\n")
    print("Same commands on the L-shape with one key changed (a copy of the case file), up to 50 000 dofs. "
          "`[adapt] marking = \"functions\"` (`--marking functions`) marks functions by Doerfler (indicator: the "
          "sum of eta_K^2 over the cells a function lives on) and refines the cells of their supports, as "
          "hierarchical codes do.\n")
    print("| family, variant | p | dofs | H1 error | rate | seconds | note |")
    print("|---|---|---|---|---|---|---|")
    for degree in (2, 3):
        for fam, key, values in (("thb", "admissibility", ["0", "2", "3"]),
                                 ("lr", "refinement", ['"structured_mesh"', '"minimal_span"', '"full_span"']),
                                 ("thb", "marking", ['"functions"']), ("lr", "marking", ['"functions"'])):
            stem = "lshape_adaptive_" + fam
            for v in values:
                path = variant(stem, scratch, {key: v})
                r = adapt(path, degree, 50000)
                if "error" in r:
                    why = r["error"].replace("knotwork: error: ", "").replace(path, f"(a copy of {stem}.toml)")
                    print(f"| {fam}, {key} = {v} | {degree} | | | | | stopped: {why} |")
                    continue
                s = r["steps"]
                print(f"| {fam}, {key} = {v} | {degree} | {s[-1]['dofs']} | {s[-1]['h1_seminorm_error']:.3e} | "
                      f"{fitted_rate(s):.2f} | {sum(x['seconds'] for x in s):.1f} | |")
    print(DEFAULTS)

    # Knot segments: the order in which extensions are tried.
    print("Knot segments, `[space] extension` (same commands on `lshape_adaptive.toml`, up to 20 000 dofs, "
          "\"minimal\" only to 5 000: it tries extensions by increasing length, and at p = 3 a run to 20 000 "
          "had not finished after 12 minutes). Every order ends in a checked semi-regular collection; they differ "
          "in which extension is found and how many are tried.\n")
    print("| extension | p | steps | dofs | H1 error | error against directed at equal dofs | seconds | refinement s |")
    print("|---|---|---|---|---|---|---|---|")
    for degree in (2, 3):
        runs = {}
        for v in ("galloping", "directed", "minimal"):
            runs[v] = adapt(variant("lshape_adaptive", scratch, {"extension": f'"{v}"'}, "space"), degree,
                            5000 if v == "minimal" else 20000)
        for v, r in runs.items():
            if "error" in r:
                print(f"| {v} | {degree} | | | | | | stopped: {r['error']} |")
                continue
            s = r["steps"]
            ratios = []
            if "steps" in runs["directed"]:
                d = runs["directed"]["steps"]
                for n in (1000, 3000, 10000):
                    a, b = loglog_error_at(s, n), loglog_error_at(d, n)
                    if a and b:
                        ratios.append(f"{a / b:.2f} at {n}")
            print(f"| {v} | {degree} | {len(s)} | {s[-1]['dofs']} | {s[-1]['h1_seminorm_error']:.3e} | "
                  f"{', '.join(ratios)} | {sum(x['seconds'] for x in s):.1f} | "
                  f"{sum(x['seconds_refine'] for x in s):.1f} |")
    print("\nThe default is galloping, the fastest; directed reaches a somewhat smaller error at equal dofs "
          "(the column above) for more time, `extension = \"directed\"`.\n")


if __name__ == "__main__":
    main()
