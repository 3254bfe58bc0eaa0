# A dict case is validated exactly like a case file: for each class of bad input of the
# case-file format, the same document as a TOML file (through the CLI) and as a dict
# (tomllib's reading of that file, through Python) gives the same one-line message, and
# Python raises knotwork.InputError (a ValueError).
import tomllib

import knotwork
import pytest

from conftest import cli

GOOD = """
[geometry]
type = "rectangle"
[space]
degree = 2
elements = 4
[problem]
exact = "sin(pi*x)*sin(pi*y)"
"""
NURBS = """
[geometry]
type = "nurbs"
degrees = [1, 1]
knots_u = [0, 0, 1, 1]
knots_v = [0, 0, 1, 1]
control_points = [[0, 0], [1, 0], [0, 1], [1, 1]]
weights = [1, 1, 1, 1]
[space]
degree = 2
elements = 2
[problem]
exact = "x*y"
"""
SEGMENTS = GOOD.replace("degree = 2", 'family = "knot_segments"\ndegree = 2')


def segment(s):
    return SEGMENTS.replace("elements = 4", "elements = 4\nsegments = [ " + s + " ]")


# (class of bad input, the TOML text, a piece of the expected message)
BAD = [
    ("unknown key", GOOD.replace("degree = 2", "degre = 2"), "did you mean 'degree'"),
    ("missing key", GOOD.replace("degree = 2\n", ""), "[space] degree"),
    ("degree out of range", GOOD.replace("degree = 2", "degree = 11"), "[space] degree"),
    ("elements out of range", GOOD.replace("elements = 4", "elements = 0"), "[space] elements"),
    ("wrong type", GOOD.replace("degree = 2", 'degree = "two"'), "[space] degree"),
    ("unknown family", GOOD.replace("degree = 2", 'family = "tensr"\ndegree = 2'), "[space] family"),
    ("key of another family", GOOD.replace("degree = 2", "degree = 2\nsegments = []"), "knot_segments"),
    ("unknown top-level section", GOOD + "[solverr]\nmethod = \"direct\"\n", "solverr"),
    ("knots not non-decreasing", NURBS.replace("knots_u = [0, 0, 1, 1]", "knots_u = [0, 1, 0, 1]"), "knots_u"),
    ("control points count", NURBS.replace("[0, 1], [1, 1]]", "[0, 1]]"), "control_points"),
    ("weights not positive", NURBS.replace("weights = [1, 1, 1, 1]", "weights = [1, 1, 0, 1]"), "weights"),
    ("non-positive Jacobian", NURBS.replace("[[0, 0], [1, 0], [0, 1], [1, 1]]", "[[0, 0], [1, 0], [1, 1], [0, 1]]"),
     "Jacobian"),
    ("segment outside the domain", segment('{ direction = "vertical", position = 1.5, from = 0, to = 1 }'),
     "segments[0]"),
    ("segment of zero length", segment('{ direction = "vertical", position = 0.3, from = 0.5, to = 0.5 }'),
     "zero length"),
    ("segment direction", segment('{ direction = "diagonal", position = 0.3, from = 0, to = 1 }'), "direction"),
    ("expression syntax", GOOD.replace("sin(pi*x)*sin(pi*y)", "sin(pi*x)*sin(pi*y"), "[problem] exact"),
    ("expression unknown variable", GOOD.replace('exact = "sin(pi*x)*sin(pi*y)"', 'source = "1"\ndirichlet = "x + q"'),
     "[problem] dirichlet"),
    ("Neumann everywhere", GOOD.replace("[problem]", '[problem]\nneumann = ["left", "right", "top", "bottom"]'),
     "[problem] neumann"),
    ("solver method", GOOD + '[solver]\nmethod = "iterativ"\n', "did you mean 'iterative'"),
    ("solver tolerance", GOOD + "[solver]\ntolerance = 1.5\n", "[solver] tolerance"),
    ("solver max_iterations", GOOD + "[solver]\nmax_iterations = 0\n", "[solver] max_iterations"),
    ("PETSc options without BoomerAMG", GOOD + '[solver]\npetsc_options = "-pc_hypre_boomeramg_max_levels 3"\n',
     "[solver] petsc_options"),
    ("PETSc option BoomerAMG does not use",
     GOOD + '[solver]\nmethod = "iterative"\npreconditioner = "boomeramg"\npetsc_options = "-pc_hypre_boomeramg_max_lvls 3"\n',
     "not an option"),
    ("preconditioner of another family",
     SEGMENTS + '[solver]\nmethod = "iterative"\npreconditioner = "fast_diagonalization"\n', "knot_segments"),
    ("not converged", GOOD + '[solver]\nmethod = "iterative"\npreconditioner = "jacobi"\nmax_iterations = 2\n',
     "CG stopped after 2 iterations"),
    ("adapt on a family that does not refine locally", GOOD + "[adapt]\nsteps = 3\n", "[adapt]"),
    ("adapt key", SEGMENTS + "[adapt]\nstep = 3\n", "did you mean 'steps'"),
    ("too large for the machine", GOOD.replace("degree = 2", "degree = 10").replace("elements = 4", "elements = 8000"),
     "GB"),
]


