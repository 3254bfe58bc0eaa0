#include "basis/tensor/nurbs_geometry_map.hpp"

#include "basis/core/bezier_ops.hpp"
#include "basis/core/small_products.hpp"
#include "quadrature/bernstein.hpp"

#include <atomic>

namespace knotwork {

NurbsGeometryMap::NurbsGeometryMap(const TensorDiscretization& d)
    : pu_(d.geometry_u.degree()),
      pv_(d.geometry_v.degree()),
      nu_(d.geometry_u.num_functions()),
      elements_u_(d.elements_u),
      first_row_(d.first_row),
      net_first_row_(d.net_first_row),
      spans_u_(d.geometry_u.element_spans()),
      spans_v_(d.geometry_v.element_spans()),
      cu_(bezier_extraction(d.geometry_u)),
      cv_(bezier_extraction(d.geometry_v)),
      net_(d.geometry_homogeneous),
      patch_u_(d.patch.basis_u),
      patch_v_(d.patch.basis_v) {
  const Eigen::Index n = d.patch.weights.size();
  patch_net_.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    patch_net_.row(i) << d.patch.weights[i] * d.patch.control_points(i, 0),
        d.patch.weights[i] * d.patch.control_points(i, 1), d.patch.weights[i];
  // An element lies inside one span of the patch (the space's knots refine the patch's): the
  // span holding its middle.
  auto intervals = [](const BSplineBasis1D& space, const BSplineBasis1D& patch) {
    std::vector<Interval> out;
    const auto& t = space.knots();
    for (int s : space.element_spans()) {
      const double a = t[s], b = t[s + 1];
      out.push_back({patch.find_span(0.5 * (a + b)), a, b - a});
    }
    return out;
  };
  intervals_u_ = intervals(d.space_u, patch_u_);
  intervals_v_ = intervals(d.space_v, patch_v_);
  static std::atomic<unsigned long> maps{0};
  serial_ = ++maps;
}

void NurbsGeometryMap::homogeneous_bezier(int cell, Eigen::MatrixX3d& out) const {
  const int iu = cell % elements_u_, iv = first_row_ + cell / elements_u_;
  const int su = spans_u_[iu] - pu_, sv = spans_v_[iv] - pv_ - net_first_row_;
  out.resize((pu_ + 1) * (pv_ + 1), 3);
  thread_local Eigen::MatrixXd local, half, bez;
  local.resize(pu_ + 1, pv_ + 1);
  for (int k = 0; k < 3; ++k) {
    for (int av = 0; av <= pv_; ++av)
      for (int au = 0; au <= pu_; ++au) local(au, av) = net_((su + au) + nu_ * (sv + av), k);
    // Tiny products ((p+1)^2 per coordinate): coefficient-based kernels, not blocked GEMM.
    half.noalias() = cu_[iu].transpose().lazyProduct(local);
    bez.noalias() = half.lazyProduct(cv_[iv]);
    out.col(k) = Eigen::Map<const Eigen::VectorXd>(bez.data(), bez.size());
  }
}

namespace {

// The patch's B-splines alive on `span` (and their derivatives in the element's reference
// coordinate) at the rule's points mapped into [from, from + length]: points x (p+1).
void patch_table(const BSplineBasis1D& basis, int span, double from, double length, const QuadratureRule1D& rule,
                 Eigen::MatrixXd& value, Eigen::MatrixXd& derivative) {
  const int p = basis.degree(), n = static_cast<int>(rule.nodes.size());
  value.resize(n, p + 1);
  derivative.resize(n, p + 1);
  thread_local std::vector<double> d;
  d.resize(2 * (p + 1));
  for (int i = 0; i < n; ++i) {
    basis.evaluate_derivatives(span, from + rule.nodes[i] * length, 1, d.data());
    for (int a = 0; a <= p; ++a) value(i, a) = d[a], derivative(i, a) = d[p + 1 + a] * length;
  }
}

}  // namespace

const NurbsGeometryMap::RuleTables& NurbsGeometryMap::tables(bool along_u, int n) const {
  // The serial, not the address, names the map: a new map may reuse a freed one's address.
  struct Last {
    unsigned long serial = 0;
    int n = -1;
    const RuleTables* tables = nullptr;
  };
  thread_local Last last[2];
  Last& mine = last[along_u ? 0 : 1];
  if (mine.serial == serial_ && mine.n == n) return *mine.tables;
  std::scoped_lock lock(mutex_);
  auto& slot = tables_[{along_u, n}];
  if (!slot) {
    slot = std::make_unique<RuleTables>();
    const QuadratureRule1D rule = gauss_legendre(n);
    for (const Interval& e : along_u ? intervals_u_ : intervals_v_) {
      slot->value.emplace_back();
      slot->derivative.emplace_back();
      patch_table(along_u ? patch_u_ : patch_v_, e.span, e.from, e.length, rule, slot->value.back(),
                  slot->derivative.back());
    }
  }
  mine = {serial_, n, slot.get()};
  return *slot;
}

void NurbsGeometryMap::evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const {
  evaluate_element_at_rule(cell % elements_u_, first_row_ + cell / elements_u_, nu, nv, out);
}

void NurbsGeometryMap::evaluate_element_at_rule(int eu, int ev, int nu, int nv, GeometryAtPoints& out) const {
  // h(u_i, v_j) = sum_ab Nu_a(u_i) Nv_b(v_j) P_ab over the patch's own (pu+1)(pv+1) control
  // points, summed one direction at a time: the cost follows the geometry's degree, not the
  // space's (a bilinear square costs the same at p = 2 and p = 10).
  const int gu = patch_u_.degree(), gv = patch_v_.degree(), n_u = patch_u_.num_functions();
  const int su = intervals_u_[eu].span - gu, sv = intervals_v_[ev].span - gv;
  const RuleTables& table_u = tables(true, nu);
  const RuleTables& table_v = tables(false, nv);
  const Eigen::MatrixXd &Nu = table_u.value[eu], &Nuu = table_u.derivative[eu];
  const Eigen::MatrixXd &Nv = table_v.value[ev], &Nvv = table_v.derivative[ev];
  thread_local Eigen::MatrixXd P, T, Tu, S;
  thread_local Eigen::MatrixX3d h, hu, hv;
  const Eigen::Index n = static_cast<Eigen::Index>(nu) * nv;
  h.resize(n, 3);
  hu.resize(n, 3);
  hv.resize(n, 3);
  P.resize(gv + 1, gu + 1);
  for (int k = 0; k < 3; ++k) {
    // P^T, so that T = Nu P is product_abt(Nu, P^T).
    for (int av = 0; av <= gv; ++av)
      for (int au = 0; au <= gu; ++au) P(av, au) = patch_net_((su + au) + n_u * (sv + av), k);
    product_abt(Nu, P, T);  // nu x (gv+1): summed over u
    product_abt(Nuu, P, Tu);
    // Point i + nu j of column k is (T Nv^T)(i, j), stored column by column.
    product_abt(T, Nv, S);
    h.col(k) = S.reshaped();
    product_abt(Tu, Nv, S);
    hu.col(k) = S.reshaped();
    product_abt(T, Nvv, S);
    hv.col(k) = S.reshaped();
  }
  dehomogenize_map(h, hu, hv, out);
}

void NurbsGeometryMap::evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                GeometryAtPoints& out) const {
  Eigen::MatrixXd B, Bu, Bv;
  tensor_bernstein(pu_, pv_, u, v, B, Bu, Bv);
  Eigen::MatrixX3d bez;
  homogeneous_bezier(cell, bez);
  dehomogenize_map(B * bez, Bu * bez, Bv * bez, out);
}

