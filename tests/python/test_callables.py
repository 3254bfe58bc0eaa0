# Problems given as Python functions: the same solutions as the equivalent formulas, within what
# the condition allows (the two evaluate f in different orders of operations); clear refusals of
# what cannot be derived from a function; the function's own errors raised as they are.
import math

import knotwork
import numpy as np
import pytest

from conftest import CASES

EPS = np.finfo(float).eps
SQUARE = {"geometry": {"type": "rectangle"}, "space": {"degree": 2, "elements": 16}}
PI = math.pi


def condition(case):
    s = knotwork.system(case)
    return np.linalg.cond(s.stiffness[s.free][:, s.free].toarray())


def assert_same_solution(formula, functions):
    a, b = knotwork.run(formula), knotwork.run(functions)
    tol = 100 * condition(formula) * EPS
    assert np.linalg.norm(a.coefficients - b.coefficients) <= tol * np.linalg.norm(a.coefficients)
    assert b.l2_error == pytest.approx(a.l2_error, rel=1e-6)
    assert b.h1_seminorm_error == pytest.approx(a.h1_seminorm_error, rel=1e-6)
    return a, b


def test_a_python_source_gives_the_formulas_solution():
    formula = dict(SQUARE, problem={"exact": "sin(pi*x)*sin(pi*y)", "source": "2*pi^2*sin(pi*x)*sin(pi*y)"})
    source = dict(SQUARE, problem={"exact": "sin(pi*x)*sin(pi*y)",
                                   "source": lambda x, y: 2 * PI**2 * np.sin(PI * x) * np.sin(PI * y)})
    assert_same_solution(formula, source)


def test_a_python_exact_solution_with_its_gradient():
    formula = dict(SQUARE, problem={"exact": "exp(x)*sin(2*y)", "source": "3*exp(x)*sin(2*y)"})
    problem = {"exact": lambda x, y: np.exp(x) * np.sin(2 * y),
               "exact_gradient": (lambda x, y: np.exp(x) * np.sin(2 * y), lambda x, y: 2 * np.exp(x) * np.cos(2 * y)),
               "source": lambda x, y: 3 * np.exp(x) * np.sin(2 * y)}
    functions = dict(SQUARE, problem=problem)
    a, b = assert_same_solution(formula, functions)
    # The caller's dict is left as it was.
    assert set(problem) == {"exact", "exact_gradient", "source"} and callable(problem["exact"])
    # sample() evaluates the Python exact solution too.
    assert np.abs(b.sample(2)["error"] - a.sample(2)["error"]).max() <= 1e-10


def test_python_coefficients_and_reaction_with_a_source_derived_here():
    # cases/annulus_anisotropic.toml: u = sin x cos 2y, A = [[2 + xy, x/2], [x/2, 1 + y^2]],
    # c = 1 + x^2, a Neumann side (the flux A grad u . n from the exact solution and A).
    # f = -div(A grad u) + c u, differentiated by hand below.
    def source(x, y):
        ux, uy = np.cos(x) * np.cos(2 * y), -2 * np.sin(x) * np.sin(2 * y)
        uxx, uyy, uxy = -np.sin(x) * np.cos(2 * y), -4 * np.sin(x) * np.cos(2 * y), -2 * np.cos(x) * np.sin(2 * y)
        a11, a12, a22 = 2 + x * y, 0.5 * x, 1 + y**2
        div = y * ux + a11 * uxx + 0.5 * uy + 2 * a12 * uxy + 2 * y * uy + a22 * uyy
        return -div + (1 + x**2) * np.sin(x) * np.cos(2 * y)

    file_case = CASES / "annulus_anisotropic.toml"
    formula = knotwork.run(file_case)
    import tomllib
    d = tomllib.loads(file_case.read_text())
    d["problem"]["coefficient"] = [[lambda x, y: 2 + x * y, lambda x, y: 0.5 * x], [lambda x, y: 0.5 * x, lambda x, y: 1 + y**2]]
    d["problem"]["reaction"] = lambda x, y: 1 + x**2
    d["problem"]["source"] = source
    functions = knotwork.run(d)
    tol = 100 * condition(file_case) * EPS
    assert np.linalg.norm(functions.coefficients - formula.coefficients) <= tol * np.linalg.norm(formula.coefficients)


