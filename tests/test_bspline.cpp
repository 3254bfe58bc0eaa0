#include <catch2/catch.hpp>
#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "basis/core/bezier_ops.hpp"
#include "basis/core/bspline_basis.hpp"
#include "quadrature/bernstein.hpp"

using namespace knotwork;

namespace {

// The definition itself (docs/MATH.md §0), recursive, with 0/0 := 0: an oracle that shares
// no code with the library. Right end of the domain belongs to the last non-empty span.
double cox_de_boor(const std::vector<double>& U, int i, int p, double t, double end) {
  if (p == 0) {
    if (U[i] <= t && t < U[i + 1]) return 1.0;
    if (t == end && U[i] < U[i + 1] && U[i + 1] == end) return 1.0;
    return 0.0;
  }
  double r = 0;
  if (U[i + p] > U[i]) r += (t - U[i]) / (U[i + p] - U[i]) * cox_de_boor(U, i, p - 1, t, end);
  if (U[i + p + 1] > U[i + 1])
    r += (U[i + p + 1] - t) / (U[i + p + 1] - U[i + 1]) * cox_de_boor(U, i + 1, p - 1, t, end);
  return r;
}

// Open knot vector on [0, 1] (or [a, b]) with random interior knots and multiplicities <= max_mult.
BSplineBasis1D random_basis(std::mt19937& rng, int p, int max_mult, double a = 0, double b = 1) {
  std::uniform_int_distribution<int> count(0, 6), mult(1, std::max(1, max_mult));
  std::uniform_real_distribution<double> pos(a, b);
  std::vector<double> U(p + 1, a);
  std::vector<double> interior;
  const int n = count(rng);
  for (int k = 0; k < n; ++k) interior.push_back(std::round(pos(rng) * 64) / 64);
  std::sort(interior.begin(), interior.end());
  interior.erase(std::unique(interior.begin(), interior.end()), interior.end());
  for (double x : interior)
    if (x > a && x < b) U.insert(U.end(), mult(rng), x);
  U.insert(U.end(), p + 1, b);
  return BSplineBasis1D(p, U);
}

std::vector<double> sample_points(std::mt19937& rng, const BSplineBasis1D& B, int n) {
  std::uniform_real_distribution<double> d(B.domain_begin(), B.domain_end());
  std::vector<double> t{B.domain_begin(), B.domain_end()};
  for (double k : B.breakpoints()) t.push_back(k);
  for (int i = 0; i < n; ++i) t.push_back(d(rng));
  return t;
}

// Full vector of all basis function values at t.
Eigen::VectorXd all_values(const BSplineBasis1D& B, double t) {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(B.num_functions());
  const int s = B.find_span(t), p = B.degree();
  std::vector<double> N(p + 1);
  B.evaluate(s, t, N.data());
  for (int j = 0; j <= p; ++j) v[s - p + j] = N[j];
  return v;
}

}  // namespace

TEST_CASE("Cox-de Boor values match the recursive definition, and partition of unity", "[bspline]") {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 200; ++trial) {
    const int p = trial % 7;
    const BSplineBasis1D B = random_basis(rng, p, p + 1 > 1 ? p : 1);
    for (double t : sample_points(rng, B, 10)) {
      const Eigen::VectorXd v = all_values(B, t);
      REQUIRE(std::abs(v.sum() - 1.0) < 1e-14);
      REQUIRE(v.minCoeff() >= -1e-15);
      for (int i = 0; i < B.num_functions(); ++i)
        REQUIRE(std::abs(v[i] - cox_de_boor(B.knots(), i, p, t, B.domain_end())) < 1e-13);
    }
  }
}

// Linear precision, with the recursive definition as the basis: sum_i xi_i N_i(t) = t.
// Rounding: p + 1 nonzero terms, each value to 64 eps (the recursion's p levels) times |xi_i|,
// which is at most the largest |knot|.
TEST_CASE("Greville abscissae reproduce the identity", "[bspline]") {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 100; ++trial) {
    const int p = 1 + trial % 6;
    const BSplineBasis1D B = random_basis(rng, p, p);
    const std::vector<double> xi = greville_abscissae(B);
    REQUIRE(static_cast<int>(xi.size()) == B.num_functions());
    double largest = 0;
    for (double k : B.knots()) largest = std::max(largest, std::abs(k));
    for (double t : sample_points(rng, B, 10)) {
      double sum = 0;
      for (int i = 0; i < B.num_functions(); ++i) sum += xi[i] * cox_de_boor(B.knots(), i, p, t, B.domain_end());
      REQUIRE(std::abs(sum - t) <= (p + 1) * 64 * 2.2e-16 * largest);
    }
  }
  REQUIRE_THROWS_AS(greville_abscissae(std::vector<double>{0, 1}, 1), std::invalid_argument);
}

