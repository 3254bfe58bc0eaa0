"""CG iterations under refinement: fast diagonalization against multigrid, on two tensor patches.

Both preconditioners know the tensor-product structure of the space (docs/SOLVERS.md):

- "fast_diagonalization" inverts the parameter-domain operator with the geometry folded in as
  products a(u) b(v). Where the map's coefficients separate (the quarter annulus) that is the
  operator itself, and CG needs a handful of iterations; where they do not (the L-shape patch,
  cases/lshape.toml) the count is larger, though it does not grow with h.
- "multigrid" is a V-cycle over the space's own uniform refinement: Galerkin coarse operators
  and a block smoother. Its count stays small on both maps, for every h and p.

The script runs each case at three sizes with both, through ``knotwork.run(...,
solver="iterative", preconditioner=...)``, plots iterations against dofs, and checks that
multigrid's count does not grow with h (at most two more on the finest level than on the
coarsest) and that both reach the direct solve's H1 error.
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
cases = pathlib.Path(__file__).resolve().parents[1] / "cases"

fig, ax = plt.subplots(figsize=(6, 4))
for case, style in [("quarter_annulus.toml", "-"), ("lshape.toml", "--")]:
    for preconditioner, marker in [("fast_diagonalization", "s"), ("multigrid", "o")]:
        dofs, iterations = [], []
        for elements in (64, 128, 256):  # (below about 3 000 dofs multigrid is one direct solve)
            r = knotwork.run(cases / case, degree=3, elements=elements, solver="iterative",
                             preconditioner=preconditioner)
            direct = knotwork.run(cases / case, degree=3, elements=elements, solver="direct")
            # CG stops at a backward error of 1e-15: the algebraic error must not show in the
            # discretization error (1e-6 relative is far below the gap between two levels).
            assert abs(r.h1_error - direct.h1_error) <= 1e-6 * direct.h1_error, (case, elements)
            dofs.append(r.dofs)
            iterations.append(r.solver["iterations"])
        print(f"{case:22s} {preconditioner:21s} iterations {iterations}")
        if preconditioner == "multigrid":
            assert iterations[-1] <= iterations[0] + 2, (case, iterations)
        ax.plot(dofs, iterations, style, marker=marker, label=f"{case.removesuffix('.toml')}, {preconditioner}")

ax.set_xscale("log")
ax.set_xlabel("dofs")
ax.set_ylabel("CG iterations (backward error 1e-15)")
ax.set_title("Degree 3: CG iterations under uniform refinement")
ax.legend(fontsize=8)
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig.tight_layout()
fig.savefig(out / "solver_iterations.png", dpi=120)
print(f"wrote {out / 'solver_iterations.png'}")
