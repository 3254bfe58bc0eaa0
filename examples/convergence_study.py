"""A convergence study in a few lines: degrees 1 to 4 on the unit square, u = sin(pi x) sin(pi y).

For each degree p, knotwork.converge refines uniformly and returns one dict per level; the
log-log plot shows the L2 and H1-seminorm errors against h with triangles of the rates
theory predicts (p + 1 and p), and the table prints the observed rates.
"""
import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import knotwork  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="results/python", help="directory for the PNG")
args = parser.parse_args()


def rate_triangle(ax, x, y, rate, color):
    """A slope triangle of the given rate below the point (x, y), one tenth of a decade wide."""
    x0, x1 = x, x * 0.6
    y0, y1 = y * 0.4, y * 0.4 * (x1 / x0) ** rate
    ax.plot([x0, x1, x0, x0], [y0, y1, y1, y0], color=color, lw=0.8)
    ax.text(x0 * 1.03, (y0 * y1) ** 0.5, f"{rate}", color=color, fontsize=8, va="center")


fig, (ax_l2, ax_h1) = plt.subplots(1, 2, figsize=(10, 4.2), sharex=True)
colors = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728"]
print(f"{'p':>2} {'dofs':>7} {'L2 error':>12} {'rate':>5} {'H1 error':>12} {'rate':>5}")
for p, color in zip([1, 2, 3, 4], colors):
    # Start coarse and take fewer levels at high degree: the errors reach rounding otherwise.
    study = knotwork.converge("cases/square_sinsin.toml", levels=5 if p < 4 else 4, degree=p, elements=4)
    h = study.column("h")
    ax_l2.loglog(h, study.column("l2_error"), "o-", color=color, label=f"p = {p}")
    ax_h1.loglog(h, study.column("h1_seminorm_error"), "s-", color=color, label=f"p = {p}")
    rate_triangle(ax_l2, h[-1], study[-1]["l2_error"], p + 1, color)
    rate_triangle(ax_h1, h[-1], study[-1]["h1_seminorm_error"], p, color)
    last = study[-1]
    print(f"{p:>2} {last['dofs']:>7} {last['l2_error']:12.4e} {last['l2_rate']:5.2f} "
          f"{last['h1_seminorm_error']:12.4e} {last['h1_rate']:5.2f}")
    # What theory says, checked: the observed rates on the finest level.
    assert abs(last["l2_rate"] - (p + 1)) < 0.15 and abs(last["h1_rate"] - p) < 0.15, study
for ax, title in [(ax_l2, "L2 error"), (ax_h1, "H1-seminorm error")]:
    ax.set_xlabel("h (largest cell diameter)")
    ax.set_title(title)
    ax.grid(True, which="both", lw=0.3)
    ax.legend()
fig.suptitle("knotwork.converge: unit square, u = sin(pi x) sin(pi y), B-splines of maximal smoothness")
fig.tight_layout()
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig.savefig(out / "convergence_study.png", dpi=110)
print("wrote", out / "convergence_study.png")