def test_surface_functions_take_z():
    import tomllib
    g = tomllib.loads((CASES / "g1_sphere_xy.toml").read_text())
    g["space"]["mesh"] = str(CASES / g["space"]["mesh"])
    formula = dict(g, problem=dict(g["problem"], source="6*x*y"))
    functions = dict(g, problem=dict(g["problem"], exact=lambda x, y, z: x * y, source=lambda x, y, z: 6 * x * y,
                                     exact_gradient=(lambda x, y, z: y, lambda x, y, z: x, lambda x, y, z: 0 * z)))
    assert_same_solution(formula, functions)
    two = dict(functions, problem=dict(functions["problem"], exact_gradient=(lambda x, y, z: y, lambda x, y, z: x)))
    with pytest.raises(knotwork.InputError, match="2 components on a surface"):
        knotwork.run(two)


def test_what_cannot_be_derived_is_asked_for():
    f = lambda x, y: x  # noqa: E731
    with pytest.raises(knotwork.InputError, match=r"\[problem\] exact_gradient: missing"):
        knotwork.run(dict(SQUARE, problem={"exact": f, "source": "0"}))
    with pytest.raises(knotwork.InputError, match=r"\[problem\] source: missing"):
        knotwork.run(dict(SQUARE, problem={"exact": f, "exact_gradient": (f, f)}))
    with pytest.raises(knotwork.InputError, match="cannot be differentiated"):  # f derived from exact and A
        knotwork.run(dict(SQUARE, problem={"exact": "x*y", "coefficient": lambda x, y: 1 + x}))
    with pytest.raises(knotwork.InputError, match="only with a Python function as exact"):
        knotwork.run(dict(SQUARE, problem={"exact": "x*y", "exact_gradient": (f, f)}))


def test_the_functions_own_errors_and_wrong_results():
    def broken(x, y):
        raise RuntimeError("my source is broken")

    with pytest.raises(RuntimeError, match="my source is broken"):
        knotwork.run(dict(SQUARE, problem={"exact": "x*y", "source": broken}))
    with pytest.raises(ValueError, match=r"\[problem\] source: .* n values .* shape \(3,\)"):
        knotwork.run(dict(SQUARE, problem={"exact": "x*y", "source": lambda x, y: np.zeros(3)}))
    with pytest.raises(ValueError, match="not numbers"):
        knotwork.run(dict(SQUARE, problem={"exact": "x*y", "source": lambda x, y: "abc"}))
    with pytest.raises(knotwork.InputError, match="not a finite number"):
        knotwork.run(dict(SQUARE, problem={"exact": "x*y", "source": lambda x, y: np.full_like(x, np.nan)}))
    # One number for all points is broadcast: u = xy is harmonic, and in the space (to rounding).
    case = dict(SQUARE, problem={"exact": "x*y", "source": lambda x, y: 0.0})
    assert knotwork.run(case).l2_error <= 100 * condition(case) * EPS


def test_boundary_data_as_python_functions():
    # u = x^2 - y^2 (harmonic): Dirichlet data on three sides, the flux du/dn = 2x on the right.
    formula = dict(SQUARE, problem={"exact": "x^2 - y^2", "source": "0", "dirichlet": "x^2 - y^2",
                                    "neumann": {"right": "2*x"}})
    functions = dict(SQUARE, problem={"exact": "x^2 - y^2", "source": "0", "dirichlet": lambda x, y: x**2 - y**2,
                                      "neumann": {"right": lambda x, y: 2 * x}})
    assert_same_solution(formula, functions)


def test_a_function_that_raises_while_writing_leaves_no_files(tmp_path):
    broken = {"now": False}

    def exact(x, y):
        if broken["now"]:
            raise RuntimeError("exact broke while writing")
        return x * y

    case = dict(SQUARE, problem={"exact": exact, "exact_gradient": (lambda x, y: y, lambda x, y: x), "source": "0"})
    r = knotwork.run(case)
    broken["now"] = True
    with pytest.raises(RuntimeError, match="exact broke while writing"):
        r.write_paraview(tmp_path / "out")
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
    with pytest.raises(RuntimeError, match="exact broke while writing"):
        r.sample(2)
