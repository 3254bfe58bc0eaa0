# The module's results are the CLI's: the same case through `knotwork <command> --json` and
# through Python gives the same numbers, to the last bit (more than the 1e-12 asked for: both
# run the same code on the same data, and every result is the same bits in every process).
import math

import knotwork
import pytest

from conftest import CASES, cli_json

# Keys that are measurements of time or memory, or name files: not results.
VOLATILE = {"timings", "seconds", "seconds_space", "seconds_solve", "seconds_estimate", "seconds_refine", "seconds_output", "solve_phases", "outputs",
            "peak_memory_mb_per_rank"}

def assert_same(cli_value, py_value, where="result"):
    """Recursively equal, numbers to the last bit; VOLATILE keys skipped."""
    if isinstance(cli_value, dict):
        assert isinstance(py_value, dict), where
        keys = set(cli_value) - VOLATILE
        assert keys == set(py_value) - VOLATILE, f"{where}: keys differ"
        for k in keys:
            assert_same(cli_value[k], py_value[k], f"{where}.{k}")
    elif isinstance(cli_value, list):
        assert isinstance(py_value, list) and len(cli_value) == len(py_value), where
        for i, (a, b) in enumerate(zip(cli_value, py_value)):
            assert_same(a, b, f"{where}[{i}]")
    elif isinstance(cli_value, float) or isinstance(py_value, float):
        assert py_value == cli_value, f"{where}: {py_value!r} != {cli_value!r}"
    else:
        assert cli_value == py_value, where


RUNS = [
    ("square_sinsin.toml", ["--degree", "3", "--elements", "12"], {"degree": 3, "elements": 12}),
    ("quarter_annulus.toml", [], {}),
    ("quarter_annulus.toml", ["--solver", "iterative", "--degree", "3"], {"solver": "iterative", "degree": 3}),
    ("quarter_annulus.toml", ["--solver", "petsc"], {"solver": "petsc"}),
    ("lshape.toml", ["--solver", "iterative", "--preconditioner", "multigrid", "--elements", "48"],
     {"solver": "iterative", "preconditioner": "multigrid", "elements": 48}),
    ("lshape.toml", [], {}),
    ("square_sinsin.toml", ["--solver", "iterative", "--matrix", "assembled", "--elements", "40"],
     {"solver": "iterative", "matrix": "assembled", "elements": 40}),
    ("square_sinsin.toml", ["--solver", "iterative", "--matrix", "matrix_free", "--elements", "40"],
     {"solver": "iterative", "matrix": "matrix_free", "elements": 40}),
    ("square_knot_segments.toml", [], {}),
    ("lshape_adaptive_pt.toml", [], {}),
    ("g1_pentagon.toml", [], {}),
    ("g1_sphere_xy.toml", [], {}),
    ("annulus_anisotropic.toml", [], {}),
    ("g1_variable_coefficient.toml", [], {}),
    ("g1_sphere_anisotropic.toml", [], {}),
    # Multipatch geometry files, G+Smo XML and GeoPDEs text: Python reads the same files.
    ("multipatch_lshape.toml", [], {}),
    ("multipatch_ring.toml", [], {}),
    # A G+Smo problem file (domain, source, boundary conditions) runs as the case it describes.
    ("multipatch_lshape_problem.xml", ["--degree", "2", "--elements", "4"], {"degree": 2, "elements": 4}),
]


@pytest.mark.parametrize("case,args,overrides", RUNS, ids=[f"{c}{' '.join(a)}" for c, a, _ in RUNS])
def test_run_equals_cli(case, args, overrides):
    path = str(CASES / case)
    expected = cli_json(["run", path, "--no-output", *args])
    result = knotwork.run(path, **overrides)
    assert_same(expected, result.data)
    assert result.dofs == expected["dofs"] and result.cells == expected["cells"]
    assert len(result.coefficients) == expected["dofs"]


def test_converge_equals_cli(tmp_path):
    path = str(CASES / "square_sinsin.toml")
    expected = cli_json(["converge", path, "--levels", "3", "--degree", "2", "--out", str(tmp_path / "cli")])
    study = knotwork.converge(path, levels=3, degree=2)
    assert_same(expected["levels"], list(study))
    assert_same({k: v for k, v in expected.items() if k != "levels"}, study.info)
    assert study.info["outputs"] == []  # nothing written without output=


def test_converge_writes_the_cli_files_when_asked(tmp_path):
    path = str(CASES / "square_sinsin.toml")
    study = knotwork.converge(path, levels=2, output=tmp_path / "py")
    names = sorted(p.split("/")[-1] for p in study.info["outputs"])
    assert "convergence.json" in names and "convergence.csv" in names and "level_1.vtu" in names
    assert all((tmp_path / "py" / n).exists() for n in names)


