#include "basis/core/bezier_ops.hpp"

#include <stdexcept>

#include <algorithm>
#include <cmath>

namespace knotwork {

namespace {
double binomial(int n, int k) {
  if (k < 0 || k > n) return 0.0;
  double r = 1.0;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}
}  // namespace

Eigen::MatrixXd subdivision_matrix(int p, double s, double t) {
  // Entry (i, j): blossom of B^p_j at (s^{p-i}, t^i), i.e. the i-th Bernstein
  // coefficient of B^p_j restricted to [s, t].
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(p + 1, p + 1);
  for (int i = 0; i <= p; ++i)
    for (int j = 0; j <= p; ++j) {
      double sum = 0.0;
      for (int l = std::max(0, j - (p - i)); l <= std::min(i, j); ++l)
        sum += binomial(i, l) * binomial(p - i, j - l) * std::pow(t, l) *
               std::pow(1.0 - t, i - l) * std::pow(s, j - l) * std::pow(1.0 - s, p - i - j + l);
      m(i, j) = sum;
    }
  return m;
}

Eigen::MatrixXd degree_elevation_matrix(int p, int r) {
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(p + r + 1, p + 1);
  for (int j = 0; j <= p; ++j)
    for (int i = j; i <= j + r; ++i)
      m(i, j) = binomial(p, j) * binomial(r, i - j) / binomial(p + r, i);
  return m;
}

}  // namespace knotwork

#include <Eigen/LU>
#include "quadrature/bernstein.hpp"

namespace knotwork {
Eigen::MatrixXd bernstein_interpolation_inverse(int p, int q) {
  const int nb = (p + 1) * (q + 1);
  Eigen::MatrixXd A(nb, nb);
  std::vector<double> bu(p + 1), du(p + 1), bv(q + 1), dv(q + 1);
  for (int j = 0; j <= q; ++j)
    for (int i = 0; i <= p; ++i) {
      bernstein_values_and_derivatives(p, p > 0 ? double(i) / p : 0.5, bu.data(), du.data());
      bernstein_values_and_derivatives(q, q > 0 ? double(j) / q : 0.5, bv.data(), dv.data());
      for (int c = 0; c <= q; ++c)
        for (int a = 0; a <= p; ++a) A(i + (p + 1) * j, a + (p + 1) * c) = bu[a] * bv[c];
    }
  return A.fullPivLu().inverse();
}
Eigen::MatrixXd bernstein_interpolant(int p, int q, int r, const Eigen::MatrixXd& values) {
  const int degree[3] = {p, q, r};
  const Eigen::Index n[3] = {p + 1, q + 1, r + 1};
  if (values.rows() != n[0] * n[1] * n[2]) throw std::invalid_argument("bernstein_interpolant: one value per node");
  Eigen::MatrixXd out = values;
  for (int d = 0; d < 3; ++d) {
    const Eigen::MatrixXd inverse = bernstein_interpolation_inverse(degree[d], 0);  // univariate, n[d] x n[d]
    const Eigen::Index stride = d == 0 ? 1 : d == 1 ? n[0] : n[0] * n[1];
    Eigen::VectorXd line(n[d]);
    for (Eigen::Index col = 0; col < out.cols(); ++col)
      for (Eigen::Index start = 0; start < out.rows(); ++start) {
        if ((start / stride) % n[d] != 0) continue;  // the first node of each line along d
        for (Eigen::Index i = 0; i < n[d]; ++i) line[i] = out(start + i * stride, col);
        const Eigen::VectorXd coefficients = inverse * line;
        for (Eigen::Index i = 0; i < n[d]; ++i) out(start + i * stride, col) = coefficients[i];
      }
  }
  return out;
}

}  // namespace knotwork
