"""Conditioning of the stiffness matrix: G1 splines against C0 multipatch B-splines on the L-shape.

knotwork.system gives the assembled matrices as scipy matrices. This script takes the stiffness
block of the free functions, scales it by its diagonal (Jacobi), A = D^(-1/2) K D^(-1/2), and
finds A's extreme eigenvalues with scipy's Lanczos (eigsh; shift-invert at 0 for the
smallest one). It does this for two spaces of degree 4 under uniform refinement:

- the G1 space on the 36-quad L-shape mesh (cases/g1_lshape.toml: C1 across every edge,
  Dirichlet data imposed by Nitsche's method);
- the C0 B-splines on the three-patch L-shape (cases/multipatch_lshape.toml: C3 inside each
  patch, C0 across the interfaces).

For a second-order operator in 2D, theory says kappa(A) grows like h^-2, that is like the
number of unknowns N, once h is small enough. The constant depends on the space. The plot
shows kappa against N with a slope-1 line, and the script checks the slope over the two finest
levels.
"""
import argparse
import pathlib
import tomllib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import scipy.sparse  # noqa: E402
import scipy.sparse.linalg  # noqa: E402

import knotwork  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="results/python", help="directory for the PNG")
args = parser.parse_args()
cases = pathlib.Path(__file__).resolve().parents[1] / "cases"


def extreme_eigenvalues(system):
    """Smallest and largest eigenvalue of the Jacobi-scaled stiffness on the free functions."""
    f = system.free
    K = system.stiffness[f][:, f]
    scale = scipy.sparse.diags(1 / np.sqrt(K.diagonal()))
    A = (scale @ K @ scale).tocsc()
    largest, v_max = scipy.sparse.linalg.eigsh(A, k=1, which="LA")
    smallest, v_min = scipy.sparse.linalg.eigsh(A, k=1, sigma=0, which="LM")
    # Each pair checked by its residual, relative to ||A|| ~ the largest eigenvalue.
    for lam, v in [(largest[0], v_max[:, 0]), (smallest[0], v_min[:, 0])]:
        assert np.linalg.norm(A @ v - lam * v) <= 1e-8 * largest[0], lam
    return smallest[0], largest[0], K.shape[0]


# The G1 case refines by [space] refine (each quad split into four); as a dict, its mesh file
# is given from the repository root.
g1 = tomllib.loads((cases / "g1_lshape.toml").read_text())
g1["space"]["mesh"] = str(cases / g1["space"]["mesh"])
spaces = {
    "G1, degree 4": [dict(g1, space=dict(g1["space"], refine=r)) for r in (0, 1, 2)],
    "C0 multipatch, degree 4": [(cases / "multipatch_lshape.toml", e) for e in (8, 16, 32, 64)],
}

fig, ax = plt.subplots(figsize=(6, 4.5))
print(f"{'space':<24} {'unknowns':>9} {'lambda_min':>11} {'lambda_max':>10} {'kappa':>9}")
for (label, levels), marker in zip(spaces.items(), ["o", "s"]):
    rows = []
    for level in levels:
        if isinstance(level, dict):
            s = knotwork.system(level, name="g1_lshape.toml")
        else:
            s = knotwork.system(level[0], degree=4, elements=level[1])
        lo, hi, n = extreme_eigenvalues(s)
        rows.append((n, hi / lo))
        print(f"{label:<24} {n:>9} {lo:11.4e} {hi:10.4f} {hi / lo:9.1f}")
    n, kappa = np.array(rows).T
    ax.loglog(n, kappa, marker + "-", label=label)
    # What theory says, checked: kappa ~ N on the two finest levels.
    slope = np.log(kappa[-1] / kappa[-2]) / np.log(n[-1] / n[-2])
    print(f"{label:<24} slope of kappa against N on the finest levels: {slope:.2f} (theory: 1)")
    assert 0.7 < slope < 1.3, slope
n_ref = np.array([1e3, 2e4])
ax.loglog(n_ref, 0.05 * n_ref, "k--", lw=0.8, label="slope 1 (h^-2)")
ax.set_xlabel("unknowns N (free functions)")
ax.set_ylabel("condition number of the Jacobi-scaled stiffness")
ax.set_title("knotwork.system + scipy eigsh: L-shape, degree 4")
ax.grid(True, which="both", lw=0.3)
ax.legend()
fig.tight_layout()
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig.savefig(out / "conditioning_study.png", dpi=110)
print("wrote", out / "conditioning_study.png")
