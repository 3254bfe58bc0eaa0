#!/usr/bin/env python3
"""knotwork under mpirun: what is written, and what is refused.

- `mpirun -n 2 knotwork run --solver petsc` writes a piece per rank and a .pvtu summary for
  each output of a serial run (no staging folder left), prints one summary, and VTK's own
  parallel reader reads every cell of the serial output back from the .pvtu, with the
  Bezier cells' rational weights and degrees as active attributes. `converge` on 2 ranks
  writes a .pvd over the levels' .pvtu files, each with every cell of its level.
- The KSP stops at the backward error (the default, 1e-15) unless the options give -ksp_rtol,
  and the JSON says which.
- A PETSc option nobody reads, a serial method under mpirun, and a command that does not run
  under mpirun each get exit code 2 and exactly one error line (rank 0's), not one per rank.

Usage: check_output_and_refusals.py KNOTWORK_BINARY CASE_FILE
"""
import os
import subprocess
import sys
import json
import re
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_distributed import MPIRUN, mpi_environment, under_mpirun  # noqa: E402


def read_back(pvtu):
    """Cells and active attributes of a .pvtu as VTK's XML parallel reader sees them."""
    from vtkmodules.vtkIOXML import vtkXMLPUnstructuredGridReader
    reader = vtkXMLPUnstructuredGridReader()
    reader.SetFileName(pvtu)
    reader.Update()
    grid = reader.GetOutput()
    weights = grid.GetPointData().GetRationalWeights()
    return {"cells": grid.GetNumberOfCells(), "weights": weights.GetName() if weights else None,
            "degrees": grid.GetCellData().GetHigherOrderDegrees() is not None}


def elements_of(case):
    return int(re.search(r"^elements\s*=\s*(\d+)", open(case).read(), re.M).group(1))


def cells_of(vtu):
    # The XML header only: VTK appends the arrays as raw bytes after it.
    with open(vtu, "rb") as f:
        header = f.read().split(b"<AppendedData")[0].decode()
    return sum(int(n) for n in re.findall(r'NumberOfCells="(\d+)"', header))


