#!/usr/bin/env python3
"""Tensor multigrid as PETSc's PCShell (method = "petsc", preconditioner = "multigrid").

For one tensor case at --elements N and 2N, on 2 and 3 processes, PETSc's CG run to the default
stop (the backward error 1e-15, as serial CG) must give:
- the serial direct solve's L2 and H1-seminorm errors to 1e-6 relative;
- a shell built from what the case calls for (--built-from): "operator" (no matrix) where the
  map is one affine map and the problem the operator's, "whole_matrix" (gathered on every
  process) elsewhere;
- iterations bounded in h: at most --max-iterations at both sizes, and at 2N no more than one
  above N (a V-cycle's contraction does not depend on h). N must give the hierarchy a level
  below the finest (more than 3 000 unknowns).

With --degree P the case's degree is replaced (a case whose errors at N are near the rounding
floor would compare rounding, not the solve).

Usage: check_multigrid_shell.py KNOTWORK_BINARY CASE_FILE --elements N --built-from WHAT
                                [--degree P] [--max-iterations M] [--max-added K]
Everything runs on this machine (OpenMPI's shared-memory transport only) and stops by itself.
"""
import os
import sys

from check_distributed import MPIRUN, mpi_environment, run, under_mpirun


def main():
    binary, case, options = sys.argv[1], sys.argv[2], sys.argv[3:]
    def value_of(flag, default=None):
        return options[options.index(flag) + 1] if flag in options else default
    elements = int(value_of("--elements"))
    built_from = value_of("--built-from")
    max_iterations = int(value_of("--max-iterations", "12"))
    max_added = int(value_of("--max-added", "1"))
    env = mpi_environment()
    failures = []
    for ranks in (2, 3):
        iterations = []
        for n in (elements, 2 * elements):
            base = [binary, "run", case, "--json", "-q", "--no-output", "--elements", str(n)]
            if value_of("--degree"):
                base += ["--degree", value_of("--degree")]
            reference = run(base + ["--solver", "direct"], env)
            command = [MPIRUN, "-n", str(ranks), "--oversubscribe"] + base + [
                "--solver", "petsc", "--preconditioner", "multigrid"]
            got = run(command, under_mpirun(env, ranks))
            solver = got["solver"]
            what = f"{ranks} ranks, {n} elements"
            if solver["pc"] != "shell" or solver.get("shell_built_from") != built_from:
                failures.append(f"{what}: PC {solver['pc']} built from {solver.get('shell_built_from')}, "
                                f"not a shell from {built_from}")
            if not solver["converged_reason"].startswith("CONVERGED"):
                failures.append(f"{what}: {solver['converged_reason']}")
            iterations.append(solver["iterations"])
            print(f"{what}: {solver['iterations']} iterations ({reference['free_dofs']} unknowns)")
            for key in ("l2_error", "h1_seminorm_error"):
                relative = abs(got[key] - reference[key]) / reference[key]
                line = f"{what}: {key} {got[key]:.15e} against {reference[key]:.15e} (relative {relative:.1e})"
                print(line)
                if not relative <= 1e-6:
                    failures.append(line)
        if max(iterations) > max_iterations or iterations[1] > iterations[0] + max_added:
            failures.append(f"{ranks} ranks: {iterations[0]} then {iterations[1]} iterations at {elements} and "
                            f"{2 * elements} elements (at most {max_iterations}, and no more than {max_added} added)")
    if failures:
        raise SystemExit("FAIL\n" + "\n".join(failures))
    print(f"{os.path.basename(case)}: multigrid as a PCShell agrees with the direct solve, iterations bounded")


if __name__ == "__main__":
    main()
