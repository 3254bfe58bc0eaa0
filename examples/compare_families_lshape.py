"""Five spline families on the L-shape, u = r^(2/3) sin(2 theta / 3), per degree of freedom.

Uniform refinement of the one-patch tensor space (C0 fold along the diagonal) converges
like N^(-1/3) in H1 because of the corner singularity; adaptive refinement with knot
segments (Weller's semi-regular bases), PT-splines, THB-splines and LR B-splines recovers
the optimal N^(-1) for degree 2, each with the same estimator, marking and solver. One
figure, errors against dofs (docs/ADAPTIVITY.md has the full comparison).
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

uniform = knotwork.converge("cases/lshape.toml", levels=4)
segments = knotwork.adapt("cases/lshape_adaptive.toml", max_dofs=1500)
pt = knotwork.adapt("cases/lshape_adaptive_pt.toml", max_dofs=700)
thb = knotwork.adapt("cases/lshape_adaptive_thb.toml", max_dofs=1500, steps=40)
lr = knotwork.adapt("cases/lshape_adaptive_lr.toml", max_dofs=1500, steps=40)


def slope(study, last=6):
    """Least-squares slope of log(H1 error) against log(dofs) over the last entries."""
    n = study.column("dofs")[-last:]
    e = study.column("h1_seminorm_error")[-last:]
    return np.polyfit(np.log(n), np.log(e), 1)[0]


fig, ax = plt.subplots(figsize=(6.4, 4.6))
for study, label, style in [(uniform, "tensor, uniform", "o-"), (segments, "knot segments, adaptive", "s-"),
                            (pt, "PT-splines, adaptive", "^-"), (thb, "THB-splines, adaptive", "v-"),
                            (lr, "LR B-splines, adaptive", "d-")]:
    rate = slope(study, last=min(6, len(study)))
    ax.loglog(study.column("dofs"), study.column("h1_seminorm_error"), style, ms=4,
              label=f"{label} (slope {rate:.2f})")
    print(f"{label:26s} {len(study):3d} solves, {int(study[-1]['dofs']):6d} dofs, "
          f"H1 error {study[-1]['h1_seminorm_error']:.3e}, slope {rate:.2f}")
n = np.array([1e2, 2e3])
ax.loglog(n, 0.5 * n ** -1.0, "k--", lw=0.8, label="N^-1 (optimal for p = 2)")
ax.loglog(n, 0.5 * n ** (-1 / 3), "k:", lw=0.8, label="N^-1/3 (uniform)")
ax.set_xlabel("degrees of freedom")
ax.set_ylabel("H1-seminorm error")
ax.set_title("L-shape, degree 2: uniform against adaptive")
ax.grid(True, which="both", lw=0.3)
ax.legend(fontsize=8)
fig.tight_layout()
# Theory's rates, checked: uniform about -1/3, adaptive clearly better.
assert -0.45 < slope(uniform, 3) < -0.25
for study in (segments, pt, thb, lr):
    assert slope(study) < -0.8
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig.savefig(out / "compare_families_lshape.png", dpi=110)
print("wrote", out / "compare_families_lshape.png")
