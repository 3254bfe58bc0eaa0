// The one B-spline kernel (basis/core/bspline_kernel.hpp) in both number types it serves:
// rationals, where its identities must hold exactly, and doubles, where they hold to rounding.
#include <catch2/catch.hpp>
#include <gmpxx.h>

#include <cmath>
#include <vector>

#include "basis/core/bspline_kernel.hpp"

using namespace knotwork;

namespace {
const std::vector<std::vector<int>> kKnotVectors = {
    {0, 0, 0, 1, 2, 3, 3, 3}, {0, 0, 0, 0, 1, 1, 3, 4, 4, 4, 4}, {0, 1, 2, 3, 4, 5, 6}, {0, 0, 2, 2, 2, 5, 6, 6}};
int degree_of(const std::vector<int>& t, int index) { return index == 0 ? 2 : index == 1 ? 3 : index == 2 ? 2 : 1; }
}  // namespace

TEST_CASE("bspline_kernel, exact: partition of unity, the span form against the degree recursion, and a split",
          "[bspline][exact]") {
  for (size_t v = 0; v < kKnotVectors.size(); ++v) {
    const int p = degree_of(kKnotVectors[v], int(v));
    std::vector<mpq_class> t(kKnotVectors[v].begin(), kKnotVectors[v].end());
    // Points inside every non-empty span (and the right end of an open vector).
    for (size_t s = 0; s + 1 < t.size(); ++s) {
      if (t[s] == t[s + 1]) continue;
      const mpq_class x = t[s] + (t[s + 1] - t[s]) * mpq_class(2, 7);
      const auto all = bspline_kernel::all_at<mpq_class>(t, p, x);
      // Where p knots exist on both sides: the span form gives the same values, exactly.
      if (int(s) >= p && s + p + 1 < t.size()) {
        std::vector<mpq_class> alive(p + 1);
        bspline_kernel::alive_on_span<mpq_class>(t.data(), int(s), p, x, alive.data());
        for (int j = 0; j <= p; ++j) REQUIRE(alive[j] == all[s - p + j]);
        mpq_class sum = 0;
        for (const auto& a : alive) sum += a;
        REQUIRE(sum == 1);  // partition of unity inside the domain [t_p, t_{n}]
      }
      // Each B-spline is the weighted sum of its two halves after inserting any interior x0.
      for (size_t f = 0; f + p + 1 < t.size(); ++f) {
        const std::vector<mpq_class> local(t.begin() + f, t.begin() + f + p + 2);
        if (local.front() == local.back()) continue;
        const mpq_class x0 = local.front() + (local.back() - local.front()) * mpq_class(3, 5);
        const auto [a, b] = bspline_kernel::split_weights<mpq_class>(local, x0);
        std::vector<mpq_class> w = local;
        w.insert(std::upper_bound(w.begin(), w.end(), x0), x0);
        const std::vector<mpq_class> left(w.begin(), w.end() - 1), right(w.begin() + 1, w.end());
        REQUIRE(bspline_kernel::local_value<mpq_class>(local, x) ==
                a * bspline_kernel::local_value<mpq_class>(left, x) + b * bspline_kernel::local_value<mpq_class>(right, x));
        REQUIRE(all[f] == bspline_kernel::local_value<mpq_class>(local, x));
      }
    }
  }
}

TEST_CASE("bspline_kernel, double: the same identities to rounding", "[bspline]") {
  // Values lie in [0, 1] and each is a sum of at most 2^p products of ratios that each round
  // once: 8 (p + 1) eps bounds the difference between two ways of computing them here.
  for (size_t v = 0; v < kKnotVectors.size(); ++v) {
    const int p = degree_of(kKnotVectors[v], int(v));
    const std::vector<double> t(kKnotVectors[v].begin(), kKnotVectors[v].end());
    const double tol = 8 * (p + 1) * 2.2e-16;
    for (size_t s = 0; s + 1 < t.size(); ++s) {
      if (t[s] == t[s + 1]) continue;
      const double x = t[s] + (t[s + 1] - t[s]) * 0.3;
      const auto all = bspline_kernel::all_at<double>(t, p, x);
      if (int(s) >= p && s + p + 1 < t.size()) {
        std::vector<double> alive(p + 1);
        bspline_kernel::alive_on_span<double>(t.data(), int(s), p, x, alive.data());
        double sum = 0;
        for (int j = 0; j <= p; ++j) {
          REQUIRE(std::abs(alive[j] - all[s - p + j]) <= tol);
          sum += alive[j];
        }
        REQUIRE(std::abs(sum - 1) <= tol);
      }
    }
  }
}

TEST_CASE("bspline_kernel: a B-spline in the B-splines of a finer knot vector", "[bspline][exact]") {
  // N[0,1,2,3] (quadratic) on the fine vector 0, 1/2, 1, ..., 3: the pieces' sum is the
  // B-spline at every point, exactly.
  std::vector<mpq_class> t{0, 1, 2, 3}, fine;
  for (int i = 0; i <= 6; ++i) fine.push_back(mpq_class(i, 2));
  const auto pieces = bspline_kernel::in_finer_knots(t, fine);
  REQUIRE(pieces.size() == 4);  // the windows of 4 knots inside [0, 3]
  for (int k = 0; k < 12; ++k) {
    const mpq_class x(2 * k + 1, 8);
    mpq_class sum = 0;
    for (const auto& [first, c] : pieces)
      sum += c * bspline_kernel::local_value<mpq_class>(std::vector<mpq_class>(fine.begin() + first, fine.begin() + first + 4), x);
    REQUIRE(sum == bspline_kernel::local_value<mpq_class>(t, x));
  }
  REQUIRE_THROWS(bspline_kernel::in_finer_knots<mpq_class>({0, 1, 1, 2}, fine));  // 1 is simple in fine
}
