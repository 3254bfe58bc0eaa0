#pragma once
#include <string>

namespace knotwork {

// The kernel family OpenBLAS runs on this CPU ("SkylakeX", "Haswell", "Prescott", ...), or ""
// when the BLAS is not OpenBLAS.
std::string blas_kernel();

// The kernel to name in OPENBLAS_CORETYPE before OpenBLAS is loaded again, or "" to leave
// OpenBLAS's own choice: see blas_kernel.cpp.
std::string better_blas_kernel();

}  // namespace knotwork
