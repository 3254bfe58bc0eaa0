#!/usr/bin/python3
"""Every measurement the O(N) solver issue asks for, in one sitting, printed as Markdown
(docs/PERFORMANCE.md, "The O(N) solvers in one sitting"):

1. whole default runs of the unit square at p = 2: 1024^2 and 4096^2, two rounds alternating,
   and p = 4 at 2048^2 (wall time and peak RSS by /usr/bin/time);
2. CG iterations and solve times in h (64^2 .. 4096^2, p = 2) and in p (2..6 at 256^2) on the
   square and the quarter annulus, for multigrid, the fast diagonalization and BoomerAMG
   (BoomerAMG up to 1024^2), with the H1 errors against CHOLMOD's where it runs (to 512^2);
3. volumes at p = 2: the cube and the thick quarter annulus in h (16^3 .. 128^3) and p (2..4
   at 32^3) for the same three, and the cube at 256^3 by default;
4. `knotwork bench` at the issue's configurations;
5. the small configurations, this binary against an earlier one (BEFORE), two rounds
   alternating: nothing slower;
6. the micro-benchmark of the sum-factorized operator against the assembled matrix-vector
   product.

    bench/solver_issue.py [--knotwork build/app/knotwork] [--before OLD_BINARY] [--micro build/bench/knotwork_micro_bench]

About 25 minutes on 2 cores. Run from the repository root after building, on a quiet machine:
timings of a shared machine are noisy, so compare within one sitting.
"""
import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile

RSS = os.path.join(tempfile.mkdtemp(), "rss")


def timed(command):
    """Runs command under /usr/bin/time; returns (stdout, seconds, peak RSS in MB)."""
    done = subprocess.run(["/usr/bin/time", "-f", "%M %e", "-o", RSS] + command, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(command)}: {done.stderr.strip().splitlines()[-1] if done.stderr.strip() else 'failed'}")
    kb, seconds = open(RSS).read().split()[-2:]
    return done.stdout, float(seconds), int(kb) / 1024


def run(knotwork, case, extra):
    out, wall, rss = timed([knotwork, "run", case, "--no-output", "--json", "-q"] + extra)
    return json.loads(out), wall, rss


def whole_runs(knotwork):
    print("### 1. Whole default runs, unit square\n")
    print("`knotwork run cases/square_sinsin.toml --elements N [--degree 4] --no-output --json`\n")
    print("| N | p | preconditioner | CG | wall s | peak RSS | H1 error | against 1024² |")
    print("|---|---|---|---|---|---|---|---|")
    base = {}
    for n, p in [(1024, 2), (4096, 2), (1024, 2), (4096, 2), (2048, 4)]:
        d, wall, rss = run(knotwork, "cases/square_sinsin.toml", ["--elements", str(n), "--degree", str(p)])
        if n == 1024:
            base.setdefault("runs", []).append(wall)
        ratio = f"{wall / base['runs'][-1]:.1f}×" if n == 4096 else ""
        print(f"| {n}² | {p} | {d['solver']['preconditioner']} | {d['solver']['iterations']} | {wall:.2f} | {rss:.0f} MB | "
              f"{d['h1_error']:.6e} | {ratio} |", flush=True)
    print()


def in_h_and_p(knotwork, cases, sizes, degrees, p_size, boomeramg_max, direct_max, extra=()):
    print("| case | p | elements | dofs | multigrid: CG, s | fast_diagonalization: CG, s | boomeramg: CG, s | "
          "H1 error (multigrid) | CHOLMOD's H1 error |")
    print("|---|---|---|---|---|---|---|---|---|")
    for case in cases:
        for p, n in [(2, e) for e in sizes] + [(p, p_size) for p in degrees if p != 2]:
            cells, h1 = [], None
            for pc in ("multigrid", "fast_diagonalization", "boomeramg"):
                if pc == "boomeramg" and n > boomeramg_max:
                    cells.append("—")
                    continue
                d, _, _ = run(knotwork, case, ["--degree", str(p), "--elements", str(n), "--solver", "iterative",
                                               "--preconditioner", pc] + list(extra))
                t = d["timings"]
                cells.append(f"{d['solver']['iterations']}, {t['preconditioner'] + t['iterations']:.3g}")
                if pc == "multigrid":
                    h1, dofs = d["h1_error"], d["dofs"]
            direct = "—"
            if n <= direct_max:
                d, _, _ = run(knotwork, case, ["--degree", str(p), "--elements", str(n), "--solver", "direct"])
                direct = f"{d['h1_error']:.10e}"
            print(f"| `{os.path.basename(case)}` | {p} | {n} | {dofs:,} | " + " | ".join(cells) + f" | {h1:.10e} | {direct} |",
                  flush=True)
    print()


def volumes_large(knotwork):
    print("`knotwork run cases/cube.toml --elements N --no-output --json` (the default: the fast diagonalization "
          "without a matrix), and `--preconditioner multigrid`\n")
    print("| N | preconditioner | unknowns | CG | wall s | peak RSS | H1 error |")
    print("|---|---|---|---|---|---|---|")
    for n in (128, 256):
        for extra in ([], ["--solver", "iterative", "--preconditioner", "multigrid"]):
            d, wall, rss = run(knotwork, "cases/cube.toml", ["--elements", str(n)] + extra)
            print(f"| {n}³ | {d['solver']['preconditioner']} | {d['free_dofs']:,} | {d['solver']['iterations']} | {wall:.2f} | "
                  f"{rss:.0f} MB | {d['h1_error']:.6e} |", flush=True)
    print()


