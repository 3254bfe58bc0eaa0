# Importing knotwork names an OpenBLAS kernel where OpenBLAS would run its generic one on a CPU
# with AVX2 (Debian 12's OpenBLAS on CPU models newer than it knows), keeps a user's
# OPENBLAS_CORETYPE, and warns when OpenBLAS was loaded first and can no longer change.
# Each case is a fresh interpreter: OpenBLAS picks its kernels once per process.
import os
import subprocess
import sys

ENV = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
REPORT = "import os, knotwork; print(knotwork._core.blas_kernel(), os.environ.get('OPENBLAS_CORETYPE', '-'))"


def cpu_flags():
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("flags"):
                return set(line.split(":", 1)[1].split())
    return set()


def fresh(code, **env):
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env={**ENV, **env})
    assert p.returncode == 0, p.stderr
    return p.stdout.split(), p.stderr


def test_importing_knotwork_first_avoids_the_generic_kernel():
    (kernel, named), _ = fresh(REPORT)
    if {"avx2", "fma"} <= cpu_flags():
        assert kernel != "Prescott"
    # Named only where OpenBLAS's own choice was the generic kernel; then it is the one running.
    assert named in ("-", kernel)


def test_a_users_kernel_is_kept():
    (kernel, named), err = fresh(REPORT, OPENBLAS_CORETYPE="Prescott")
    assert (kernel, named) == ("Prescott", "Prescott")
    assert "RuntimeWarning" not in err


def test_openblas_loaded_first_gets_a_warning_naming_the_variable():
    # numpy (Debian's) loads the same OpenBLAS; its own choice stands, and knotwork says so
    # exactly when it is the generic kernel on a CPU that allows a better one.
    code = ("import ctypes, os; ctypes.CDLL('libopenblas.so.0'); import knotwork; "
            "print(knotwork._core.blas_kernel(), knotwork._core.better_blas_kernel() or '-')")
    (kernel, better), err = fresh(code)
    assert (better != "-") == (kernel == "Prescott" and {"avx2", "fma"} <= cpu_flags())
    assert ("OPENBLAS_CORETYPE=" + better in err) == (better != "-")