@pytest.mark.parametrize("what,text,piece", BAD, ids=[b[0] for b in BAD])
def test_dict_is_refused_like_the_file(tmp_path, what, text, piece):
    (tmp_path / "bad.toml").write_text(text)
    code, out, err = cli(["run", "-q", "--no-output", "bad.toml"], cwd=tmp_path)
    assert code != 0 and err.startswith("knotwork: error: "), err
    cli_message = err.removeprefix("knotwork: error: ").rstrip("\n")
    assert piece in cli_message
    with pytest.raises(knotwork.InputError) as e:
        knotwork.run(tomllib.loads(text), name="bad.toml")
    assert str(e.value) == cli_message
    assert isinstance(e.value, ValueError)
    assert "\n" not in str(e.value)


# What only a dict can get wrong: values no case file can hold.
DICT_ONLY = [
    ("None value", {"space": {"degree": None}}, "<dict>: [space] degree: None is not a value"),
    ("key not a string", {"space": {2: "x"}}, "<dict>: space: key 2 is not a string"),
    ("object value", {"space": {"degree": object()}}, "<dict>: [space] degree: a value of type object"),
    ("set value", {"geometry": {"type": {"rectangle"}}}, "<dict>: [geometry] type: a value of type set"),
    ("integer beyond 64 bits", {"space": {"degree": 2**70}}, "<dict>: [space] degree: integer out of the 64-bit range"),
]


@pytest.mark.parametrize("what,patch,message", DICT_ONLY, ids=[d[0] for d in DICT_ONLY])
def test_values_only_a_dict_can_hold(what, patch, message):
    case = tomllib.loads(GOOD)
    for section, values in patch.items():
        case[section].update(values)
    with pytest.raises(knotwork.InputError) as e:
        knotwork.run(case)
    assert str(e.value).startswith(message), str(e.value)


def test_deep_nesting_is_refused_not_a_crash():
    deep = []
    for _ in range(1000):
        deep = [deep]
    case = tomllib.loads(GOOD)
    case["space"]["segments"] = deep
    with pytest.raises(knotwork.InputError, match="nested deeper than 200 levels"):
        knotwork.run(case)
    loop = []
    loop.append(loop)
    case["space"]["segments"] = loop
    with pytest.raises(knotwork.InputError, match="nested deeper"):
        knotwork.run(case)


def test_a_good_dict_solves_like_its_file(tmp_path):
    (tmp_path / "good.toml").write_text(GOOD)
    from_file = knotwork.run(str(tmp_path / "good.toml"))
    from_dict = knotwork.run(tomllib.loads(GOOD))
    assert from_dict.dofs == from_file.dofs == 36  # (4 + 2)^2
    assert from_dict.l2_error == from_file.l2_error
    # numpy values are accepted where the schema takes numbers
    import numpy as np
    case = tomllib.loads(GOOD)
    case["space"]["degree"] = np.int64(3)
    assert knotwork.run(case).dofs == 49


BAD_OVERRIDES = [
    (dict(degree=0), "degree: must be >= 1"),
    (dict(degree=2.5), "degree: must be an integer"),
    (dict(degree=True), "degree: must be an integer"),
    (dict(elements="8"), "elements: must be an integer"),
    (dict(solver="cg"), "--solver"),
    (dict(solver=3), "solver: must be a string"),
    (dict(tolerance=0), "tolerance: must be in (0, 1)"),
    (dict(tolerance=2.0), "tolerance: must be in (0, 1)"),
    (dict(tolerance="small"), "tolerance: must be a number"),
    (dict(ordering="random"), "random"),
    (dict(preconditioner="multigird"), "--preconditioner: 'multigird' is not a choice (did you mean 'multigrid'"),
    (dict(preconditioner=2), "preconditioner: must be a string"),
    (dict(matrix="free"), "--matrix: 'free' is not a choice"),
    (dict(matrix=1), "matrix: must be a string"),
    (dict(matrix="matrix_free", solver="direct"), "[solver] matrix: \"matrix_free\" needs CG"),
]


@pytest.mark.parametrize("overrides,piece", BAD_OVERRIDES, ids=[str(o) for o, _ in BAD_OVERRIDES])
def test_bad_overrides(overrides, piece):
    with pytest.raises(knotwork.InputError) as e:
        knotwork.run(tomllib.loads(GOOD), **overrides)
    assert piece in str(e.value)


def test_bad_study_arguments(tmp_path):
    good = tomllib.loads(GOOD)
    with pytest.raises(knotwork.InputError, match="levels"):
        knotwork.converge(good, levels=13)
    with pytest.raises(knotwork.InputError, match="levels"):
        knotwork.converge(good, levels="3")
    with pytest.raises(knotwork.InputError, match="theta"):
        knotwork.adapt(tomllib.loads(SEGMENTS), theta=1.5)
    with pytest.raises(knotwork.InputError, match="family"):
        knotwork.adapt(good, steps=2)
    with pytest.raises(knotwork.InputError, match="exact"):
        knotwork.converge({"geometry": {"type": "rectangle"}, "space": {"degree": 2, "elements": 2},
                           "problem": {"source": "1", "dirichlet": "0"}})
    with pytest.raises(knotwork.InputError, match="not a directory|not writable"):
        (tmp_path / "occupied").write_text("x")
        knotwork.run(good, output=tmp_path / "occupied")
    assert (tmp_path / "occupied").read_text() == "x"
    with pytest.raises(knotwork.InputError, match="cannot|no such|not found|No such"):
        knotwork.run(str(tmp_path / "missing.toml"))
    with pytest.raises(knotwork.InputError, match="give a case-file path or a dict"):
        knotwork.run(42)
