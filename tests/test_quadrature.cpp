#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "quadrature/bernstein.hpp"
#include "quadrature/gauss_legendre.hpp"

using namespace knotwork;

TEST_CASE("Gauss-Legendre integrates x^k exactly for k <= 2n-1", "[quadrature]") {
  for (int n = 1; n <= 30; ++n) {
    const auto r = gauss_legendre(n);
    double wsum = 0;
    for (double w : r.weights) {
      REQUIRE(w > 0);
      wsum += w;
    }
    REQUIRE(std::abs(wsum - 1.0) < 1e-14);
    for (int i = 0; i < n; ++i) {
      REQUIRE(r.nodes[i] > 0);
      REQUIRE(r.nodes[i] < 1);
      REQUIRE(std::abs(r.nodes[i] + r.nodes[n - 1 - i] - 1.0) < 1e-15);  // symmetric
    }
    for (int k = 0; k <= 2 * n - 1; ++k) {
      double q = 0;
      for (int i = 0; i < n; ++i) q += r.weights[i] * std::pow(r.nodes[i], k);
      INFO("n = " << n << ", k = " << k);
      REQUIRE(std::abs(q - 1.0 / (k + 1)) < 2e-15);
    }
    // ... and not for 2n: the rule is what it claims, no more (visible while the
    // error term (n!)^4 / ((2n+1) ((2n)!)^2) is above roundoff).
    if (n > 6) continue;
    double q = 0;
    for (int i = 0; i < n; ++i) q += r.weights[i] * std::pow(r.nodes[i], 2 * n);
    REQUIRE(std::abs(q - 1.0 / (2 * n + 1)) > 1e-15);
  }
}

TEST_CASE("Gauss-Legendre matches the known 3-point rule", "[quadrature]") {
  const auto r = gauss_legendre(3);
  const double s = std::sqrt(3.0 / 5.0) / 2;
  REQUIRE(std::abs(r.nodes[0] - (0.5 - s)) < 2e-16);
  REQUIRE(std::abs(r.nodes[1] - 0.5) < 2e-16);
  REQUIRE(std::abs(r.weights[0] - 5.0 / 18) < 2e-16);
  REQUIRE(std::abs(r.weights[1] - 8.0 / 18) < 2e-16);
  REQUIRE_THROWS(gauss_legendre(0));
}

TEST_CASE("Trivariate Bernstein tables: partition of unity, derivatives, exact integrals, the 2D values", "[quadrature]") {
  const double eps = std::numeric_limits<double>::epsilon();
  for (int p = 0; p <= 4; ++p) {
    const int q = p + 1, r = std::max(p - 1, 0);
    const BernsteinTable& t = bernstein_table(p, q, r, p + 1, q + 1, r + 2);
    REQUIRE(&t == &bernstein_table(p, q, r, p + 1, q + 1, r + 2));  // cached
    REQUIRE(t.num_functions() == (p + 1) * (q + 1) * (r + 1));
    REQUIRE(t.num_points() == (p + 1) * (q + 1) * (r + 2));
    // The de Casteljau values are sums of products of numbers in [0, 1]: each value and each
    // sum carries at most a few (p + q + r + 3) roundings.
    const double tolerance = 4 * (p + q + r + 3) * eps;
    for (int k = 0; k < t.num_points(); ++k) {
      CHECK(std::abs(t.value.row(k).sum() - 1.0) <= tolerance * t.num_functions());
      // Each derivative row sums to 0; its entries are at most the degree in size.
      CHECK(std::abs(t.d_u.row(k).sum()) <= tolerance * t.num_functions() * (p + 1));
      CHECK(std::abs(t.d_v.row(k).sum()) <= tolerance * t.num_functions() * (q + 1));
      CHECK(std::abs(t.d_w.row(k).sum()) <= tolerance * t.num_functions() * (r + 1));
    }
    // Every Bernstein polynomial of degrees (p, q, r) integrates to 1/((p+1)(q+1)(r+1)), and
    // these rules are exact for its degree.
    const Eigen::VectorXd integrals = t.value.transpose() * t.weight;
    for (Eigen::Index b = 0; b < integrals.size(); ++b)
      CHECK(std::abs(integrals[b] - 1.0 / t.num_functions()) <= tolerance * t.num_points() / t.num_functions());
    // A layer of the trivariate table at w is the bivariate table times the univariate
    // Bernstein values at w (the same products, formed in the same order).
    const BernsteinTable& flat = bernstein_table(p, q, p + 1, q + 1);
    std::vector<double> bw(r + 1), dw(r + 1);
    for (int l = 0; l < r + 2; ++l) {
      bernstein_values_and_derivatives(r, t.rule_w.nodes[l], bw.data(), dw.data());
      for (int k = 0; k < flat.num_points(); ++k)
        for (int c = 0; c <= r; ++c)
          for (int b = 0; b < flat.num_functions(); ++b) {
            const int point = k + flat.num_points() * l, function = b + flat.num_functions() * c;
            CHECK(t.value(point, function) == flat.value(k, b) * bw[c]);
            CHECK(t.d_u(point, function) == flat.d_u(k, b) * bw[c]);
            CHECK(t.d_w(point, function) == flat.value(k, b) * dw[c]);
          }
    }
  }
  CHECK_THROWS_AS(bernstein_table(1, 1, 1, 2, 2, 0), std::invalid_argument);
}

TEST_CASE("Bernstein tables: partition of unity, derivatives, exact integrals", "[quadrature]") {
  for (int p = 0; p <= 8; ++p) {
    const BernsteinTable& t = bernstein_table(p, p + 1, p + 1, p + 2);
    REQUIRE(&t == &bernstein_table(p, p + 1, p + 1, p + 2));  // cached
    for (int k = 0; k < t.num_points(); ++k) {
      REQUIRE(std::abs(t.value.row(k).sum() - 1.0) < 1e-14);
      REQUIRE(std::abs(t.d_u.row(k).sum()) < 1e-12);
      REQUIRE(std::abs(t.d_v.row(k).sum()) < 1e-12);
    }
    // Every Bernstein polynomial of degree (p, q) integrates to 1/((p+1)(q+1)).
    const Eigen::VectorXd integrals = t.value.transpose() * t.weight;
    for (Eigen::Index b = 0; b < integrals.size(); ++b)
      REQUIRE(std::abs(integrals[b] - 1.0 / ((p + 1) * (p + 2))) < 1e-15);
  }
  // Derivatives against central differences.
  for (int p = 1; p <= 8; ++p) {
    std::vector<double> v(p + 1), d(p + 1), vp(p + 1), vm(p + 1), dummy(p + 1);
    const double t = 0.37, h = 1e-6;
    bernstein_values_and_derivatives(p, t, v.data(), d.data());
    bernstein_values_and_derivatives(p, t + h, vp.data(), dummy.data());
    bernstein_values_and_derivatives(p, t - h, vm.data(), dummy.data());
    for (int j = 0; j <= p; ++j) REQUIRE(std::abs(d[j] - (vp[j] - vm[j]) / (2 * h)) < 1e-8);
  }
}
