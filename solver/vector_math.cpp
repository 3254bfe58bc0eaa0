// glibc's libmvec called directly, dispatched once on the CPU (why: solver/vector_math.hpp).
// Every function here has been in libmvec since glibc 2.35 (sin, cos, exp, log, pow since 2.22).
#include "solver/vector_math.hpp"

#include <cmath>

// The one-argument functions with an array form (the grammar's names), for X(name).
#define KNOTWORK_ARRAY_FUNCTIONS(X) X(sin) X(cos) X(tan) X(asin) X(acos) X(atan) X(sinh) X(cosh) X(tanh) X(exp) X(log)

#if defined(__x86_64__)
#include <immintrin.h>

// libmvec's x86-64 vector ABI: 'b' 2 lanes in SSE registers, 'd' 4 lanes in AVX2 registers.
// The 'd' ones are declared for AVX2 (their arguments in ymm registers). Clang 14 does not
// honour that for a call with two vector arguments (pow read its base as the exponent at -O0
// and under UBSan; GCC 12 is right at every level), so builds by clang (the sanitizer and fuzz
// builds) take the 2-lane functions, whose registers every x86-64 compiler agrees on.
#define KNOTWORK_AVX2 __attribute__((target("avx2,fma")))
extern "C" {
#define KNOTWORK_DECLARE(f) \
  __m128d _ZGVbN2v_##f(__m128d); \
  KNOTWORK_AVX2 __m256d _ZGVdN4v_##f(__m256d);
KNOTWORK_ARRAY_FUNCTIONS(KNOTWORK_DECLARE)
#undef KNOTWORK_DECLARE
__m128d _ZGVbN2vv_pow(__m128d, __m128d);
__m128d _ZGVbN2vv_atan2(__m128d, __m128d);
KNOTWORK_AVX2 __m256d _ZGVdN4vv_pow(__m256d, __m256d);
KNOTWORK_AVX2 __m256d _ZGVdN4vv_atan2(__m256d, __m256d);
}

namespace knotwork {

namespace {

// The last n % lanes values in a vector padded with copies of the first of them.
template <__m128d (*F)(__m128d)>
void lanes2(const double* a, double* t, long n) {
  long k = 0;
  for (; k + 2 <= n; k += 2) _mm_storeu_pd(t + k, F(_mm_loadu_pd(a + k)));
  if (k < n) {
    alignas(16) double in[2] = {a[k], a[k]}, out[2];
    _mm_store_pd(out, F(_mm_load_pd(in)));
    t[k] = out[0];
  }
}
template <__m128d (*F)(__m128d, __m128d)>
void lanes2(const double* a, const double* b, double* t, long n) {
  long k = 0;
  for (; k + 2 <= n; k += 2) _mm_storeu_pd(t + k, F(_mm_loadu_pd(a + k), _mm_loadu_pd(b + k)));
  if (k < n) {
    alignas(16) double x[2] = {a[k], a[k]}, y[2] = {b[k], b[k]}, out[2];
    _mm_store_pd(out, F(_mm_load_pd(x), _mm_load_pd(y)));
    t[k] = out[0];
  }
}
template <__m256d (*F)(__m256d)>
KNOTWORK_AVX2 void lanes4(const double* a, double* t, long n) {
  long k = 0;
  for (; k + 4 <= n; k += 4) _mm256_storeu_pd(t + k, F(_mm256_loadu_pd(a + k)));
  if (k < n) {
    alignas(32) double in[4], out[4];
    for (int l = 0; l < 4; ++l) in[l] = a[k + (k + l < n ? l : 0)];
    _mm256_store_pd(out, F(_mm256_load_pd(in)));
    for (; k < n; ++k) t[k] = out[k % 4];
  }
}
template <__m256d (*F)(__m256d, __m256d)>
KNOTWORK_AVX2 void lanes4(const double* a, const double* b, double* t, long n) {
  long k = 0;
  for (; k + 4 <= n; k += 4) _mm256_storeu_pd(t + k, F(_mm256_loadu_pd(a + k), _mm256_loadu_pd(b + k)));
  if (k < n) {
    alignas(32) double x[4], y[4], out[4];
    for (int l = 0; l < 4; ++l) x[l] = a[k + (k + l < n ? l : 0)], y[l] = b[k + (k + l < n ? l : 0)];
    _mm256_store_pd(out, F(_mm256_load_pd(x), _mm256_load_pd(y)));
    for (; k < n; ++k) t[k] = out[k % 4];
  }
}

bool wide() {
#if defined(__clang__)
  return false;
#else
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return avx2;
#endif
}

}  // namespace

ArrayFunction1 array_function(const std::string& name) {
  const bool w = wide();
#define KNOTWORK_UNARY(f) \
  if (name == #f) return w ? lanes4<_ZGVdN4v_##f> : lanes2<_ZGVbN2v_##f>;
  KNOTWORK_ARRAY_FUNCTIONS(KNOTWORK_UNARY)
#undef KNOTWORK_UNARY
  return nullptr;
}

ArrayFunction2 array_pow() { return wide() ? lanes4<_ZGVdN4vv_pow> : lanes2<_ZGVbN2vv_pow>; }
ArrayFunction2 array_atan2() { return wide() ? lanes4<_ZGVdN4vv_atan2> : lanes2<_ZGVbN2vv_atan2>; }

const char* vector_math_kind() { return wide() ? "avx2" : "sse2"; }

}  // namespace knotwork

#else  // other CPUs: the scalar functions, a value at a time

namespace knotwork {

namespace {
template <double (*F)(double)>
void one_by_one(const double* a, double* t, long n) {
  for (long k = 0; k < n; ++k) t[k] = F(a[k]);
}
template <double (*F)(double, double)>
void two_by_two(const double* a, const double* b, double* t, long n) {
  for (long k = 0; k < n; ++k) t[k] = F(a[k], b[k]);
}
#define KNOTWORK_SCALAR(f) \
  double f##_of(double a) { return std::f(a); }
KNOTWORK_ARRAY_FUNCTIONS(KNOTWORK_SCALAR)
#undef KNOTWORK_SCALAR
double pow_of(double a, double b) { return std::pow(a, b); }
double atan2_of(double a, double b) { return std::atan2(a, b); }
}  // namespace

ArrayFunction1 array_function(const std::string& name) {
#define KNOTWORK_UNARY(f) \
  if (name == #f) return one_by_one<f##_of>;
  KNOTWORK_ARRAY_FUNCTIONS(KNOTWORK_UNARY)
#undef KNOTWORK_UNARY
  return nullptr;
}
ArrayFunction2 array_pow() { return two_by_two<pow_of>; }
ArrayFunction2 array_atan2() { return two_by_two<atan2_of>; }
const char* vector_math_kind() { return "scalar"; }

}  // namespace knotwork

#endif
