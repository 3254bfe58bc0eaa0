#!/usr/bin/env python3
"""The same case on 1, 2 and 3 MPI processes (method = "petsc") against the serial direct solve.

For one case file: CHOLMOD's errors (serial, `--solver direct`) are the reference; PETSc's CG +
BoomerAMG (the default) on 1, 2 and 3 ranks, run to knotwork's default stop (the backward
error 1e-15, as serial CG), must give the same L2 and H1-seminorm errors to 1e-6 relative (a
relative residual of 1e-10, PETSc's usual stop, left the G1 pentagon 1.7e-6 off), MUMPS's distributed Cholesky on 2 and 3 ranks
to 1e-10 (and for tensor cases, whose default is their own preconditioner, BoomerAMG by
options to 1e-6: with --rows and --patches). Partition-dependent bugs (a cell on a rank boundary, a Dirichlet dof owned elsewhere)
change the errors far beyond that.

With --rows N (a tensor case with N rows of cells along v, or a volume with N slabs of cells
along w), each process must hold only its part of the space on 2 and 3 ranks: at most its
ceil(N / ranks) rows and the q rows below them (q the degree along v, or along w) where the
functions of its matrix rows also live, of every row's cells/N cells. With --elements N, every
run (serial and distributed) takes `--elements N`. With --patches (a multipatch case with at least 3 patches), each process must
hold a part of whole patches and their halo: fewer cells than the whole space. Without either,
the whole space (built on every rank).

With --assembly METHOD (kronecker_form, sum_factorization or element_loop), every distributed
run must report that it made its matrix that way (`solver.assembly_method`): a patch with one
affine map has each process write its owned rows from the Kronecker form; where only some
processes' rows are affine, the others write theirs by sum factorization (reported so).

Usage: check_distributed.py KNOTWORK_BINARY CASE_FILE [--rows N | --patches] [--assembly METHOD] [--elements N]
Everything runs on this machine (OpenMPI's shared-memory transport only) and stops by itself.
"""
import json
import os
import subprocess
import sys

MUMPS = "-ksp_type preonly -pc_type cholesky -pc_factor_mat_solver_type mumps"
MPIRUN = os.environ.get("MPIRUN", "mpirun")


def mpi_environment():
    env = dict(os.environ)
    env.update({
        "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",  # CI runs as root
        "OMPI_MCA_btl": "self,vader",  # no network: processes talk through shared memory
        "OMPI_MCA_btl_vader_single_copy_mechanism": "none",  # no ptrace between processes (sandboxes)
        "OMPI_MCA_rmaps_base_oversubscribe": "1",  # 3 ranks on 2 cores
    })
    return env


def under_mpirun(env, ranks):
    """The environment for the processes of `mpirun -n ranks`: in the sanitizer build, its
    options for two or more (scripts/sanitizers/environment.sh says why)."""
    env = dict(env)
    if ranks > 1 and "KNOTWORK_MPI_ASAN_OPTIONS" in env:
        env["ASAN_OPTIONS"] = env["KNOTWORK_MPI_ASAN_OPTIONS"]
    return env


def run(command, env):
    done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=300)
    if done.returncode != 0:
        raise SystemExit(f"FAIL {' '.join(command)}: exit {done.returncode}\n{done.stderr}")
    return json.loads(done.stdout)


def main():
    binary, case, options = sys.argv[1], sys.argv[2], sys.argv[3:]
    def value_of(flag):
        return options[options.index(flag) + 1] if flag in options else None
    rows = int(value_of("--rows")) if "--rows" in options else None
    patches = "--patches" in options
    assembly = value_of("--assembly")
    env = mpi_environment()
    base = [binary, "run", case, "--json", "-q", "--no-output"]
    if "--elements" in options:
        base += ["--elements", value_of("--elements")]
    reference = run(base + ["--solver", "direct"], env)
    failures = []
    runs = [(n, "", 1e-6) for n in (1, 2, 3)] + [(n, MUMPS, 1e-10) for n in (2, 3)]
    if rows is not None or patches:  # the default there is the space's PCShell: BoomerAMG on the parts too
        runs += [(n, "-pc_type hypre", 1e-6) for n in (2, 3)]
    for ranks, options, tolerance in runs:
        command = [MPIRUN, "-n", str(ranks), "--oversubscribe"] + base + ["--solver", "petsc"]
        if options:
            command += ["--petsc-options", options]
        got = run(command, under_mpirun(env, ranks))
        what = f"{ranks} rank(s), {got['solver']['ksp']} + {got['solver']['pc']}"
        if got["ranks"] != ranks:
            failures.append(f"{what}: reports {got['ranks']} ranks")
        if got["cells"] != reference["cells"] or got["dofs"] != reference["dofs"]:
            failures.append(f"{what}: reports {got['cells']} cells and {got['dofs']} functions, serial "
                            f"{reference['cells']} and {reference['dofs']}")
        held = got["largest_part_cells"]
        if rows is not None and ranks > 1:
            per_row = reference["cells"] // rows
            limit = (-(-rows // ranks) + reference["degree"][-1]) * per_row
            if not (got["space_parts"] and held <= limit and held < reference["cells"]):
                failures.append(f"{what}: a process held {held} of {reference['cells']} cells "
                                f"(parts: {got['space_parts']}; at most {limit})")
        elif patches and ranks > 1:
            if not (got["space_parts"] and held < reference["cells"]):
                failures.append(f"{what}: a process held {held} of {reference['cells']} cells "
                                f"(parts: {got['space_parts']}), not a part of whole patches")
        elif got["space_parts"] or held != reference["cells"]:
            failures.append(f"{what}: a process held {held} of {reference['cells']} cells (parts: {got['space_parts']}), "
                            "not the whole space")
        if assembly and got["solver"]["assembly_method"] != assembly:
            failures.append(f"{what}: the matrix by {got['solver']['assembly_method']}, not {assembly}")
        if got["free_dofs"] != reference["free_dofs"]:
            failures.append(f"{what}: {got['free_dofs']} unknowns, serial {reference['free_dofs']}")
        for key in ("l2_error", "h1_seminorm_error"):
            relative = abs(got[key] - reference[key]) / reference[key]
            line = f"{what}: {key} {got[key]:.15e} against {reference[key]:.15e} (relative {relative:.1e}, limit {tolerance:.0e})"
            print(line)
            if not relative <= tolerance:
                failures.append(line)
    if failures:
        raise SystemExit("FAIL\n" + "\n".join(failures))
    print(f"{os.path.basename(case)}: {len(runs)} distributed solves agree with the serial one")


if __name__ == "__main__":
    main()
