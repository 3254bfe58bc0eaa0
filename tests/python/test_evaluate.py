# Result.evaluate and Space.evaluate_basis, checked against what does not use them: the sampled
# solution (evaluated at the cells' own reference points, no inversion), the exact solution, the
# partition of unity.
import math

import knotwork
import numpy as np
import pytest

from conftest import CASES

EPS = np.finfo(float).eps
N = 4  # sample grid: (N + 1)^2 reference points per cell

FAMILIES = [
    ("square_sinsin.toml", {"degree": 2, "elements": 6}),
    ("quarter_annulus.toml", {}),
    ("multipatch_lshape.toml", {}),
    ("square_knot_segments.toml", {}),
    ("lshape_adaptive_thb.toml", {}),
    ("lshape_adaptive_pt.toml", {}),
    ("lshape_adaptive_lr.toml", {}),
    ("g1_lshape.toml", {}),
    ("g1_sphere_xy.toml", {}),
]


def tolerance(sample):
    """Inverting the map moves a point by a few ulps of its coordinates: the value moves by
    |grad u_h| times that, and the evaluation itself rounds at the size of u_h."""
    size = np.abs(sample["points"]).max()
    return 1e3 * EPS * (np.abs(sample["solution"]).max() + np.abs(sample["gradient"]).max() * size)


@pytest.mark.parametrize("name,overrides", FAMILIES)
def test_evaluate_matches_the_sampled_solution(name, overrides):
    r = knotwork.run(CASES / name, **overrides)
    s = r.sample(N)
    tol = tolerance(s)
    dim = s["points"].shape[-1]
    # Points inside cells: one cell each, where the gradient is the cell's.
    inner = (slice(None), slice(1, N), slice(1, N))
    e = r.evaluate(s["points"][inner].reshape(-1, dim))
    assert np.abs(e["value"] - s["solution"][inner].ravel()).max() <= tol
    assert np.abs(e["gradient"] - s["gradient"][inner].reshape(-1, dim)).max() <= tol * 10
    cells = np.repeat(np.arange(s["points"].shape[0]), (N - 1) ** 2)
    assert np.array_equal(e["cell"], cells)
    grid = np.array([[i / N, j / N] for j in range(1, N) for i in range(1, N)])
    assert np.abs(e["reference"] - np.tile(grid, (s["points"].shape[0], 1))).max() <= 1e-12
    # Every sample point, edges and corners included: u_h is continuous there.
    every = r.evaluate(s["points"].reshape(-1, dim))
    assert np.abs(every["value"] - s["solution"].ravel()).max() <= tol


def test_evaluate_agrees_with_the_exact_solution_as_the_l2_error_says():
    # The mean square of u_h - u over uniform random points of the unit square estimates the
    # squared L2 error (Monte Carlo, 4000 points: within a factor 2 with overwhelming odds).
    r = knotwork.run(CASES / "square_sinsin.toml", degree=2, elements=8)
    rng = np.random.default_rng(7)
    p = rng.random((4000, 2))
    e = r.evaluate(p)
    exact = np.sin(math.pi * p[:, 0]) * np.sin(math.pi * p[:, 1])
    mean_square = np.mean((e["value"] - exact) ** 2)
    assert 0.5 < mean_square / r.l2_error ** 2 < 2


def test_points_outside_are_refused_by_index():
    r = knotwork.run(CASES / "lshape.toml")
    with pytest.raises(knotwork.InputError, match=r"2 of 4 points are outside the domain \(indices 1, 3\)"):
        r.evaluate([[-0.5, 0.5], [0.5, -0.5], [0.5, 0.5], [2.0, 0.0]])  # (0.5, -0.5): the cut-out quadrant
    with pytest.raises(knotwork.InputError, match="outside the domain"):
        r.evaluate([[math.nan, 0.0]])
    with pytest.raises(knotwork.InputError, match=r"shape \(n, 2\)"):
        r.evaluate(np.zeros((3, 3)))
    assert r.evaluate([0.25, 0.25])["value"].shape == (1,)  # one point, flat


def test_surface_points_within_a_distance():
    r = knotwork.run(CASES / "g1_sphere_xy.toml")
    s = r.sample(2)
    p = s["points"][:, 1, 1]  # cell centres, on the discrete surface
    off = p * (1 + 1e-4)  # moved off the surface along the radius
    with pytest.raises(knotwork.InputError, match="not within"):
        r.evaluate(off)
    e = r.evaluate(off, distance=1e-2)
    assert np.all(e["distance"] > 0) and np.all(e["distance"] <= 1e-2)
    assert np.abs(r.evaluate(p)["value"] - s["solution"][:, 1, 1]).max() <= tolerance(s)


def bernstein(p, t):
    """The p + 1 Bernstein polynomials of degree p at the points t (rows)."""
    return np.stack([math.comb(p, a) * t ** a * (1 - t) ** (p - a) for a in range(p + 1)], axis=1)


def test_evaluate_basis_agrees_with_the_extraction_and_the_sampled_solution():
    uv = np.array([[i / N, j / N] for j in range(N + 1) for i in range(N + 1)])
    for name in ("square_knot_segments.toml", "quarter_annulus.toml", "lshape_adaptive_thb.toml", "g1_lshape.toml"):
        r = knotwork.run(CASES / name)
        space = r.space
        s = r.sample(N)
        for cell in range(0, space.num_cells, max(1, space.num_cells // 5)):
            b = space.evaluate_basis(cell, uv)
            m = len(b["functions"])
            assert np.array_equal(b["functions"], space.functions(cell))
            if space.is_rational:  # NURBS: a partition of unity
                assert np.abs(b["value"].sum(axis=1) - 1).max() <= 100 * m * EPS
            else:  # N = C B, from the extraction matrix and Bernstein polynomials computed here
                p, q = space.cell(cell)["degree"]
                B = (bernstein(p, uv[:, 0])[:, :, None] * bernstein(q, uv[:, 1])[:, None, :]).transpose(0, 2, 1)
                expected = B.reshape(len(uv), -1) @ np.asarray(space.extraction(cell)).T
                assert np.abs(b["value"] - expected).max() <= 100 * m * EPS * np.abs(expected).max()
            assert np.abs(b["points"] - s["points"][cell].reshape(-1, s["points"].shape[-1])).max() <= 1e-13
            # u_h and its gradient from the functions equal the sampled solution.
            u = b["value"] @ r.coefficients[b["functions"]]
            assert np.abs(u - s["solution"][cell].ravel()).max() <= tolerance(s)
            g = np.einsum("kad,a->kd", b["gradient"], r.coefficients[b["functions"]])
            assert np.abs(g - s["gradient"][cell].reshape(-1, g.shape[1])).max() <= 10 * tolerance(s)
    with pytest.raises(knotwork.InputError, match=r"\[0, 1\]"):
        space.evaluate_basis(0, [[1.5, 0.5]])
    with pytest.raises(IndexError):
        space.evaluate_basis(space.num_cells, [[0.5, 0.5]])
