#pragma once
// sin, cos, tan, their inverses, the hyperbolic functions, exp, log, pow and atan2 over arrays,
// several values per instruction: glibc's vector math
// library (libmvec), which GCC calls by itself only under -ffast-math. Written here because
// no library on this machine exposes it otherwise (Eigen 3.4 vectorizes exp and log of doubles,
// not sin, cos or pow). With AVX2 and FMA, 4 lanes (3.3x scalar sin measured here), else 2
// (SSE2, every x86-64 CPU; 1.8x), chosen once from the CPU; 2 in builds by clang (why: the .cpp). Each value is within 4 ulp of the scalar
// function (glibc's bound; 3 ulp measured) and does not depend on its position or on n: the
// last values are computed in a padded vector, so that one value alone (n = 1) is bitwise the
// one a long array gives.
#include <string>

namespace knotwork {

using ArrayFunction1 = void (*)(const double* a, double* t, long n);                   // t = f(a)
using ArrayFunction2 = void (*)(const double* a, const double* b, double* t, long n);  // t = f(a, b)

// The array form of a grammar function (sin, cos, tan, asin, acos, atan, sinh, cosh, tanh, exp,
// log); null for the others (sqrt and abs: exact in every lane already).
ArrayFunction1 array_function(const std::string& name);
// pow(a, b) and atan2(a, b) over arrays.
ArrayFunction2 array_pow();
ArrayFunction2 array_atan2();
// Which lanes ran: "avx2" (4 lanes), "sse2" (2) or "scalar" (not x86-64).
const char* vector_math_kind();

}  // namespace knotwork
