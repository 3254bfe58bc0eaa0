"""A source with no formula, given as a Python function: a hot disk in a square plate.

-Laplace(u) = f on the unit square, u = 0 on its sides, with f = 1 inside the disk of radius
0.2 around (0.35, 0.6) and f = 0 outside: a step that no formula of knotwork's grammar writes.
It goes into the case as a vectorized numpy function f(x, y). knotwork calls it once per cell,
with that cell's quadrature points.

Two checks that do not depend on the solver:
- The load sums to the integral of f. The basis functions sum to one, so the entries of
  knotwork.system's load add up to the integral of f, which is the disk's area pi r^2. The
  quadrature cannot resolve the step exactly, so the sum is only close to it, and closer on
  finer meshes.
- The total flux through the boundary balances the source. Green's identity gives
  -integral of du/dn over the boundary = integral of f. The flux is measured here from u_h's
  gradient along the four sides (Result.evaluate, the trapezoidal rule).
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

CENTRE, RADIUS = (0.35, 0.6), 0.2


def hot_disk(x, y):
    return np.where((x - CENTRE[0]) ** 2 + (y - CENTRE[1]) ** 2 < RADIUS**2, 1.0, 0.0)


area = math.pi * RADIUS**2
print(f"{'elements':>8} {'sum of the load':>16} {'pi r^2':>9} {'boundary flux':>14}")
for elements in (16, 32, 64):
    case = {"geometry": {"type": "rectangle"}, "space": {"degree": 2, "elements": elements},
            "problem": {"source": hot_disk, "dirichlet": "0"}}
    load = knotwork.system(case).load.sum()
    r = knotwork.run(case)
    # The outward flux -du/dn along the four sides, 2001 points each (the corners' values count
    # half, as the trapezoidal rule weighs them).
    t = np.linspace(0, 1, 2001)
    sides = [(np.column_stack([t, 0 * t]), (0, -1)), (np.column_stack([1 + 0 * t, t]), (1, 0)),
             (np.column_stack([t, 1 + 0 * t]), (0, 1)), (np.column_stack([0 * t, t]), (-1, 0))]
    flux = 0.0
    for points, normal in sides:
        dudn = r.evaluate(points)["gradient"] @ np.array(normal, dtype=float)
        flux -= np.trapz(dudn, t)
    print(f"{elements:>8} {load:16.6f} {area:9.6f} {flux:14.6f}")
    # The step limits the quadrature's accuracy: the load is within 2% of the area on the
    # coarsest mesh, and the flux balances the load to the discretization's accuracy.
    assert abs(load - area) < 0.02 * area, (load, area)
    assert abs(flux - load) < 0.01 * load, (flux, load)

s = r.sample(6)
fig, ax = plt.subplots(figsize=(5.2, 4.4))
points = s["points"].reshape(-1, 2)
image = ax.tripcolor(points[:, 0], points[:, 1], s["solution"].ravel(), triangles=s["triangles"], shading="gouraud")
ax.add_patch(plt.Circle(CENTRE, RADIUS, fill=False, color="white", lw=0.8, ls="--"))
fig.colorbar(image, ax=ax, label="u_h")
ax.set_aspect("equal")
ax.set_title("f = 1 in the disk (a Python function), u = 0 on the sides", fontsize=9)
fig.tight_layout()
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig.savefig(out / "python_source.png", dpi=110)
print("wrote", out / "python_source.png")
