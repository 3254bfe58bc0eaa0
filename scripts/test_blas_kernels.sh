#!/usr/bin/env bash
# The numerical tests again under other OpenBLAS kernels than this machine's default: users'
# CPUs differ, and OpenBLAS falls back to its generic Prescott kernel on a CPU it does not
# know, whose rounding differs from the AVX2/AVX-512 kernels' (CHOLMOD's supernodes are BLAS
# calls). A check of rounding must hold under each (tests/rounding_bounds.hpp). This is what CI
# runs after scripts/test.sh (.ci/run).
#
# Usage: scripts/test_blas_kernels.sh [KERNEL ...]    (default: Prescott Haswell, and the kernel
#        the knotwork command runs with if it is neither: it names a kernel where OpenBLAS takes
#        the CPU for a generic one, solver/blas_kernel.cpp; a kernel that is already the machine's
#        default is skipped: the full suite ran under it)
# Needs the build of scripts/build.sh. About 3 minutes per kernel here (2 cores).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${KNOTWORK_BUILD_DIR:-$root/build}"
kernels=("$@")
if [[ ${#kernels[@]} -eq 0 ]]; then
  kernels=(Prescott Haswell)
  command_kernel="$("$build/app/knotwork" bench --json --config 1:4 |
    /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["blas_kernel"])')"
  [[ -n "$command_kernel" && "$command_kernel" != Prescott && "$command_kernel" != Haswell ]] &&
    kernels+=("$command_kernel")
fi

# The kernel OpenBLAS picks with the given OPENBLAS_CORETYPE ("" for its own choice: the
# variable unset: OpenBLAS 0.3.21 reads an empty one as a kernel name, and gave Cooperlake here).
corename() {
  if [[ -n "$1" ]]; then export OPENBLAS_CORETYPE="$1"; else unset OPENBLAS_CORETYPE; fi
  /usr/bin/python3 -c '
import ctypes
blas = ctypes.CDLL("libopenblas.so.0")
blas.openblas_get_corename.restype = ctypes.c_char_p
print(blas.openblas_get_corename().decode())'
}

# The tests whose results depend on rounding: solves that reproduce a function of the space,
# solvers that must agree, bases checked against their conditions, the G1 cases on meshes where
# the conditioning once decided the outcome. The long rate studies of the surfaces and the
# adaptive loops' rates run once, in the full suite.
numerical='^test_(poisson|g1_basis|g1_space|g1_poisson|g1_refine|pt_poisson|semi_regular|thb|lr|lr_and_hb|geometry|bspline|tensor_volume|volume_cases|volume_files|volume_estimator|thb_volume|volume_multipatch|fast_diagonalization_3d|affine_volume_operator|adaptive|multipatch|thb_multipatch|multigrid_3d|adaptive_multigrid):'
numerical+='|^test_g1_cases:(Defaults on random|Analysis-suitable data, (pentagon|unit square|L-shape|valences 8))'
numerical+='|^test_patchwise_multigrid:(The prolongation|CG . multigrid on several patches)'
slow='H1 error ~ N|adaptive H1 rate|Random refinement sequences|Adaptive LR on the L-shape'

# The kernel the full suite ran under: the machine's own choice, or the one the environment
# already forces (some machines set OPENBLAS_CORETYPE for CPUs older OpenBLAS builds mishandle).
default="$(corename "${OPENBLAS_CORETYPE:-}")"
echo "test_blas_kernels: this machine's OpenBLAS kernel is $default"
failed=0
for kernel in "${kernels[@]}"; do
  got="$(corename "$kernel")"
  if [[ "$got" == "$default" ]]; then
    echo "test_blas_kernels: $kernel is the default kernel here: the full suite ran under it"
    continue
  fi
  if [[ "$got" != "$kernel" ]]; then
    echo "test_blas_kernels: OPENBLAS_CORETYPE=$kernel gives kernel $got, not $kernel" >&2
    exit 1
  fi
  echo "test_blas_kernels: the numerical tests under OPENBLAS_CORETYPE=$kernel"
  OPENBLAS_CORETYPE="$kernel" ctest --test-dir "$build" --output-on-failure -j "$(nproc)" -R "$numerical" -E "$slow" \
    || failed=1
done
exit $failed
