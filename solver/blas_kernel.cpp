// Debian 12's OpenBLAS (0.3.21) picks its kernels from the CPU's model number and, for a model
// newer than it knows, falls back to its generic x86-64 kernels ("Prescott", SSE3). On an Intel
// Xeon of model 207 (2026) CHOLMOD's factorizations took 2.0-2.5x as long as with the AVX-512
// kernels the CPU has (docs/PERFORMANCE.md). OpenBLAS reads OPENBLAS_CORETYPE only when it
// loads: the command line names the kernel the features call for and starts again
// (app/main.cpp); the Python module does it before OpenBLAS loads, or warns
// (python/knotwork/__init__.py). A user's own OPENBLAS_CORETYPE is kept. No library answers
// "which OpenBLAS kernel do these CPU features allow", hence these lines.
#include "solver/blas_kernel.hpp"

// Weak: absent (null) when the program is linked against another BLAS.
extern "C" char* openblas_get_corename(void) __attribute__((weak));

namespace knotwork {

std::string blas_kernel() {
  if (openblas_get_corename == nullptr) return "";
  const char* name = openblas_get_corename();
  return name ? name : "";
}

std::string better_blas_kernel() {
  if (blas_kernel() != "Prescott") return "";  // OpenBLAS knew the CPU, or is not there
  // libgcc's feature bits include the OS's consent (XCR0) to save the AVX and AVX-512 state.
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl"))
    return "SkylakeX";
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "Haswell";
  return "";
}

}  // namespace knotwork
