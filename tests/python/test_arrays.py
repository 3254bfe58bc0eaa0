# Arrays: shapes, dtypes, views without copies, and what they mean, checked against
# properties that do not depend on knotwork (partition of unity from the extraction
# matrices, the sampled solution against the exact one, the coefficient count).
import math

import knotwork
import numpy as np
import pytest

from conftest import CASES


@pytest.fixture(scope="module")
def square():
    return knotwork.run(str(CASES / "square_sinsin.toml"), degree=3, elements=8)


def test_coefficients_are_a_read_only_view(square):
    c = square.coefficients
    assert c.dtype == np.float64 and c.shape == (square.dofs,) == (11 * 11,)
    assert not c.flags.writeable and not c.flags.owndata
    assert square.coefficients.ctypes.data == c.ctypes.data  # the same memory, not a copy
    with pytest.raises(ValueError):
        c[0] = 1.0
    # The array keeps the solution alive after the result is gone.
    r = knotwork.run(str(CASES / "square_sinsin.toml"), degree=2, elements=4)
    kept = r.coefficients
    expected = kept.copy()
    del r
    import gc
    gc.collect()
    assert np.array_equal(kept, expected)


def test_space_arrays_and_partition_of_unity(square):
    space = square.space
    assert space.num_functions == square.dofs and space.num_cells == square.cells == 64
    assert space.degree == (3, 3) and space.family == "tensor"
    for cell in (0, 27, 63):
        ids = space.functions(cell)
        ext = space.extraction(cell)
        assert ids.dtype == np.int32 and ext.dtype == np.float64
        assert ext.shape == (len(ids), 16) and len(ids) == 16  # (p+1)^2 B-splines alive on a cell
        assert np.all((ids >= 0) & (ids < space.num_functions))
        # Bernstein polynomials sum to 1: so do the functions iff every column of C sums to 1.
        assert np.abs(ext.sum(axis=0) - 1).max() < 1e-13
        assert not ext.flags.writeable
    info = space.cell(9)
    assert info["degree"] == (3, 3) and len(info["parameter_box"]) == 4 and len(info["boundary"]) == 4
    with pytest.raises(IndexError):
        space.functions(64)
    with pytest.raises(IndexError):
        space.extraction(-1)
    # Every function is alive on some cell.
    alive = np.unique(np.concatenate([space.functions(c) for c in range(space.num_cells)]))
    assert np.array_equal(alive, np.arange(space.num_functions))
    assert space.rank() == space.num_functions


def test_sample_shapes_and_values(square):
    n = 6
    s = square.sample(n)
    cells = square.cells
    assert s["points"].shape == (cells, n + 1, n + 1, 2)
    assert s["solution"].shape == s["exact"].shape == s["error"].shape == (cells, n + 1, n + 1)
    assert s["gradient"].shape == (cells, n + 1, n + 1, 2)
    assert s["triangles"].shape == (cells * n * n * 2, 3) and s["triangles"].dtype == np.int64
    assert s["triangles"].max() == cells * (n + 1) ** 2 - 1
    x, y = s["points"][..., 0], s["points"][..., 1]
    assert np.allclose(s["exact"], np.sin(np.pi * x) * np.sin(np.pi * y), atol=1e-14)
    assert np.array_equal(s["error"], s["solution"] - s["exact"])
    # The pointwise error of a p = 3, h = 1/8 solution is of the L2 error's size, not more.
    assert np.abs(s["error"]).max() < 20 * square.l2_error
    # The gradient of sin(pi x) sin(pi y), to the H1 error's accuracy.
    gx = np.pi * np.cos(np.pi * x) * np.sin(np.pi * y)
    assert np.abs(s["gradient"][..., 0] - gx).max() < 20 * square.h1_seminorm_error
    with pytest.raises(knotwork.InputError):
        square.sample(0)


def test_surface_sample_is_three_dimensional():
    r = knotwork.run(str(CASES / "g1_sphere_xy.toml"))
    s = r.sample(2)
    assert s["points"].shape[-1] == 3
    radius = np.linalg.norm(s["points"], axis=-1)
    assert np.abs(radius - radius.mean()).max() < 0.1 * radius.mean()  # points lie near the sphere