TEST_CASE("B-spline derivatives match finite differences", "[bspline]") {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 100; ++trial) {
    const int p = 1 + trial % 6;
    const BSplineBasis1D B = random_basis(rng, p, 1);
    std::uniform_real_distribution<double> d(0.01, 0.99);
    for (int k = 0; k < 10; ++k) {
      const double t = d(rng), h = 1e-6;
      const int s = B.find_span(t);
      if (t - h < B.knots()[s] || t + h >= B.knots()[s + 1]) continue;  // stay inside the span
      std::vector<double> ders(3 * (p + 1)), dp(3 * (p + 1)), dm(3 * (p + 1));
      B.evaluate_derivatives(s, t, 2, ders.data());
      B.evaluate_derivatives(s, t + h, 2, dp.data());
      B.evaluate_derivatives(s, t - h, 2, dm.data());
      for (int j = 0; j <= p; ++j) {
        const double fd1 = (dp[j] - dm[j]) / (2 * h);
        const double fd2 = (dp[(p + 1) + j] - dm[(p + 1) + j]) / (2 * h);
        REQUIRE(std::abs(ders[(p + 1) + j] - fd1) < 1e-6 * (1 + std::abs(fd1)));
        if (p >= 2) REQUIRE(std::abs(ders[2 * (p + 1) + j] - fd2) < 1e-5 * (1 + std::abs(fd2)));
      }
      // Derivatives of a partition of unity sum to zero.
      double s1 = 0;
      for (int j = 0; j <= p; ++j) s1 += ders[(p + 1) + j];
      REQUIRE(std::abs(s1) < 1e-10);
    }
  }
}

TEST_CASE("de Boor evaluation equals sum of coefficients times basis functions", "[bspline]") {
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  for (int trial = 0; trial < 100; ++trial) {
    const BSplineBasis1D B = random_basis(rng, trial % 6, std::max(1, std::min(2, trial % 6)));
    std::vector<double> c(B.num_functions());
    for (double& x : c) x = g(rng);
    for (double t : sample_points(rng, B, 10)) {
      const double direct = all_values(B, t).dot(Eigen::Map<Eigen::VectorXd>(c.data(), c.size()));
      REQUIRE(std::abs(de_boor(B, c, t) - direct) < 1e-12);
    }
  }
}

TEST_CASE("Knot insertion and degree elevation leave a spline unchanged", "[bspline]") {
  std::mt19937 rng(4);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> pos(0.02, 0.98);
  for (int trial = 0; trial < 150; ++trial) {
    const int p = 1 + trial % 5;
    const BSplineBasis1D B = random_basis(rng, p, p);
    Eigen::MatrixXd c(B.num_functions(), 2);
    for (Eigen::Index i = 0; i < c.size(); ++i) c(i) = g(rng);
    Eigen::MatrixXd ci = c, ce = c, cr = c;
    BSplineBasis1D Bi = B;
    for (int k = 0; k < 3; ++k) Bi = insert_knot(Bi, ci, pos(rng));  // Boehm
    const int r = 1 + trial % 3;
    const BSplineBasis1D Be = elevate_degree(B, ce, r);
    REQUIRE(Be.degree() == p + r);
    // The general refinement operator on the same inserted knots (independent of Boehm).
    cr = refinement_matrix(B, Bi) * c;
    INFO("p = " << p << ", max difference " << (cr - ci).cwiseAbs().maxCoeff() << ", knots " << Eigen::Map<const Eigen::RowVectorXd>(Bi.knots().data(), Bi.knots().size()));
    REQUIRE((cr - ci).cwiseAbs().maxCoeff() < 1e-12);
    for (double t : sample_points(rng, B, 20))
      for (int d = 0; d < 2; ++d) {
        const double ref = all_values(B, t).dot(c.col(d));
        REQUIRE(std::abs(all_values(Bi, t).dot(ci.col(d)) - ref) < 1e-12);
        REQUIRE(std::abs(all_values(Be, t).dot(ce.col(d)) - ref) < 1e-11);
      }
  }
}

TEST_CASE("Bezier extraction reproduces B-spline evaluation on random knot vectors", "[bspline]") {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 300; ++trial) {
    const int p = trial % 8;
    const BSplineBasis1D B = random_basis(rng, p, std::max(1, p), -0.5, 2.0);
    const auto C = bezier_extraction(B);
    const auto spans = B.element_spans();
    REQUIRE(C.size() == spans.size());
    std::uniform_real_distribution<double> d(0, 1);
    for (size_t e = 0; e < spans.size(); ++e) {
      const double a = B.knots()[spans[e]], b = B.knots()[spans[e] + 1];
      for (int k = 0; k < 5; ++k) {
        const double s = k == 0 ? 0.0 : (k == 1 ? 1.0 - 1e-12 : d(rng));
        const double t = a + s * (b - a);
        std::vector<double> bern(p + 1), dummy(p + 1);
        bernstein_values_and_derivatives(p, s, bern.data(), dummy.data());
        const Eigen::VectorXd via = C[e] * Eigen::Map<Eigen::VectorXd>(bern.data(), p + 1);
        for (int j = 0; j <= p; ++j)
          REQUIRE(std::abs(via[j] - cox_de_boor(B.knots(), spans[e] - p + j, p, t, B.domain_end())) < 1e-13);
      }
    }
  }
}

