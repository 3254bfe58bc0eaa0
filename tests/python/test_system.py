# knotwork.system: the assembled matrices over all basis functions. Checked against what does
# not depend on them: run's coefficients (a scipy solve of the free rows must give them), the
# constants in the Laplacian's kernel, the domain's area from the mass matrix, symmetry.
import math

import knotwork
import numpy as np
import pytest
import scipy.sparse.linalg

from conftest import CASES

EPS = np.finfo(float).eps

# (case, overrides, area of the domain where the map is polynomial (so that Gauss quadrature of
# its Jacobian is exact) or None, pure Laplacian with no weak boundary terms)
CASES_BY_FAMILY = [
    ("square_sinsin.toml", {"degree": 2, "elements": 8}, 1.0, True),           # tensor
    ("quarter_annulus.toml", {}, None, True),                                  # NURBS
    ("annulus_anisotropic.toml", {}, None, False),                             # A, Neumann side
    ("square_variable_coefficient.toml", {}, 1.0, False),                     # A(x), c(x)
    ("multipatch_lshape.toml", {}, 3.0, True),                                 # several patches, Neumann
    ("square_knot_segments.toml", {}, 1.0, True),                              # knot segments
    ("lshape_adaptive_pt.toml", {}, 3.0, True),                                # PT-splines
    ("lshape_adaptive_thb.toml", {}, 3.0, True),                               # THB
    ("lshape_adaptive_lr.toml", {}, 3.0, True),                                # LR
    ("g1_lshape.toml", {}, None, False),                                       # G1 (Nitsche)
]


def scipy_solution(s):
    """The Dirichlet values moved to the right-hand side, the free rows solved by SuperLU."""
    K, F, d, f = s.stiffness, s.load, s.dirichlet, s.free
    u = np.zeros(K.shape[0])
    u[d] = s.dirichlet_values
    Kff = K[f][:, f].tocsc()
    u[f] = scipy.sparse.linalg.spsolve(Kff, F[f] - K[f][:, d] @ u[d])
    return u, Kff


@pytest.mark.parametrize("name,overrides,area,laplacian", CASES_BY_FAMILY)
def test_system_solves_to_runs_coefficients(name, overrides, area, laplacian):
    s = knotwork.system(CASES / name, **overrides)
    r = knotwork.run(CASES / name, **overrides)
    n = r.space.num_functions
    assert s.stiffness.shape == (n, n) and s.mass.shape == (n, n) and s.load.shape == (n,)
    assert not s.zero_mean
    # The same pipeline on the same space: the same bits.
    assert np.array_equal(s.solve(), r.coefficients)
    assert np.array_equal(r.coefficients[s.dirichlet], s.dirichlet_values)
    # Whole and symmetric, to the bit (both triangles from one).
    assert (s.stiffness - s.stiffness.T).count_nonzero() == 0
    assert (s.mass - s.mass.T).count_nonzero() == 0
    # Another solver on these matrices: agreement within what the condition allows (two
    # backward-stable solves differ by at most a small multiple of kappa eps in relative terms).
    u, Kff = scipy_solution(s)
    kappa = np.linalg.cond(Kff.toarray())
    assert np.linalg.norm(u - r.coefficients) <= 100 * kappa * EPS * np.linalg.norm(r.coefficients)
    one = np.ones(n)
    if area is not None:  # 1^T M 1 is the area (partition of unity)
        assert one @ s.mass @ one == pytest.approx(area, rel=1e-12)
    if laplacian:  # the constants are in the Laplacian's kernel (partition of unity)
        row_size = abs(s.stiffness) @ one
        assert np.all(np.abs(s.stiffness @ one) <= 1e3 * EPS * row_size)


def test_closed_surface_system():
    # No Dirichlet functions; the constants are in the kernel; run fixes the mean.
    s = knotwork.system(CASES / "g1_sphere_xy.toml")
    r = knotwork.run(CASES / "g1_sphere_xy.toml")
    assert s.zero_mean
    assert len(s.dirichlet) == 0 and len(s.free) == s.stiffness.shape[0]
    one = np.ones(s.stiffness.shape[0])
    assert np.all(np.abs(s.stiffness @ one) <= 1e3 * EPS * (abs(s.stiffness) @ one))
    assert np.array_equal(s.solve(), r.coefficients)
    # run's solution has mean zero over the surface: 1^T M u = 0, up to rounding.
    u = r.coefficients
    assert abs(one @ s.mass @ u) <= 1e3 * EPS * (one @ abs(s.mass) @ abs(u))


def test_system_arrays_are_views_and_bad_input_is_refused(tmp_path):
    s = knotwork.system(CASES / "square_sinsin.toml", degree=2, elements=4)
    assert not s.load.flags.writeable and not s.stiffness.data.flags.writeable
    assert s.stiffness.indices.dtype == np.int32 and s.dirichlet.dtype == np.int32
    assert "knotwork.System" in repr(s)
    with pytest.raises(knotwork.InputError, match="degree"):
        knotwork.system(CASES / "square_sinsin.toml", degree=0)
    with pytest.raises(knotwork.InputError):
        knotwork.system(tmp_path / "missing.toml")
