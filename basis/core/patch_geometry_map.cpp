// The one NURBS map (geometry_map.hpp): a patch evaluated on the cells of a space in its
// parameter domain, from univariate tables at quadrature points, directly elsewhere, and as
// exact rational Bezier cells.
#include <algorithm>
#include <atomic>
#include <bit>
#include <cstdint>
#include <map>
#include <mutex>
#include <sstream>
#include <unordered_map>

#include "basis/core/bezier_ops.hpp"
#include "basis/core/geometry_map.hpp"
#include "basis/core/input_error.hpp"
#include "basis/core/small_products.hpp"
#include "quadrature/bernstein.hpp"
#include "quadrature/gauss_legendre.hpp"

namespace knotwork {

// The patch's B-splines on each interval at an n-point Gauss rule, per direction, made on
// first use of a rule and kept; each thread remembers its last lookup (by the map's serial: a
// new map may reuse a freed one's address).
struct PatchGeometryMap::RuleTables {
  std::vector<Eigen::MatrixXd> value, derivative;  // per interval: points x (degree + 1)
};
struct PatchGeometryMap::Lookup {
  std::mutex mutex;
  std::map<std::pair<bool, int>, std::unique_ptr<RuleTables>> tables;
  unsigned long serial = 0;
};

PatchGeometryMap::~PatchGeometryMap() = default;

namespace {

unsigned long next_serial() {
  static std::atomic<unsigned long> maps{0};
  return ++maps;
}

Eigen::MatrixX3d homogeneous_net(const NurbsPatch& p) {
  Eigen::MatrixX3d net(p.weights.size(), 3);
  for (Eigen::Index i = 0; i < net.rows(); ++i)
    net.row(i) << p.weights[i] * p.control_points(i, 0), p.weights[i] * p.control_points(i, 1), p.weights[i];
  return net;
}

}  // namespace

PatchGeometryMap::PatchGeometryMap(const BezierMesh& mesh, NurbsPatch patch)
    : PatchGeometryMap(mesh, std::move(patch), nullptr) {}

PatchGeometryMap::PatchGeometryMap(const BezierMesh& mesh, NurbsPatch patch, ElementGrid grid)
    : PatchGeometryMap(mesh, std::move(patch), &grid) {}

PatchGeometryMap::PatchGeometryMap(const BezierMesh& mesh, NurbsPatch patch, const ElementGrid* grid)
    : mesh_(mesh),
      patch_(std::move(patch)),
      net_(homogeneous_net(patch_)),
      extraction_u_(bezier_extraction(patch_.basis_u)),
      extraction_v_(bezier_extraction(patch_.basis_v)),
      breaks_u_(patch_.basis_u.breakpoints()),
      breaks_v_(patch_.basis_v.breakpoints()),
      lookup_(std::make_unique<Lookup>()) {
  lookup_->serial = next_serial();
  if (!grid) {
    find_intervals();
  } else {
    grid_columns_ = static_cast<int>(grid->u.size()) - 1;
    first_row_ = grid->first_row;
    const auto intervals = [](const std::vector<double>& b, const BSplineBasis1D& basis) {
      std::vector<Interval> out;
      for (size_t k = 0; k + 1 < b.size(); ++k)
        out.push_back({basis.find_span(0.5 * (b[k] + b[k + 1])), 0, b[k], b[k + 1] - b[k]});
      return out;
    };
    intervals_u_ = intervals(grid->u, patch_.basis_u);
    intervals_v_ = intervals(grid->v, patch_.basis_v);
  }
  check_intervals();
}

// Each distinct (from, to) of the cells, per direction, once (cells of one row share their v
// interval, of one column their u interval).
void PatchGeometryMap::find_intervals() {
  struct Key {
    double a, b;
    bool operator==(const Key& o) const { return a == o.a && b == o.b; }
  };
  struct Hash {
    // The bits mixed (splitmix64's finalizer), both zeros alike as == has them: std::hash of a
    // double runs a byte hash, 1% of an adaptive THB loop.
    static uint64_t mix(double x) {
      uint64_t z = x == 0 ? 0 : std::bit_cast<uint64_t>(x);
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
      return z ^ (z >> 31);
    }
    size_t operator()(const Key& k) const { return mix(k.a) * 31 + mix(k.b); }
  };
  std::unordered_map<Key, int, Hash> seen_u, seen_v;
  const int n = mesh_.num_cells();
  cell_u_.resize(n);
  cell_v_.resize(n);
  const auto index = [](std::unordered_map<Key, int, Hash>& seen, std::vector<Interval>& out,
                        const BSplineBasis1D& basis, double a, double b) {
    const auto [it, fresh] = seen.try_emplace(Key{a, b}, static_cast<int>(out.size()));
    if (fresh) out.push_back({basis.find_span(0.5 * (a + b)), 0, a, b - a});
    return it->second;
  };
  for (int c = 0; c < n; ++c) {
    const BezierCell& cell = mesh_.cell(c);
    cell_u_[c] = index(seen_u, intervals_u_, patch_.basis_u, cell.u0, cell.u1);
    cell_v_[c] = index(seen_v, intervals_v_, patch_.basis_v, cell.v0, cell.v1);
  }
}

// A cell across a knot of the patch would be mapped by the wrong polynomial on one side of it.
// Also numbers each interval's span among the patch's elements (for its Bezier form).
void PatchGeometryMap::check_intervals() {
  const auto check = [&](std::vector<Interval>& intervals, const BSplineBasis1D& basis, bool along_u) {
    const std::vector<double> b = basis.breakpoints();
    const std::vector<int> spans = basis.element_spans();
    const double eps = 1e-12 * (b.back() - b.front());
    for (size_t k = 0; k < intervals.size(); ++k) {
      Interval& e = intervals[k];
      const auto it = std::upper_bound(b.begin(), b.end(), e.from + eps);
      if (it != b.end() && *it < e.from + e.length - eps) {
        std::ostringstream s;
        if (grid_columns_ == 0) {
          const std::vector<int>& of = along_u ? cell_u_ : cell_v_;
          const int cell = static_cast<int>(std::find(of.begin(), of.end(), static_cast<int>(k)) - of.begin());
          const BezierCell& c = mesh_.cell(cell);
          s << "cell " << cell << " ([" << c.u0 << ", " << c.u1 << "] x [" << c.v0 << ", " << c.v1 << "])";
        } else {
          s << "the elements with " << (along_u ? "u" : "v") << " in [" << e.from << ", " << e.from + e.length << "]";
        }
        s << " straddle" << (grid_columns_ == 0 ? "s" : "") << " the geometry's knot " << (along_u ? "u = " : "v = ")
          << *it
          << ": the map is a different polynomial on each side, so every cell must lie inside one knot span "
             "(put a knot there)";
        throw GeometryError(s.str());
      }
      e.element = static_cast<int>(std::lower_bound(spans.begin(), spans.end(), e.span) - spans.begin());
    }
  };
  check(intervals_u_, patch_.basis_u, true);
  check(intervals_v_, patch_.basis_v, false);
}

std::pair<int, int> PatchGeometryMap::intervals_of(int cell) const {
  if (grid_columns_ > 0) return {cell % grid_columns_, first_row_ + cell / grid_columns_};
  return {cell_u_[cell], cell_v_[cell]};
}

namespace {

// The patch's B-splines alive on `span` (and their derivatives in the interval's reference
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

const PatchGeometryMap::RuleTables& PatchGeometryMap::tables(bool along_u, int n) const {
  struct Last {
    unsigned long serial = 0;
    int n = -1;
    const RuleTables* tables = nullptr;
  };
  thread_local Last last[2];
  Last& mine = last[along_u ? 0 : 1];
  if (mine.serial == lookup_->serial && mine.n == n) return *mine.tables;
  std::scoped_lock lock(lookup_->mutex);
  auto& slot = lookup_->tables[{along_u, n}];
  if (!slot) {
    slot = std::make_unique<RuleTables>();
    const QuadratureRule1D rule = gauss_legendre(n);
    for (const Interval& e : along_u ? intervals_u_ : intervals_v_) {
      slot->value.emplace_back();
      slot->derivative.emplace_back();
      patch_table(along_u ? patch_.basis_u : patch_.basis_v, e.span, e.from, e.length, rule, slot->value.back(),
                  slot->derivative.back());
    }
  }
  mine = {lookup_->serial, n, slot.get()};
  return *slot;
}

void PatchGeometryMap::evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const {
  const auto [iu, iv] = intervals_of(cell);
  interval_at_rule(iu, iv, nu, nv, out);
}

void PatchGeometryMap::evaluate_element_at_rule(int eu, int ev, int nu, int nv, GeometryAtPoints& out) const {
  if (grid_columns_ == 0) throw std::logic_error("evaluate_element_at_rule: not a grid map");
  interval_at_rule(eu, ev, nu, nv, out);
}

void PatchGeometryMap::interval_at_rule(int iu, int iv, int nu, int nv, GeometryAtPoints& out) const {
  // h(u_i, v_j) = sum_ab Nu_a(u_i) Nv_b(v_j) P_ab over the patch's own (pu+1)(pv+1) control
  // points, summed one direction at a time: the cost follows the geometry's degree, not the
  // space's (a bilinear square costs the same at p = 2 and p = 10).
  const int gu = patch_.basis_u.degree(), gv = patch_.basis_v.degree(), n_u = patch_.basis_u.num_functions();
  const int su = intervals_u_[iu].span - gu, sv = intervals_v_[iv].span - gv;
  const RuleTables& table_u = tables(true, nu);
  const RuleTables& table_v = tables(false, nv);
  const Eigen::MatrixXd &Nu = table_u.value[iu], &Nuu = table_u.derivative[iu];
  const Eigen::MatrixXd &Nv = table_v.value[iv], &Nvv = table_v.derivative[iv];
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
      for (int au = 0; au <= gu; ++au) P(av, au) = net_((su + au) + n_u * (sv + av), k);
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

// The patch on the cell as a rational Bezier patch: its B-splines on the span, in Bernstein
// form (Bezier extraction), restricted to the cell's interval (subdivision), raised to the
// cell's degree where that is higher (so the cell's geometry and its functions share a degree).
BezierGeometryCell PatchGeometryMap::bezier_cell(int cell) const {
  const auto [iu, iv] = intervals_of(cell);
  const BezierCell& c = mesh_.cell(cell);
  const auto restricted = [](const std::vector<Eigen::MatrixXd>& extraction, const std::vector<double>& b, int p,
                             const Interval& e, int degree) {
    const double a = b[e.element], len = b[e.element + 1] - a;
    // Rows: the span's p+1 B-splines; columns: Bernstein polynomials on the interval.
    Eigen::MatrixXd m =
        extraction[e.element] * subdivision_matrix(p, (e.from - a) / len, (e.from + e.length - a) / len).transpose();
    if (degree > p) m = m * degree_elevation_matrix(p, degree - p).transpose();
    return m;
  };
  const int du = std::max(c.degree_u, patch_.basis_u.degree()), dv = std::max(c.degree_v, patch_.basis_v.degree());
  const Eigen::MatrixXd Bu = restricted(extraction_u_, breaks_u_, patch_.basis_u.degree(), intervals_u_[iu], du);
  const Eigen::MatrixXd Bv = restricted(extraction_v_, breaks_v_, patch_.basis_v.degree(), intervals_v_[iv], dv);
  const int gu = patch_.basis_u.degree(), gv = patch_.basis_v.degree(), n_u = patch_.basis_u.num_functions();
  const int su = intervals_u_[iu].span - gu, sv = intervals_v_[iv].span - gv;
  BezierGeometryCell g;
  g.degree_u = du;
  g.degree_v = dv;
  Eigen::MatrixX3d h((du + 1) * (dv + 1), 3);
  Eigen::MatrixXd P(gu + 1, gv + 1);
  for (int k = 0; k < 3; ++k) {
    for (int b = 0; b <= gv; ++b)
      for (int a = 0; a <= gu; ++a) P(a, b) = net_((su + a) + n_u * (sv + b), k);
    const Eigen::MatrixXd H = Bu.transpose() * P * Bv;  // (du+1) x (dv+1): Bernstein a + (du+1) b
    h.col(k) = H.reshaped();
  }
  g.weights = h.col(2);
  g.points = h.leftCols<2>().array().colwise() / h.col(2).array();
  return g;
}

namespace {
// B-spline values and derivatives at the distinct parameters of one call: quadrature rules are
// tensor products, so a cell's points repeat a few u and v values (the estimator evaluates
// the map at every point of every cell and side: per point, it was 25% slower).
class DerivativeCache {
 public:
  DerivativeCache(const BSplineBasis1D& basis, int span, int order)
      : basis_(basis), span_(span), order_(order), size_((order + 1) * (basis.degree() + 1)) {
    params_.reserve(8);
    values_.reserve(8 * size_);
  }
  const double* at(double t) {
    for (size_t k = 0; k < params_.size(); ++k)
      if (params_[k] == t) return values_.data() + k * size_;
    params_.push_back(t);
    values_.resize(params_.size() * size_);
    basis_.evaluate_derivatives(span_, t, order_, values_.data() + (params_.size() - 1) * size_);
    return values_.data() + (params_.size() - 1) * size_;
  }

 private:
  const BSplineBasis1D& basis_;
  int span_, order_;
  size_t size_;
  std::vector<double> params_, values_;
};
}  // namespace

void PatchGeometryMap::evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                GeometryAtPoints& out) const {
  const BezierCell& c = mesh_.cell(cell);
  const int p = patch_.basis_u.degree(), q = patch_.basis_v.degree(), nu = patch_.basis_u.num_functions();
  // Span from the cell's middle, so a point on a cell edge uses the cell's own polynomial.
  const int su = patch_.basis_u.find_span(0.5 * (c.u0 + c.u1)), sv = patch_.basis_v.find_span(0.5 * (c.v0 + c.v1));
  DerivativeCache cu(patch_.basis_u, su, 1), cv(patch_.basis_v, sv, 1);
  out.x.resize(u.size(), 2);
  out.jacobian.resize(u.size(), 4);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const double* du = cu.at(c.u0 + u[k] * (c.u1 - c.u0));
    const double* dv = cv.at(c.v0 + v[k] * (c.v1 - c.v0));
    // The homogeneous point (w x, w y, w) and its derivatives in the cell's reference u and v,
    // dehomogenized point by point: no arrays per call.
    double h[3] = {0, 0, 0}, hu[3] = {0, 0, 0}, hv[3] = {0, 0, 0};
    for (int b = 0; b <= q; ++b)
      for (int a = 0; a <= p; ++a) {
        const int i = (su - p + a) + nu * (sv - q + b);
        const double w = patch_.weights[i];
        const double P[3] = {w * patch_.control_points(i, 0), w * patch_.control_points(i, 1), w};
        const double n = du[a] * dv[b], n_u = du[p + 1 + a] * dv[b], n_v = du[a] * dv[q + 1 + b];
        for (int d = 0; d < 3; ++d) {
          h[d] += n * P[d];
          hu[d] += n_u * P[d] * (c.u1 - c.u0);
          hv[d] += n_v * P[d] * (c.v1 - c.v0);
        }
      }
    dehomogenize_point(h, hu, hv, out, k);
  }
}

bool PatchGeometryMap::second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                          Eigen::MatrixXd& out) const {
  const BezierCell& c = mesh_.cell(cell);
  const int p = patch_.basis_u.degree(), q = patch_.basis_v.degree(), nu = patch_.basis_u.num_functions();
  const double su_len = c.u1 - c.u0, sv_len = c.v1 - c.v0;
  const int su = patch_.basis_u.find_span(0.5 * (c.u0 + c.u1)), sv = patch_.basis_v.find_span(0.5 * (c.v0 + c.v1));
  DerivativeCache cu(patch_.basis_u, su, 2), cv(patch_.basis_v, sv, 2);
  out.resize(u.size(), 6);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const double* du = cu.at(c.u0 + u[k] * su_len);
    const double* dv = cv.at(c.v0 + v[k] * sv_len);
    // Homogeneous map H = (w x, w y, w) and its derivatives in the cell's reference coordinates.
    Eigen::RowVector3d H = Eigen::RowVector3d::Zero(), Hu = H, Hv = H, Huu = H, Huv = H, Hvv = H;
    for (int b = 0; b <= q; ++b)
      for (int a = 0; a <= p; ++a) {
        const int i = (su - p + a) + nu * (sv - q + b);
        const double w = patch_.weights[i];
        const Eigen::RowVector3d P(w * patch_.control_points(i, 0), w * patch_.control_points(i, 1), w);
        const double n0 = du[a], n1 = du[p + 1 + a] * su_len, n2 = du[2 * (p + 1) + a] * su_len * su_len;
        const double m0 = dv[b], m1 = dv[q + 1 + b] * sv_len, m2 = dv[2 * (q + 1) + b] * sv_len * sv_len;
        H += n0 * m0 * P;
        Hu += n1 * m0 * P;
        Hv += n0 * m1 * P;
        Huu += n2 * m0 * P;
        Huv += n1 * m1 * P;
        Hvv += n0 * m2 * P;
      }
    // Quotient rule for g = h / w, one coordinate at a time.
    const double w = H[2];
    for (int d = 0; d < 2; ++d) {
      const double g = H[d] / w;
      const double gu = (Hu[d] - g * Hu[2]) / w, gv = (Hv[d] - g * Hv[2]) / w;
      out(k, 3 * d + 0) = (Huu[d] - 2 * gu * Hu[2] - g * Huu[2]) / w;
      out(k, 3 * d + 1) = (Huv[d] - gu * Hv[2] - gv * Hu[2] - g * Huv[2]) / w;
      out(k, 3 * d + 2) = (Hvv[d] - 2 * gv * Hv[2] - g * Hvv[2]) / w;
    }
  }
  return true;
}

}  // namespace knotwork