TEST_CASE("Bernstein subdivision and elevation matrices", "[bspline]") {
  std::mt19937 rng(6);
  std::normal_distribution<double> g;
  for (int p = 0; p <= 7; ++p) {
    Eigen::VectorXd beta(p + 1);
    for (auto& x : beta) x = g(rng);
    auto eval = [](int q, const Eigen::VectorXd& c, double t) {
      std::vector<double> b(q + 1), d(q + 1);
      bernstein_values_and_derivatives(q, t, b.data(), d.data());
      return Eigen::Map<Eigen::VectorXd>(b.data(), q + 1).dot(c);
    };
    const double s = 0.2, t = 0.65;
    const Eigen::VectorXd sub = subdivision_matrix(p, s, t) * beta;
    const Eigen::VectorXd el = degree_elevation_matrix(p, 2) * beta;
    for (double x : {0.0, 0.3, 0.77, 1.0}) {
      REQUIRE(std::abs(eval(p, sub, x) - eval(p, beta, s + x * (t - s))) < 1e-13);
      REQUIRE(std::abs(eval(p + 2, el, x) - eval(p, beta, x)) < 1e-13);
    }
  }
}

TEST_CASE("Invalid knot vectors are rejected with a reason", "[bspline]") {
  REQUIRE_THROWS_WITH(BSplineBasis1D(2, {0, 0, 0, 0.6, 0.5, 1, 1, 1}), Catch::Contains("not non-decreasing"));
  REQUIRE_THROWS_WITH(BSplineBasis1D(1, {0, 0, 0.5, 0.5, 0.5, 1, 1}), Catch::Contains("multiplicity 3"));
  REQUIRE_THROWS_WITH(BSplineBasis1D(2, {0, 0, 1, 1}), Catch::Contains("at least 6 knots"));
  REQUIRE_THROWS_WITH(BSplineBasis1D(1, {0, 0, NAN, 1, 1}), Catch::Contains("not a finite"));
  REQUIRE_THROWS(BSplineBasis1D(1, {1, 1, 1, 1}));
}

TEST_CASE("One B-spline's Bernstein piece on a sub-interval matches the recursive definition", "[bspline]") {
  // single_bspline_bernstein evaluates blossoms; the oracle is the definition on the local
  // knot vector, sampled inside [a, b] (Bernstein polynomials of degree d at d + 3 points).
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  int pieces = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int d = trial % 7;
    std::uniform_int_distribution<int> mult(1, d + 1);
    std::vector<double> knots;
    double x = std::round(unit(rng) * 8) / 8 - 0.5;
    while (static_cast<int>(knots.size()) < d + 2) {
      const int m = std::min(mult(rng), d + 2 - static_cast<int>(knots.size()));
      knots.insert(knots.end(), m, x);
      x += 0.125 + std::round(unit(rng) * 8) / 16;
    }
    for (int m = 0; m <= d; ++m) {
      if (!(knots[m] < knots[m + 1])) continue;
      // The whole span, and a random sub-interval of it.
      for (int sub = 0; sub < 2; ++sub) {
        double a = knots[m], b = knots[m + 1];
        if (sub == 1) {
          const double s = unit(rng), t = unit(rng);
          a = knots[m] + std::min(s, t) * (knots[m + 1] - knots[m]);
          b = knots[m] + std::max(s, t) * (knots[m + 1] - knots[m]);
          if (!(a < b)) continue;
        }
        const Eigen::VectorXd c = single_bspline_bernstein(knots, a, b);
        REQUIRE(c.size() == d + 1);
        for (int k = 0; k <= d + 2; ++k) {
          const double s = double(k) / (d + 3);
          std::vector<double> bern(d + 1), dummy(d + 1);
          bernstein_values_and_derivatives(d, s, bern.data(), dummy.data());
          const double value = Eigen::Map<Eigen::VectorXd>(bern.data(), d + 1).dot(c);
          REQUIRE(std::abs(value - cox_de_boor(knots, 0, d, a + s * (b - a), knots.back())) < 1e-13);
        }
        ++pieces;
      }
    }
    // Outside the support: the zero polynomial; across a knot: refused.
    REQUIRE(single_bspline_bernstein(knots, knots.back(), knots.back() + 1).isZero());
    REQUIRE(single_bspline_bernstein(knots, knots.front() - 1, knots.front()).isZero());
    if (d >= 1 && knots.front() < knots[d] && knots[d] < knots.back())
      REQUIRE_THROWS_WITH(single_bspline_bernstein(knots, knots.front(), knots.back()),
                          Catch::Contains("not inside one knot span"));
  }
  REQUIRE(pieces > 800);
}
