#include "quadrature/bernstein.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
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

namespace {

// Tensor-product Bernstein polynomials in `dim` (2 or 3) directions of degrees `degree` at the
// points (coordinate[0][k], coordinate[1][k][, coordinate[2][k]]): values and the reference
// derivative along each direction, function a + (p+1) b [+ (p+1)(q+1) c]. The products are
// formed direction by direction from u on, so the 2D values are those of two factors.
void tensor_bernstein_in(int dim, const int* degree, const Eigen::VectorXd* const* coordinate, Eigen::MatrixXd& B,
                         Eigen::MatrixXd* const* derivative) {
  const Eigen::Index n = coordinate[0]->size();
  const int p = degree[0], q = degree[1], r = dim == 3 ? degree[2] : 0;
  const int nb = (p + 1) * (q + 1) * (r + 1);
  B.resize(n, nb);
  for (int d = 0; d < dim; ++d) derivative[d]->resize(n, nb);
  // In 2D the third factor is the constant 1 (degree 0), and x * 1 is x exactly.
  std::vector<double> b[3] = {{}, {}, {1.0}}, db[3] = {{}, {}, {0.0}};
  for (int d = 0; d < dim; ++d) b[d].resize(degree[d] + 1), db[d].resize(degree[d] + 1);
  for (Eigen::Index k = 0; k < n; ++k) {
    for (int d = 0; d < dim; ++d) bernstein_values_and_derivatives(degree[d], (*coordinate[d])[k], b[d].data(), db[d].data());
    for (int c = 0; c <= r; ++c)
      for (int e = 0; e <= q; ++e)
        for (int a = 0; a <= p; ++a) {
          const int f = a + (p + 1) * (e + (q + 1) * c);
          B(k, f) = b[0][a] * b[1][e] * b[2][c];
          (*derivative[0])(k, f) = db[0][a] * b[1][e] * b[2][c];
          (*derivative[1])(k, f) = b[0][a] * db[1][e] * b[2][c];
          if (dim == 3) (*derivative[2])(k, f) = b[0][a] * b[1][e] * db[2][c];
        }
  }
}

}  // namespace

void tensor_bernstein(int p, int q, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                      Eigen::MatrixXd& B, Eigen::MatrixXd& Bu, Eigen::MatrixXd& Bv) {
  const int degree[2] = {p, q};
  const Eigen::VectorXd* coordinate[2] = {&u, &v};
  Eigen::MatrixXd* derivative[2] = {&Bu, &Bv};
  tensor_bernstein_in(2, degree, coordinate, B, derivative);
}

void tensor_bernstein(int p, int q, int r, const Eigen::VectorXd& u, const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                      Eigen::MatrixXd& B, Eigen::MatrixXd& Bu, Eigen::MatrixXd& Bv, Eigen::MatrixXd& Bw) {
  const int degree[3] = {p, q, r};
  const Eigen::VectorXd* coordinate[3] = {&u, &v, &w};
  Eigen::MatrixXd* derivative[3] = {&Bu, &Bv, &Bw};
  tensor_bernstein_in(3, degree, coordinate, B, derivative);
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

void tensor_bernstein_second(int p, int q, int r, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                             const Eigen::VectorXd& w, Eigen::MatrixXd (&second)[6]) {
  const Eigen::Index n = u.size();
  const int nb = (p + 1) * (q + 1) * (r + 1);
  for (Eigen::MatrixXd& m : second) m.resize(n, nb);
  const int m = std::max({p, q, r}) + 1;
  std::vector<double> lower(m), lower_d(m);
  std::vector<double> b[3], d[3], dd[3];
  for (int k = 0; k < 3; ++k) b[k].resize(m), d[k].resize(m), dd[k].resize(m);
  const int degree[3] = {p, q, r};
  const Eigen::VectorXd* at[3] = {&u, &v, &w};
  for (Eigen::Index k = 0; k < n; ++k) {
    for (int x = 0; x < 3; ++x)
      bernstein_up_to_second(degree[x], (*at[x])[k], b[x].data(), d[x].data(), dd[x].data(), lower.data(), lower_d.data());
    for (int c = 0; c <= r; ++c)
      for (int e = 0; e <= q; ++e)
        for (int a = 0; a <= p; ++a) {
          const int f = a + (p + 1) * (e + (q + 1) * c);
          second[0](k, f) = dd[0][a] * b[1][e] * b[2][c];
          second[1](k, f) = d[0][a] * d[1][e] * b[2][c];
          second[2](k, f) = d[0][a] * b[1][e] * d[2][c];
          second[3](k, f) = b[0][a] * dd[1][e] * b[2][c];
          second[4](k, f) = b[0][a] * d[1][e] * d[2][c];
          second[5](k, f) = b[0][a] * b[1][e] * dd[2][c];
        }
  }
}

namespace {

// nw = 0: a 2D table (r is then 0).
BernsteinTable make_table(int p, int q, int r, int nu, int nv, int nw) {
  BernsteinTable t;
  t.p = p;
  t.q = q;
  t.r = r;
  t.rule_u = gauss_legendre(nu);
  t.rule_v = gauss_legendre(nv);
  if (nw > 0) t.rule_w = gauss_legendre(nw);
  const int layers = std::max(nw, 1);
  const int np = nu * nv * layers;
  t.point_u.resize(np);
  t.point_v.resize(np);
  if (nw > 0) t.point_w.resize(np);
  t.weight.resize(np);
  for (int l = 0; l < layers; ++l)
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        const int k = i + nu * (j + nv * l);
        t.point_u[k] = t.rule_u.nodes[i];
        t.point_v[k] = t.rule_v.nodes[j];
        t.weight[k] = t.rule_u.weights[i] * t.rule_v.weights[j];
        if (nw > 0) {
          t.point_w[k] = t.rule_w.nodes[l];
          t.weight[k] *= t.rule_w.weights[l];
        }
      }
  if (nw > 0) tensor_bernstein(p, q, r, t.point_u, t.point_v, t.point_w, t.value, t.d_u, t.d_v, t.d_w);
  else tensor_bernstein(p, q, t.point_u, t.point_v, t.value, t.d_u, t.d_v);
  return t;
}

// Called several times per cell by every thread: a thread's own short list of the tables it
// has used answers without the lock (the shared map is locked only on a thread's miss).
const BernsteinTable& cached_table(int p, int q, int r, int nu, int nv, int nw) {
  thread_local std::vector<std::pair<std::array<int, 6>, const BernsteinTable*>> seen;
  const std::array<int, 6> key{p, q, r, nu, nv, nw};
  for (const auto& [k, table] : seen)
    if (k == key) return *table;
  static std::mutex mutex;
  static std::map<std::array<int, 6>, std::unique_ptr<BernsteinTable>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[key];
  if (!slot) slot = std::make_unique<BernsteinTable>(make_table(p, q, r, nu, nv, nw));
  seen.emplace_back(key, slot.get());
  return *slot;
}

}  // namespace

const BernsteinTable& bernstein_table(int p, int q, int nu, int nv) { return cached_table(p, q, 0, nu, nv, 0); }

const BernsteinTable& bernstein_table(int p, int q, int r, int nu, int nv, int nw) {
  if (nw < 1) throw std::invalid_argument("bernstein_table: a trivariate rule needs nw >= 1");
  return cached_table(p, q, r, nu, nv, nw);
}

}  // namespace knotwork