def test_adapt_equals_cli(tmp_path):
    path = str(CASES / "lshape_adaptive.toml")
    expected = cli_json(["adapt", path, "--steps", "4", "--out", str(tmp_path)])
    study = knotwork.adapt(path, steps=4)
    assert_same(expected["steps"], list(study))
    assert len(study) == 4
    rates = study.column("h1_rate_vs_dofs")
    assert math.isnan(rates[0]) and all(r > 0 for r in rates[1:])


def test_adapt_on_several_patches_equals_cli(tmp_path):
    path = str(CASES / "multipatch_lshape_adaptive_thb.toml")
    expected = cli_json(["adapt", path, "--steps", "5", "--out", str(tmp_path)])
    study = knotwork.adapt(path, steps=5)
    assert_same(expected["steps"], list(study))


@pytest.mark.parametrize("case", ["lshape_adaptive_thb.toml", "lshape_adaptive_lr.toml"])
def test_adapt_marking_functions_equals_cli(tmp_path, case):
    path = str(CASES / case)
    expected = cli_json(["adapt", path, "--steps", "5", "--marking", "functions", "--out", str(tmp_path)])
    assert expected["marking"] == "functions"
    study = knotwork.adapt(path, steps=5, marking="functions")
    assert_same(expected["steps"], list(study))
    cells = knotwork.adapt(path, steps=5)
    assert [s["dofs"] for s in cells] != [s["dofs"] for s in study]  # a different marking, different meshes
    with pytest.raises(knotwork.InputError, match="marking"):
        knotwork.adapt(path, steps=2, marking="elements")


def test_adapt_maximum_strategy_equals_cli(tmp_path):
    path = str(CASES / "lshape_adaptive_thb.toml")
    args = ["--steps", "5", "--strategy", "maximum", "--theta", "0.5", "--min-fraction", "0.1", "--marking", "functions"]
    expected = cli_json(["adapt", path, *args, "--out", str(tmp_path)])
    assert (expected["strategy"], expected["min_fraction"], expected["marking"]) == ("maximum", 0.1, "functions")
    study = knotwork.adapt(path, steps=5, strategy="maximum", theta=0.5, min_fraction=0.1, marking="functions")
    assert_same(expected["steps"], list(study))
    assert (study.info["strategy"], study.info["min_fraction"]) == ("maximum", 0.1)
    with pytest.raises(knotwork.InputError, match="strategy"):
        knotwork.adapt(path, steps=2, strategy="bulk")
    with pytest.raises(knotwork.InputError, match="min_fraction"):
        knotwork.adapt(path, steps=2, min_fraction=1.5)


def test_adapt_output_every_writes_every_kth_step_and_the_last(tmp_path):
    path = str(CASES / "lshape_adaptive.toml")
    study = knotwork.adapt(path, steps=5, output=tmp_path / "py", output_every=3)
    names = {p.split("/")[-1] for p in study.info["outputs"]}
    assert {"step_0.vtu", "step_3.vtu", "step_4.vtu", "adapt.csv"} <= names
    assert not {"step_1.vtu", "step_2.vtu"} & names
    with pytest.raises(knotwork.InputError, match="output_every"):
        knotwork.adapt(path, steps=2, output_every=0)


@pytest.mark.parametrize("case", ["square_knot_segments.toml", "g1_three_quads.toml", "lshape_adaptive_pt.toml",
                                  "lshape_adaptive_thb.toml", "lshape_adaptive_lr.toml"])
def test_space_report_equals_basis_json(case):
    path = str(CASES / case)
    expected = cli_json(["basis", path])
    space = knotwork.space(path)
    assert_same(expected, space.report())
    assert space.num_functions == expected["functions"] and space.num_cells == expected["cells"]
    assert space.rank() == expected["rank"]
    assert space.partition_of_unity_error() == expected["partition_of_unity_error"]
    counts = space.dimension_check()
    assert counts["functions"] == expected["functions"] and counts["rank"] == expected["rank"]
    if "dimension_bruteforce" in expected:  # knot segments: the count against the brute force
        assert counts["dimension_bruteforce"] == expected["dimension_bruteforce"] == space.num_functions


@pytest.mark.parametrize("tmesh", ["pinwheel_generic.toml", "ray_and_segment.toml"])
def test_dimension_equals_cli(tmesh):
    path = str(CASES / "tmeshes" / tmesh)
    expected = cli_json(["dimension", path])
    assert_same(expected, knotwork.dimension(path))
