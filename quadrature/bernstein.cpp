#include "quadrature/bernstein.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>
#include <vector>

namespace knotwork {

void bernstein_values_and_derivatives(int p, double t, double* values, double* derivatives) {
  // de Casteljau-style triangle: B^k_j = (1-t) B^{k-1}_j + t B^{k-1}_{j-1}.
  std::vector<double> lower(p + 1, 0.0);
  values[0] = 1.0;
  for (int k = 1; k <= p; ++k) {
    if (k == p) std::copy(values, values + k, lower.begin());  // degree p-1 values
    double saved = 0.0;
    for (int j = 0; j < k; ++j) {
      const double v = values[j];
      values[j] = saved + (1.0 - t) * v;
      saved = t * v;
    }
    values[k] = saved;
  }
  if (p == 0) {
    derivatives[0] = 0.0;
    return;
  }
  // d/dt B^p_j = p (B^{p-1}_{j-1} - B^{p-1}_j)
  for (int j = 0; j <= p; ++j) {
    const double left = j > 0 ? lower[j - 1] : 0.0;
    const double right = j < p ? lower[j] : 0.0;
    derivatives[j] = p * (left - right);
  }
}

void tensor_bernstein(int p, int q, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                      Eigen::MatrixXd& B, Eigen::MatrixXd& Bu, Eigen::MatrixXd& Bv) {
  const Eigen::Index n = u.size();
  const int nb = (p + 1) * (q + 1);
  B.resize(n, nb);
  Bu.resize(n, nb);
  Bv.resize(n, nb);
  std::vector<double> bu(p + 1), du(p + 1), bv(q + 1), dv(q + 1);
  for (Eigen::Index k = 0; k < n; ++k) {
    bernstein_values_and_derivatives(p, u[k], bu.data(), du.data());
    bernstein_values_and_derivatives(q, v[k], bv.data(), dv.data());
    for (int c = 0; c <= q; ++c)
      for (int a = 0; a <= p; ++a) {
        B(k, a + (p + 1) * c) = bu[a] * bv[c];
        Bu(k, a + (p + 1) * c) = du[a] * bv[c];
        Bv(k, a + (p + 1) * c) = bu[a] * dv[c];
      }
  }
}

namespace {

// Values, first and second derivatives of the degree-p Bernstein polynomials at t: the first
// from bernstein_values_and_derivatives, the second by the same rule applied to the degree p-1
// derivatives (d/dt B^p_j = p (B^{p-1}_{j-1} - B^{p-1}_j)). `lower`, `lower_d`: p entries of scratch.
void bernstein_up_to_second(int p, double t, double* b, double* d1, double* d2, double* lower, double* lower_d) {
  bernstein_values_and_derivatives(p, t, b, d1);
  std::fill(d2, d2 + p + 1, 0.0);
  if (p < 2) return;
  bernstein_values_and_derivatives(p - 1, t, lower, lower_d);
  for (int j = 0; j <= p; ++j) d2[j] = p * ((j > 0 ? lower_d[j - 1] : 0.0) - (j < p ? lower_d[j] : 0.0));
}

}  // namespace

void tensor_bernstein_second(int p, int q, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                             Eigen::MatrixXd& d_uu, Eigen::MatrixXd& d_uv, Eigen::MatrixXd& d_vv) {
  const Eigen::Index n = u.size();
  const int nb = (p + 1) * (q + 1);
  d_uu.resize(n, nb);
  d_uv.resize(n, nb);
  d_vv.resize(n, nb);
  const int m = std::max(p, q) + 1;
  std::vector<double> bu(m), du(m), ddu(m), bv(m), dv(m), ddv(m), lower(m), lower_d(m);
  for (Eigen::Index k = 0; k < n; ++k) {
    bernstein_up_to_second(p, u[k], bu.data(), du.data(), ddu.data(), lower.data(), lower_d.data());
    bernstein_up_to_second(q, v[k], bv.data(), dv.data(), ddv.data(), lower.data(), lower_d.data());
    for (int c = 0; c <= q; ++c)
      for (int a = 0; a <= p; ++a) {
        d_uu(k, a + (p + 1) * c) = ddu[a] * bv[c];
        d_uv(k, a + (p + 1) * c) = du[a] * dv[c];
        d_vv(k, a + (p + 1) * c) = bu[a] * ddv[c];
      }
  }
}

namespace {

BernsteinTable make_table(int p, int q, int nu, int nv) {
  BernsteinTable t;
  t.p = p;
  t.q = q;
  t.rule_u = gauss_legendre(nu);
  t.rule_v = gauss_legendre(nv);
  const int np = nu * nv;
  t.point_u.resize(np);
  t.point_v.resize(np);
  t.weight.resize(np);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int k = i + nu * j;
      t.point_u[k] = t.rule_u.nodes[i];
      t.point_v[k] = t.rule_v.nodes[j];
      t.weight[k] = t.rule_u.weights[i] * t.rule_v.weights[j];
    }
  tensor_bernstein(p, q, t.point_u, t.point_v, t.value, t.d_u, t.d_v);
  return t;
}

}  // namespace

const BernsteinTable& bernstein_table(int p, int q, int nu, int nv) {
  // Called several times per cell by every thread: a thread's own short list of the tables
  // it has used answers without the lock (the shared map is locked only on a thread's miss).
  thread_local std::vector<std::pair<std::array<int, 4>, const BernsteinTable*>> seen;
  const std::array<int, 4> key{p, q, nu, nv};
  for (const auto& [k, table] : seen)
    if (k == key) return *table;
  static std::mutex mutex;
  static std::map<std::tuple<int, int, int, int>, std::unique_ptr<BernsteinTable>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[{p, q, nu, nv}];
  if (!slot) slot = std::make_unique<BernsteinTable>(make_table(p, q, nu, nv));
  seen.emplace_back(key, slot.get());
  return *slot;
}

}  // namespace knotwork
