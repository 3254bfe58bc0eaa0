"""A line plot through the solution: u_h and the exact u along a cut of the L-shape, with Result.evaluate.

The L-shape's exact solution r^(2/3) sin(2 theta / 3) has a singular gradient at the
re-entrant corner (0, 0). This script solves it on a uniform space and evaluates u_h along two
cuts: the diagonal y = x from (-1, -1) to (1, 1), which passes through the corner, and the line
y = 0.5 across the upper half. It plots u_h, u and the error. Points are physical coordinates:
`evaluate` finds each point's cell and inverts the geometry map there. Points outside the
L-shape (the removed quadrant x > 0, y < 0) are refused, by index.
"""
import argparse
import math
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import knotwork  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="results/python", help="directory for the PNG")
args = parser.parse_args()
case = pathlib.Path(__file__).resolve().parents[1] / "cases" / "lshape.toml"

r = knotwork.run(case, degree=2, elements=8)


def exact(x, y):
    """r^(2/3) sin(2 theta / 3), theta in [0, 3 pi / 2) measured from the positive x-axis."""
    theta = np.mod(np.arctan2(y, x), 2 * math.pi)
    return np.hypot(x, y) ** (2 / 3) * np.sin(2 * theta / 3)


cuts = {
    "y = x, through the corner": np.column_stack([np.linspace(-1, 1, 401)] * 2),
    "y = 0.5, from x = -1 to 1": np.column_stack([np.linspace(-1, 1, 401), np.full(401, 0.5)]),
}
fig, axes = plt.subplots(2, 2, figsize=(10, 6), sharex="col")
for column, (label, points) in enumerate(cuts.items()):
    e = r.evaluate(points)
    t = points[:, 0]
    u = exact(points[:, 0], points[:, 1])
    axes[0, column].plot(t, e["value"], label="u_h")
    axes[0, column].plot(t, u, "--", label="u")
    axes[0, column].set_title(label, fontsize=10)
    axes[0, column].legend()
    axes[1, column].semilogy(t, np.abs(e["value"] - u) + 1e-16)
    axes[1, column].set_xlabel("x")
    axes[1, column].set_ylabel("|u_h - u|")
    print(f"{label}: max |u_h - u| = {np.abs(e['value'] - u).max():.3e} over {len(t)} points, "
          f"in {len(np.unique(e['cell']))} cells")
# The points outside the domain are refused by index: (0.5, -0.5) is in the removed quadrant.
try:
    r.evaluate([[-0.5, -0.5], [0.5, -0.5]])
    raise AssertionError("a point outside the L-shape was accepted")
except knotwork.InputError as refused:
    print("refused:", refused)
fig.suptitle("knotwork: u_h along cuts of the L-shape (Result.evaluate), p = 2, 8 elements per knot span")
fig.tight_layout()
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig.savefig(out / "line_plot.png", dpi=110)
print("wrote", out / "line_plot.png")