def bench(knotwork, configs, extra=()):
    command = [knotwork, "bench", "--json"] + [a for c in configs for a in ("--config", c)] + list(extra)
    out = subprocess.run(command, capture_output=True, text=True, check=True).stdout
    return json.loads(out)["results"]


def bench_table(knotwork):
    print("`knotwork bench --config 2:1024 --config 2:2048 --config 2:4096 --config 4:2048 --solver iterative --json`\n")
    print("| p | n | CG (preconditioner) | setup | assembly | preconditioner s | CG s | errors | total | peak RSS |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in bench(knotwork, ["2:1024", "2:2048", "2:4096", "4:2048"], ["--solver", "iterative"]):
        print(f"| {r['degree']} | {r['elements']} | {r['solver']['iterations']} ({r['solver']['preconditioner']}) | "
              f"{r['setup']:.3f} | {r['assembly']:.3f} | {r['preconditioner']:.3f} | {r['iterations']:.3f} | "
              f"{r['errors']:.3f} | {r['total']:.3f} | {r['peak_rss_bytes'] / 1e6:.0f} MB |", flush=True)
    print()


def small_sizes(knotwork, before):
    configs = ["2:64", "2:256", "4:64", "4:256"]
    variants = [("direct", []), ("iterative", ["--solver", "iterative"]),
                ("multigrid", ["--solver", "iterative", "--preconditioner", "multigrid"])]
    print(f"`knotwork bench --config 2:64 --config 2:256 --config 4:64 --config 4:256 [--solver iterative "
          f"[--preconditioner multigrid]] --json`, totals in seconds, two rounds alternating, "
          f"{'the binary before → this one' if before else 'this binary'}\n")
    print("| solver | " + " | ".join(configs) + " |")
    print("|---|" + "---|" * len(configs))
    for name, extra in variants:
        totals = {b: [[] for _ in configs] for b in ("before", "after")}
        for _ in range(2):
            for which, binary in (("before", before), ("after", knotwork)):
                if not binary or (which == "before" and name == "multigrid"):  # (no multigrid before the issue)
                    continue
                for k, r in enumerate(bench(binary, configs, extra)):
                    totals[which][k].append(r["total"])
        cells = []
        for k in range(len(configs)):
            after = ", ".join(f"{t:.3g}" for t in totals["after"][k])
            cells.append(f"{', '.join(f'{t:.3g}' for t in totals['before'][k])} → {after}" if totals["before"][k] else after)
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
    print()


def micro(binary):
    out = subprocess.run([binary, "--benchmark_filter=BM_(SymmetricProduct|TensorOperatorApply)/",
                          "--benchmark_repetitions=3", "--benchmark_report_aggregates_only=true", "--benchmark_format=json"],
                         capture_output=True, text=True, check=True).stdout
    print("`knotwork_micro_bench --benchmark_filter='BM_(SymmetricProduct|TensorOperatorApply)/' "
          "--benchmark_repetitions=3`: one product, median of 3\n")
    print("| benchmark | p / n | median ms |")
    print("|---|---|---|")
    for b in json.loads(out)["benchmarks"]:
        if b.get("aggregate_name") == "median":
            name, p, n = b["run_name"].split("/")
            scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[b["time_unit"]]
            print(f"| {name} | {p} / {n}² | {b['real_time'] * scale:.3f} |")
    print()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--knotwork", default="build/app/knotwork")
    ap.add_argument("--before", default=None, help="an earlier knotwork binary for the small configurations")
    ap.add_argument("--micro", default="build/bench/knotwork_micro_bench")
    a = ap.parse_args()
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.machine())
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    print(f"Machine: {cpu}, {os.cpu_count()} cores; commit {commit}.\n")
    whole_runs(a.knotwork)
    print("### 2. In h and p: the square and the quarter annulus\n")
    print("`knotwork run CASE --degree P --elements N --solver iterative --preconditioner NAME --no-output --json` "
          "(the CG iterations, and the preconditioner's set-up plus CG in seconds); `--solver direct` for CHOLMOD\n")
    in_h_and_p(a.knotwork, ["cases/square_sinsin.toml", "cases/quarter_annulus.toml"], [64, 256, 1024, 2048, 4096],
               [2, 3, 4, 5, 6], 256, 1024, 512)
    print("### 3. Volumes, p = 2\n")
    in_h_and_p(a.knotwork, ["cases/cube.toml", "cases/thick_quarter_annulus.toml"], [16, 32, 64, 128], [2, 3, 4], 32, 64, 32)
    volumes_large(a.knotwork)
    print("### 4. `knotwork bench`\n")
    bench_table(a.knotwork)
    print("### 5. Small sizes\n")
    small_sizes(a.knotwork, a.before)
    print("### 6. The sum-factorized operator against the assembled product\n")
    micro(a.micro)


if __name__ == "__main__":
    main()