BezierGeometryCell NurbsGeometryMap::bezier_cell(int cell) const {
  Eigen::MatrixX3d bez;
  homogeneous_bezier(cell, bez);
  BezierGeometryCell g;
  g.degree_u = pu_;
  g.degree_v = pv_;
  g.weights = bez.col(2);
  g.points = bez.leftCols<2>().array().colwise() / bez.col(2).array();
  return g;
}

// From the cell's homogeneous Bezier net: H = (w x, w y, w) and its first and second
// derivatives, then the quotient rule for x = H / w, one coordinate at a time.
bool NurbsGeometryMap::second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                          Eigen::MatrixXd& out) const {
  thread_local Eigen::MatrixX3d bez;
  thread_local Eigen::MatrixXd B, Bu, Bv, Buu, Buv, Bvv;
  homogeneous_bezier(cell, bez);
  tensor_bernstein(pu_, pv_, u, v, B, Bu, Bv);
  tensor_bernstein_second(pu_, pv_, u, v, Buu, Buv, Bvv);
  const Eigen::MatrixX3d H = B * bez, Hu = Bu * bez, Hv = Bv * bez, Huu = Buu * bez, Huv = Buv * bez, Hvv = Bvv * bez;
  out.resize(u.size(), 6);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const double w = H(k, 2);
    for (int d = 0; d < 2; ++d) {
      const double g = H(k, d) / w;
      const double gu = (Hu(k, d) - g * Hu(k, 2)) / w, gv = (Hv(k, d) - g * Hv(k, 2)) / w;
      out(k, 3 * d + 0) = (Huu(k, d) - 2 * gu * Hu(k, 2) - g * Huu(k, 2)) / w;
      out(k, 3 * d + 1) = (Huv(k, d) - gu * Hv(k, 2) - gv * Hu(k, 2) - g * Huv(k, 2)) / w;
      out(k, 3 * d + 2) = (Hvv(k, d) - 2 * gv * Hv(k, 2) - g * Hvv(k, 2)) / w;
    }
  }
  return true;
}

}  // namespace knotwork
