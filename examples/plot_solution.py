"""A solution over the physical domain: the quarter annulus (exact NURBS geometry), p = 3.

Result.sample(n) evaluates the solution, the exact solution and their difference on an
(n+1) x (n+1) grid of every cell, at physical points; matplotlib's tripcolor draws them
with the triangles it returns.
"""
import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import knotwork  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="results/python", help="directory for the PNG")
args = parser.parse_args()

r = knotwork.run("cases/quarter_annulus.toml", degree=3, elements=12)
print(r)
s = r.sample(6)
x, y = s["points"][..., 0].ravel(), s["points"][..., 1].ravel()
fig, axes = plt.subplots(1, 2, figsize=(10, 4.4))
for ax, field, title, cmap in [(axes[0], s["solution"], "solution u_h", "viridis"),
                               (axes[1], s["error"], "u_h - u", "RdBu_r")]:
    v = field.ravel()
    lim = np.abs(v).max() if cmap == "RdBu_r" else None
    t = ax.tripcolor(x, y, v, triangles=s["triangles"], shading="gouraud", cmap=cmap,
                     vmin=-lim if lim else None, vmax=lim)
    fig.colorbar(t, ax=ax, format="%.1e" if lim else None)
    ax.set_aspect("equal")
    ax.set_title(title)
# The cell boundaries, from the sampled grid's edges.
P = s["points"]
for c in range(P.shape[0]):
    for edge in (P[c, 0], P[c, -1], P[c, :, 0], P[c, :, -1]):
        axes[0].plot(edge[:, 0], edge[:, 1], "w-", lw=0.3)
fig.suptitle(f"knotwork.run: quarter annulus, {r.space_description}, {r.dofs} dofs, "
             f"L2 error {r.l2_error:.2e}")
fig.tight_layout()
# The sampled error is of the size of the L2 error, as it must be.
assert np.abs(s["error"]).max() < 50 * r.l2_error
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig.savefig(out / "plot_solution.png", dpi=110)
print("wrote", out / "plot_solution.png")