def test_write_paraview(square, tmp_path):
    paths = square.write_paraview(tmp_path / "out")
    names = sorted(p.split("/")[-1] for p in paths)
    assert names == ["solution.vtu", "solution_sampled.vtu"]
    assert all((tmp_path / "out" / n).stat().st_size > 0 for n in names)


def test_study_columns():
    study = knotwork.converge(str(CASES / "square_sinsin.toml"), levels=3, degree=2)
    h, l2 = study.column("h"), study.column("l2_error")
    assert h.dtype == np.float64 and h.shape == (3,)
    assert np.all(np.diff(h) < 0) and np.all(np.diff(l2) < 0)
    # degree 2: L2 error like h^3, and the rate column is the slope between levels
    rates = study.column("l2_rate")
    assert math.isnan(rates[0])
    assert rates[2] == pytest.approx(math.log(l2[1] / l2[2]) / math.log(h[1] / h[2]), rel=1e-12)
    assert 2.9 < rates[2] < 3.1
    with pytest.raises(KeyError):
        study.column("l2_eror")


def test_dimension_of_a_dict_tmesh():
    # The tensor-product case: a 2 x 2 grid, bi-quadratic C^1 splines: (2 + 2)^2 = 16.
    r = knotwork.dimension({"cells": [[0, 0, 1, 1], [1, 0, 2, 1], [0, 1, 1, 2], [1, 1, 2, 2]], "degree": [2, 2]})
    assert r["dimension_bruteforce"] == 16
    with pytest.raises(knotwork.InputError, match="degree"):
        knotwork.dimension({"cells": [[0, 0, 1, 1]]})


def test_a_volume_from_python():
    # The cube: three degrees, hexahedral cells with a box along w, the errors as the command
    # line prints them.
    r = knotwork.run(str(CASES / "cube.toml"), degree=2, elements=3)
    space = r.space
    assert space.degree == (2, 2, 2)
    assert space.num_functions == r.dofs == 5 ** 3 and space.num_cells == 27
    cell = space.cell(0)
    assert cell["degree"] == (2, 2, 2) and len(cell["parameter_box"]) == 6
    # Partition of unity from the extraction: the functions' Bernstein coefficients sum to 1.
    extraction = space.extraction(13)
    assert extraction.shape == (27, 27)
    assert np.allclose(extraction.sum(axis=0), 1.0, atol=1e-14)
    assert 0 < r.l2_error < 1e-2
    # Sampled on each hexahedron's (n+1)^3 grid, [cell, k, j, i]: the points are the cube's,
    # the exact solution is sin sin sin there, and the pointwise error is of the L2 error's size.
    s = r.sample(2)
    assert s["points"].shape == (27, 3, 3, 3, 3) and s["solution"].shape == (27, 3, 3, 3)
    assert s["gradient"].shape == (27, 3, 3, 3, 3) and s["triangles"] is None
    x, y, z = (s["points"][..., d] for d in range(3))
    assert x.min() == 0 and x.max() == 1 and z.min() == 0 and z.max() == 1
    assert np.allclose(s["exact"], np.sin(np.pi * x) * np.sin(np.pi * y) * np.sin(np.pi * z), atol=1e-14)
    assert np.abs(s["error"]).max() < 20 * r.l2_error
    # i runs along u (x on the cube), k along w (z).
    assert np.all(np.diff(x, axis=3) > 0) and np.all(np.diff(z, axis=1) > 0)


def test_a_volume_reproduces_a_trilinear_function_at_samples():
    # The patch test seen through sample(): u = 1 + x - 2y + 3z lies in the degree-1 space on
    # the cube, so the samples of u_h are u's up to the solve's rounding. kappa(K) is below 1e2
    # on these 4^3 cells and |u| <= 5, so rounding stays below 1e-12; an error of the space
    # (a wrong cell, a wrong point order) would be of order 1.
    r = knotwork.run({"geometry": {"type": "box"}, "space": {"degree": 1, "elements": 4},
                      "problem": {"exact": "1 + x - 2*y + 3*z"}})
    s = r.sample(3)
    x, y, z = (s["points"][..., d] for d in range(3))
    assert np.abs(s["solution"] - (1 + x - 2 * y + 3 * z)).max() < 1e-12
    assert np.abs(s["gradient"] - np.array([1.0, -2.0, 3.0])).max() < 1e-11