def main():
    binary, case = sys.argv[1], sys.argv[2]
    serial_env = mpi_environment()
    env = under_mpirun(serial_env, 2)
    failures = []
    with tempfile.TemporaryDirectory() as scratch:
        serial, parallel = os.path.join(scratch, "serial"), os.path.join(scratch, "parallel")
        subprocess.run([binary, "run", case, "-q", "--out", serial], check=True, env=serial_env, capture_output=True,
                       timeout=300)
        done = subprocess.run([MPIRUN, "-n", "2", binary, "run", case, "-q", "--solver", "petsc", "--out", parallel],
                              env=env, capture_output=True, text=True, timeout=300)
        if done.returncode != 0:
            failures.append(f"mpirun -n 2 run: exit {done.returncode}: {done.stderr}")
        if done.stdout.count("knotwork run ") != 1:
            failures.append(f"mpirun -n 2 run: {done.stdout.count('knotwork run ')} summaries on stdout, expected 1")
        written = sorted(os.listdir(parallel)) if os.path.isdir(parallel) else []
        expected = sorted(f"{base}{suffix}" for base in (n[:-4] for n in os.listdir(serial) if n.endswith(".vtu"))
                          for suffix in ("_0.vtu", "_1.vtu", ".pvtu"))
        if written != expected:
            failures.append(f"mpirun -n 2 run wrote {written}, expected {expected}")
        for name in os.listdir(serial):
            if not name.endswith(".vtu") or name[:-4] + ".pvtu" not in written:
                continue
            cells = cells_of(os.path.join(serial, name))
            pieces = sum(cells_of(os.path.join(parallel, f"{name[:-4]}_{r}.vtu")) for r in (0, 1))
            read = read_back(os.path.join(parallel, name[:-4] + ".pvtu"))
            if pieces != cells or read["cells"] != cells:
                failures.append(f"{name}: serial {cells} cells, pieces {pieces}, read from the .pvtu {read['cells']}")
            if name == "solution.vtu" and (read["weights"] != "RationalWeights" or not read["degrees"]):
                failures.append(f"solution.pvtu: read without the Bezier attributes: {read}")
        # converge: a .pvd over the levels' .pvtu files, each read back whole.
        levels = os.path.join(scratch, "levels")
        done = subprocess.run([MPIRUN, "-n", "2", binary, "converge", case, "--levels", "2", "-q", "--solver", "petsc",
                               "--out", levels], env=env, capture_output=True, text=True, timeout=300)
        if done.returncode != 0:
            failures.append(f"mpirun -n 2 converge: exit {done.returncode}: {done.stderr}")
        else:
            with open(os.path.join(levels, "convergence.pvd")) as f:
                listed = re.findall(r'file="([^"]+)"', f.read())
            if listed != ["level_0.pvtu", "level_1.pvtu"]:
                failures.append(f"convergence.pvd lists {listed}")
            for level, name in enumerate(listed):
                serial_level = os.path.join(scratch, f"serial_level_{level}")
                subprocess.run([binary, "run", case, "-q", "--out", serial_level, "--elements",
                                str(elements_of(case) * 2 ** level)], check=True, env=serial_env, capture_output=True,
                               timeout=300)
                cells = cells_of(os.path.join(serial_level, "solution.vtu"))
                if os.path.exists(os.path.join(levels, name)) and read_back(os.path.join(levels, name))["cells"] != cells:
                    failures.append(f"{name}: not the {cells} cells of the level")
        leftovers = [n for n in os.listdir(scratch) if n not in ("serial", "parallel", "levels")
                     and not n.startswith("serial_level_")]
        if leftovers:
            failures.append(f"left in the output's parent folder: {leftovers}")

        refusals = [
            (["--solver", "petsc", "--petsc-options", "-ksp_typo cg"], "-ksp_typo: not an option of PETSc"),
            (["--solver", "direct"], "under mpirun with 2 processes"),
            # One cell (one row of cells) cannot be shared by two processes.
            (["--solver", "petsc", "--elements", "1"], "fewer than the 2 processes that share them"),
        ]
        for extra, expected_text in refusals:
            done = subprocess.run([MPIRUN, "-n", "2", binary, "run", case, "-q", "--no-output"] + extra, env=env,
                                  capture_output=True, text=True, timeout=300, cwd=scratch)
            lines = [l for l in done.stderr.splitlines() if l.startswith("knotwork: error:")]
            if done.returncode != 2 or len(lines) != 1 or expected_text not in lines[0]:
                failures.append(f"run {' '.join(extra)}: exit {done.returncode}, error lines {lines}")
        done = subprocess.run([MPIRUN, "-n", "2", binary, "bench", "--quick"], env=env, capture_output=True, text=True,
                              timeout=300, cwd=scratch)
        lines = [l for l in done.stderr.splitlines() if l.startswith("knotwork: error:")]
        if done.returncode != 2 or len(lines) != 1 or "only `run` and `converge`" not in lines[0]:
            failures.append(f"bench under mpirun: exit {done.returncode}, error lines {lines}")
        # The stop: the backward error by default (at most the tolerance, reported), PETSc's own
        # relative test (its reason, CONVERGED_RTOL) when the options give -ksp_rtol.
        stops = {}
        for extra in ([], ["--petsc-options", "-ksp_rtol 1e-4"]):
            done = subprocess.run([MPIRUN, "-n", "2", binary, "run", case, "--json", "-q", "--no-output", "--solver", "petsc"]
                                  + extra, env=env, capture_output=True, text=True, timeout=300, cwd=scratch)
            if done.returncode != 0:
                failures.append(f"run {' '.join(extra)}: exit {done.returncode}: {done.stderr}")
                continue
            solver = json.loads(done.stdout)["solver"]
            stops[bool(extra)] = (solver["stop"], solver["converged_reason"], solver["backward_error"], solver["tolerance"])
        if stops.get(False) and not (stops[False][:2] == ("backward_error", "CONVERGED_BACKWARD_ERROR") and
                                     stops[False][2] <= stops[False][3] == 1e-15):
            failures.append(f"the default stop: {stops[False]}")
        if stops.get(True) and stops[True][:2] != ("relative_residual", "CONVERGED_RTOL"):
            failures.append(f"-ksp_rtol 1e-4: {stops[True]}")
        expected_folders = {"parallel", "serial", "levels", "serial_level_0", "serial_level_1"}
        if not set(os.listdir(scratch)) <= expected_folders:
            failures.append(f"refused runs wrote {sorted(set(os.listdir(scratch)) - expected_folders)}")
    if failures:
        raise SystemExit("FAIL\n" + "\n".join(failures))
    print("output under mpirun as a serial run's; refusals: one line each, exit 2")


if __name__ == "__main__":
    main()
