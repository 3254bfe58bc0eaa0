#include "solver/tensor_operator.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "basis/core/input_error.hpp"
#include "quadrature/gauss_legendre.hpp"
#include "solver/assemble_poisson.hpp"

namespace knotwork {

namespace {

constexpr int kMaxPoints = 20;  // Gauss points per element and direction
constexpr int kMaxP = TensorPoissonOperator::kMaxDegree + 1;

// A field sum_ab c(a, b) B_a(u) B_b(v) and its two parameter derivatives at the element's
// points (i + n_i j), one direction at a time. Tables are point-major: table[i * P + a].
struct Field {
  double value[kMaxPoints * kMaxPoints], du[kMaxPoints * kMaxPoints], dv[kMaxPoints * kMaxPoints];
};

// N > 0: every size is N (the usual p + 1 functions and points in both directions), known to
// the compiler, which then unrolls and vectorizes the contractions (4-5x faster at p = 2).
template <int N, int Q = N>
void evaluate_field(const double* c, int pu, int pv, int qu, int qv, const double* bu, const double* du,
                    const double* bv, const double* dv, Field& f) {
  if constexpr (N > 0) pu = pv = N;
  if constexpr (Q > 0) qu = qv = Q;
  double t[kMaxP][kMaxPoints], tu[kMaxP][kMaxPoints];
  for (int b = 0; b < pv; ++b)
    for (int i = 0; i < qu; ++i) {
      double s = 0, su = 0;
      for (int a = 0; a < pu; ++a) s += bu[i * pu + a] * c[a + pu * b], su += du[i * pu + a] * c[a + pu * b];
      t[b][i] = s, tu[b][i] = su;
    }
  for (int j = 0; j < qv; ++j)
    for (int i = 0; i < qu; ++i) {
      double s = 0, su = 0, sv = 0;
      for (int b = 0; b < pv; ++b) {
        s += bv[j * pv + b] * t[b][i];
        su += bv[j * pv + b] * tu[b][i];
        sv += dv[j * pv + b] * t[b][i];
      }
      f.value[i + qu * j] = s, f.du[i + qu * j] = su, f.dv[i + qu * j] = sv;
    }
}

// Threads over bands of element rows, in two phases (even bands, then odd ones): bands of at
// least reach + 1 rows, so that two bands of a phase share no function row and their elements
// add into y without a race. Fixed bands: the sums do not depend on timing.
template <class Row>
void over_row_bands(int rows, int reach, Row row) {
  const int threads = omp_get_max_threads();
  int bands = std::min(2 * threads, rows / (reach + 1));
  if (bands < 2) {
    for (int r = 0; r < rows; ++r) row(r);
    return;
  }
  for (int phase = 0; phase < 2; ++phase) {
#pragma omp parallel for schedule(static, 1)
    for (int k = phase; k < bands; k += 2) {
      const int begin = static_cast<int>(long(rows) * k / bands), end = static_cast<int>(long(rows) * (k + 1) / bands);
      for (int r = begin; r < end; ++r) row(r);
    }
  }
}

bool all_equal(Eigen::Ref<const Eigen::VectorXd> w) {
  return (w.array() - w[0]).abs().maxCoeff() <= 64 * std::numeric_limits<double>::epsilon() * std::abs(w[0]);
}

}  // namespace

TensorPoissonOperator::Direction TensorPoissonOperator::direction(const BSplineBasis1D& space,
                                                                  const BSplineBasis1D& geometry, int points) {
  if (space.degree() > kMaxDegree || geometry.degree() > kMaxDegree)
    throw std::invalid_argument("TensorPoissonOperator: degree above " + std::to_string(kMaxDegree));
  if (space.breakpoints() != geometry.breakpoints())
    throw std::invalid_argument("TensorPoissonOperator: the geometry's elements are not the space's");
  Direction d;
  d.degree = space.degree();
  d.geometry_degree = geometry.degree();
  d.points = points > 0 ? points : space.degree() + 1;
  if (d.points > kMaxPoints)
    throw std::invalid_argument("TensorPoissonOperator: more than " + std::to_string(kMaxPoints) + " points per element");
  const std::vector<int> spans = space.element_spans(), geometry_spans = geometry.element_spans();
  const std::vector<double> breaks = space.breakpoints();
  d.elements = static_cast<int>(spans.size());
  const QuadratureRule1D rule = gauss_legendre(d.points);
  const int p = d.degree, g = d.geometry_degree, q = d.points;
  d.value.resize(size_t(d.elements) * q * (p + 1));
  d.derivative.resize(d.value.size());
  d.geometry_value.resize(size_t(d.elements) * q * (g + 1));
  d.geometry_derivative.resize(d.geometry_value.size());
  d.weight.resize(size_t(d.elements) * q);
  std::vector<double> s(2 * (p + 1)), t(2 * (g + 1));
  for (int e = 0; e < d.elements; ++e) {
    d.first.push_back(spans[e] - p);
    d.geometry_first.push_back(geometry_spans[e] - g);
    const double from = breaks[e], length = breaks[e + 1] - breaks[e];
    for (int i = 0; i < q; ++i) {
      const double x = from + rule.nodes[i] * length;
      space.evaluate_derivatives(spans[e], x, 1, s.data());
      geometry.evaluate_derivatives(geometry_spans[e], x, 1, t.data());
      for (int a = 0; a <= p; ++a) {
        d.value[(size_t(e) * q + i) * (p + 1) + a] = s[a];
        d.derivative[(size_t(e) * q + i) * (p + 1) + a] = s[p + 1 + a];
      }
      for (int a = 0; a <= g; ++a) {
        d.geometry_value[(size_t(e) * q + i) * (g + 1) + a] = t[a];
        d.geometry_derivative[(size_t(e) * q + i) * (g + 1) + a] = t[g + 1 + a];
      }
      d.weight[size_t(e) * q + i] = rule.weights[i] * length;
    }
  }
  const int P = p + 1;
  d.stiffness.assign(size_t(d.elements) * P * P, 0.0);
  d.mass.assign(d.stiffness.size(), 0.0);
  d.mixed.assign(d.stiffness.size(), 0.0);
  for (int e = 0; e < d.elements; ++e)
    for (int i = 0; i < q; ++i) {
      const double w = d.weight[size_t(e) * q + i], *B = &d.value[(size_t(e) * q + i) * P], *D = &d.derivative[(size_t(e) * q + i) * P];
      for (int a = 0; a < P; ++a)
        for (int c = 0; c < P; ++c) {
          d.stiffness[(size_t(e) * P + a) * P + c] += w * D[a] * D[c];
          d.mass[(size_t(e) * P + a) * P + c] += w * B[a] * B[c];
          d.mixed[(size_t(e) * P + a) * P + c] += w * D[a] * B[c];
        }
    }
  return d;
}

TensorPoissonOperator::TensorPoissonOperator(const TensorPatch& patch, double stiffness, double reaction, int points_u,
                                             int points_v)
    : space_u_(*patch.space_u),
      space_v_(*patch.space_v),
      geometry_u_(*patch.geometry_u),
      geometry_v_(*patch.geometry_v),
      stiffness_(stiffness),
      reaction_(reaction) {
  u_ = direction(*patch.space_u, *patch.geometry_u, points_u);
  v_ = direction(*patch.space_v, *patch.geometry_v, points_v);
  n_u_ = patch.space_u->num_functions();
  n_v_ = patch.space_v->num_functions();
  net_u_ = patch.geometry_u->num_functions();
  const Eigen::MatrixX3d& given = *patch.geometry;
  if (given.rows() != long(net_u_) * patch.geometry_v->num_functions())
    throw std::invalid_argument("TensorPoissonOperator: the geometry net does not match its bases");
  if (patch.weights && patch.weights->size() > 0) {
    if (patch.weights->size() != num_functions())
      throw std::invalid_argument("TensorPoissonOperator: one weight per function expected");
    // Equal weights w: R_a = w N_a / (w sum N) = N_a, the B-splines themselves. (Equal to 64
    // eps: refining a net of weights 1 can leave 1 +- 1 ulp, and the functions differ from the
    // B-splines by as much.)
    if (!all_equal(*patch.weights)) weights_ = *patch.weights;
  }
  // A net of equal weights w0 is a polynomial map: scaled to w = 1, its W needs no evaluating
  // and its third column is not read. (A refined net of weights 1 keeps 1 +- 1 ulp there: the
  // first weight 1 means x = X / 1 = X, read in place.)
  polynomial_map_ = given.rows() > 0 && all_equal(given.col(2));
  if (patch.geometry_outlives_operator && (!polynomial_map_ || given(0, 2) == 1.0)) {
    net_ = &given;  // nothing to scale
  } else {
    own_net_ = given;
    if (polynomial_map_) {
      own_net_ /= given(0, 2);
      own_net_.col(2).setOnes();
    }
  }
  reach_u_ = reach(u_, n_u_);
  reach_v_ = reach(v_, n_v_);
  if (weights_.size() == 0) find_affine_elements();
}

namespace {

// What the points of one element need, whatever is applied: the rule's weights, the geometry
// factor D = w |det J| J^-1 J^-T (three entries), the measure w |det J|, and the rational
// denominator W with its derivatives (W = 1 for B-splines).
struct Points {
  double d11[kMaxPoints * kMaxPoints], d12[kMaxPoints * kMaxPoints], d22[kMaxPoints * kMaxPoints];
  double measure[kMaxPoints * kMaxPoints], min_det = 0;
  double x[kMaxPoints * kMaxPoints], y[kMaxPoints * kMaxPoints];  // the points themselves
  // The Jacobian (x_u, x_v, y_u, y_v), for physical gradients (the error norms).
  double xu[kMaxPoints * kMaxPoints], xv[kMaxPoints * kMaxPoints], yu[kMaxPoints * kMaxPoints], yv[kMaxPoints * kMaxPoints];
  Field w;
};

}  // namespace

template <int N, int Q, class Kernel, class Affine>
void TensorPoissonOperator::for_each_element(Kernel kernel, Affine affine, const std::atomic<bool>* stop,
                                             const std::array<int, 4>* elements, const Direction* rule_u,
                                             const Direction* rule_v) const {
  const Direction &U = rule_u ? *rule_u : u_, &V = rule_v ? *rule_v : v_;
  const int pu = N ? N : U.degree + 1, pv = N ? N : V.degree + 1, gu = N ? N : U.geometry_degree + 1,
            gv = N ? N : V.geometry_degree + 1;
  const int qu = Q ? Q : U.points, qv = Q ? Q : V.points;
  const bool rational = weights_.size() > 0;
  const Eigen::MatrixX3d& net = *net_;
  const int eu_first = elements ? (*elements)[0] : 0, eu_last = elements ? (*elements)[1] : U.elements - 1;
  const auto row = [&](int ev) {
    Points pts;
    Field h[3];
    double c[kMaxP * kMaxP];
    for (int eu = eu_first; eu <= eu_last; ++eu) {
      if (stop && stop->load(std::memory_order_relaxed)) return;
      if constexpr (!std::is_same_v<Affine, std::nullptr_t>) {
        const std::array<double, 4>* f = affine_factors(eu, ev);
        if (f) {
          affine(eu, ev, U.first[eu], V.first[ev], *f);
          continue;
        }
      }
      const double *bu = &U.value[size_t(eu) * qu * pu], *du = &U.derivative[size_t(eu) * qu * pu];
      const double *bv = &V.value[size_t(ev) * qv * pv], *dv = &V.derivative[size_t(ev) * qv * pv];
      const double *gbu = &U.geometry_value[size_t(eu) * qu * gu], *gdu = &U.geometry_derivative[size_t(eu) * qu * gu];
      const double *gbv = &V.geometry_value[size_t(ev) * qv * gv], *gdv = &V.geometry_derivative[size_t(ev) * qv * gv];
      // A polynomial map relative to the element's first control point (the functions sum to 1
      // and their derivatives to 0): the Jacobian then sums terms of the element's size, not of
      // the domain's, and rounds to a few eps of itself whatever the mesh size.
      const long first = U.geometry_first[eu] + long(net_u_) * V.geometry_first[ev];
      for (int k = 0; k < (polynomial_map_ ? 2 : 3); ++k) {
        const double origin = polynomial_map_ ? net(first, k) : 0.0;
        for (int b = 0; b < gv; ++b)
          for (int a = 0; a < gu; ++a) c[a + gu * b] = net(first + a + long(net_u_) * b, k) - origin;
        evaluate_field<N, Q>(c, gu, gv, qu, qv, gbu, gdu, gbv, gdv, h[k]);
        if (origin != 0)
          for (int q = 0; q < qu * qv; ++q) h[k].value[q] += origin;
      }
      const int fu = U.first[eu], fv = V.first[ev];
      if (rational) {
        for (int b = 0; b < pv; ++b)
          for (int a = 0; a < pu; ++a) c[a + pu * b] = weights_[(fu + a) + n_u_ * (fv + b)];
        evaluate_field<N, Q>(c, pu, pv, qu, qv, bu, du, bv, dv, pts.w);
      }
      double min_det = std::numeric_limits<double>::infinity();
      for (int j = 0; j < qv; ++j)
        for (int i = 0; i < qu; ++i) {
          const int k = i + qu * j;
          double xu = h[0].du[k], xv = h[0].dv[k], yu = h[1].du[k], yv = h[1].dv[k];
          pts.x[k] = h[0].value[k], pts.y[k] = h[1].value[k];
          if (!polynomial_map_) {  // x = X / W: x_u = (X_u - x W_u) / W
            const double w = h[2].value[k], x = h[0].value[k] / w, y = h[1].value[k] / w;
            pts.x[k] = x, pts.y[k] = y;
            xu = (xu - x * h[2].du[k]) / w, xv = (xv - x * h[2].dv[k]) / w;
            yu = (yu - y * h[2].du[k]) / w, yv = (yv - y * h[2].dv[k]) / w;
          }
          const double det = xu * yv - xv * yu, weight = U.weight[size_t(eu) * qu + i] * V.weight[size_t(ev) * qv + j];
          min_det = std::min(min_det, det);
          const double scale = weight / std::abs(det);
          pts.d11[k] = scale * (xv * xv + yv * yv);
          pts.d12[k] = -scale * (xu * xv + yu * yv);
          pts.d22[k] = scale * (xu * xu + yu * yu);
          pts.measure[k] = weight * std::abs(det);
          pts.xu[k] = xu, pts.xv[k] = xv, pts.yu[k] = yu, pts.yv[k] = yv;
        }
      pts.min_det = min_det;
      kernel(eu, ev, fu, fv, bu, du, bv, dv, pts);
    }
  };
  if (elements) {
    for (int ev = (*elements)[2]; ev <= (*elements)[3]; ++ev) row(ev);
  } else {
    over_row_bands(V.elements, V.degree, row);
  }
}

// Affine elements: the same factors at every point (to 64 eps of the largest). A first pass
// stores nothing (32 bytes per element, 537 MB at 4096^2): it finds whether every element is
// affine and whether all share the first element's factors; only affine elements whose
// factors differ need a second pass that keeps them.
void TensorPoissonOperator::find_affine_elements() {
  std::atomic<bool> curved{false};  // then the search stops: a curved mesh costs a few elements
  std::atomic<double> known{0.0};   // the largest rounding tolerance of an element's factors
  // The largest distance of any element's factors from the first element's (D, then |det J|).
  std::atomic<double> apart_d{0.0}, apart_det{0.0};
  std::array<double, 4> first_factors{};
  const auto raise = [](std::atomic<double>& to, double value) {
    for (double seen = to.load(std::memory_order_relaxed); value > seen && !to.compare_exchange_weak(seen, value);) {
    }
  };
  const int qu = u_.points, qv = v_.points;
  const Eigen::MatrixX3d& net = *net_;
  // The element's factors and their tolerance; false when it is not affine.
  const auto element_factors = [&](int eu, int ev, const Points& pts, std::array<double, 4>& first, double& eps64) {
    double largest_d = 0, spread_d = 0, largest_det = 0, spread_det = 0;
    for (int j = 0; j < qv; ++j)
      for (int i = 0; i < qu; ++i) {
        const int k = i + qu * j;
        const double w = u_.weight[size_t(eu) * qu + i] * v_.weight[size_t(ev) * qv + j];
        const std::array<double, 4> f{pts.d11[k] / w, pts.d12[k] / w, pts.d22[k] / w, pts.measure[k] / w};
        if (k == 0) first = f;
        for (int m = 0; m < 3; ++m) {
          largest_d = std::max(largest_d, std::abs(f[m]));
          spread_d = std::max(spread_d, std::abs(f[m] - first[m]));
        }
        largest_det = std::max(largest_det, f[3]);
        spread_det = std::max(spread_det, std::abs(f[3] - first[3]));
      }
    // The net's points carry rounding of their own size, so the element's shape is known to
    // eps |P| / |P - P_0| relative along each direction (1 / h on a mesh of the unit square,
    // 1 / h_u for elements much shorter along u): variations below 64 times the larger are the
    // data's rounding, not its geometry.
    const long corner = u_.geometry_first[eu] + long(net_u_) * v_.geometry_first[ev];
    const auto point = [&](int a, int b, int k) {
      const long m = corner + a + long(net_u_) * b;
      return net(m, k) / net(m, 2);
    };
    double size = 0, extent_u = 0, extent_v = 0;
    for (int b = 0; b <= v_.geometry_degree; ++b)
      for (int a = 0; a <= u_.geometry_degree; ++a)
        for (int k = 0; k < 2; ++k) {
          size = std::max(size, std::abs(point(a, b, k)));
          extent_u = std::max(extent_u, std::abs(point(a, b, k) - point(0, b, k)));
          extent_v = std::max(extent_v, std::abs(point(a, b, k) - point(a, 0, k)));
        }
    const double extent = std::min(extent_u, extent_v);
    eps64 = 64 * std::numeric_limits<double>::epsilon() * (extent > 0 ? std::max(1.0, size / extent) : 1.0);
    return pts.min_det > 0 && spread_d <= eps64 * largest_d && spread_det <= eps64 * largest_det;
  };
  const std::array<int, 4> first_element{0, 0, 0, 0};
  for_each_element<0>([&](int eu, int ev, int, int, const double*, const double*, const double*, const double*,
                          const Points& pts) {
    double eps64;
    if (!element_factors(eu, ev, pts, first_factors, eps64)) curved = true;
  }, nullptr, nullptr, &first_element);
  if (curved) return;
  if (net_is_affine()) {  // then every element has the first one's factors: nothing to search
    set_uniform(first_factors);
    return;
  }
  dispatch([&](auto n) {
    for_each_element<decltype(n)::value>([&](int eu, int ev, int, int, const double*, const double*, const double*,
                                             const double*, const Points& pts) {
      std::array<double, 4> f{};
      double eps64;
      if (!element_factors(eu, ev, pts, f, eps64)) {
        curved.store(true, std::memory_order_relaxed);
        return;
      }
      raise(known, eps64);
      raise(apart_d, std::max({std::abs(f[0] - first_factors[0]), std::abs(f[1] - first_factors[1]),
                               std::abs(f[2] - first_factors[2])}));
      raise(apart_det, std::abs(f[3] - first_factors[3]));
    }, nullptr, &curved);
  });
  if (curved) return;
  // One set of factors for every element (a map affine on the whole patch, the unit square's):
  // equal to what the data's rounding can tell apart, as above.
  const std::array<double, 4>& f0 = first_factors;
  const double tolerance = known.load(), largest_d = std::max({std::abs(f0[0]), std::abs(f0[1]), std::abs(f0[2])});
  if (apart_d.load() <= tolerance * largest_d && apart_det.load() <= tolerance * f0[3]) {
    set_uniform(f0);
    return;
  }
  // Affine elements of several shapes (a kink in a piecewise-bilinear map): each keeps its own.
  affine_.assign(size_t(u_.elements) * v_.elements, {0, 0, 0, 0});
  for_each_element<0>([&](int eu, int ev, int, int, const double*, const double*, const double*, const double*,
                          const Points& pts) {
    std::array<double, 4> f{};
    double eps64;
    if (element_factors(eu, ev, pts, f, eps64)) affine_[size_t(eu) + size_t(u_.elements) * ev] = f;
  });
}

// A polynomial map is one affine map x = a + b u + c v on the whole patch exactly when its
// control points are that map at the Greville abscissae (linear precision, and the
// representation is unique): O(1) work per control point, not the geometry at every element's
// points. To the net's rounding, 64 eps of its largest coordinate, as the element test allows.
bool TensorPoissonOperator::net_is_affine() const {
  if (!polynomial_map_ || geometry_u_.degree() < 1 || geometry_v_.degree() < 1) return false;
  const std::vector<double> xi = greville_abscissae(geometry_u_), eta = greville_abscissae(geometry_v_);
  const long nu = long(xi.size()), nv = long(eta.size());
  const Eigen::MatrixX3d& net = *net_;
  if (nu < 2 || nv < 2 || net.rows() != nu * nv) return false;
  const double size = net.leftCols<2>().cwiseAbs().maxCoeff();
  const double tolerance = 64 * std::numeric_limits<double>::epsilon() * size;
  std::atomic<bool> affine{true};
  for (int k = 0; k < 2; ++k) {
    const auto at = [&](long i, long j) { return net(i + nu * j, k); };
    const double b = (at(nu - 1, 0) - at(0, 0)) / (xi[nu - 1] - xi[0]);
    const double c = (at(0, nv - 1) - at(0, 0)) / (eta[nv - 1] - eta[0]);
    const double a = at(0, 0) - b * xi[0] - c * eta[0];
#pragma omp parallel for schedule(static)
    for (long j = 0; j < nv; ++j) {
      if (!affine.load(std::memory_order_relaxed)) continue;
      for (long i = 0; i < nu; ++i)
        if (!(std::abs(at(i, j) - (a + b * xi[i] + c * eta[j])) <= tolerance)) {
          affine.store(false, std::memory_order_relaxed);
          break;
        }
    }
  }
  return affine;
}

std::unique_ptr<TensorPoissonOperator> TensorPoissonOperator::uniformly_affine(const BSplineBasis1D& space_u,
                                                                             const BSplineBasis1D& space_v,
                                                                             const std::array<double, 4>& factors,
                                                                             double stiffness, double reaction, int points_u,
                                                                             int points_v) {
  std::unique_ptr<TensorPoissonOperator> op(new TensorPoissonOperator());
  // (The space stands in for the geometry's basis: the tables need its elements only.)
  op->u_ = direction(space_u, space_u, points_u);
  op->v_ = direction(space_v, space_v, points_v);
  op->space_u_ = op->geometry_u_ = space_u;
  op->space_v_ = op->geometry_v_ = space_v;
  op->n_u_ = space_u.num_functions();
  op->n_v_ = space_v.num_functions();
  op->stiffness_ = stiffness;
  op->reaction_ = reaction;
  op->polynomial_map_ = true;
  op->reach_u_ = reach(op->u_, op->n_u_);
  op->reach_v_ = reach(op->v_, op->n_v_);
  op->set_uniform(factors);
  return op;
}

void TensorPoissonOperator::set_uniform(const std::array<double, 4>& factors) {
  uniform_ = true;
  uniform_factors_ = factors;
  band_u_ = band(u_);
  band_v_ = band(v_);
  const double d11 = stiffness_ * factors[0], d12 = stiffness_ * factors[1], d22 = stiffness_ * factors[2],
               r = reaction_ * factors[3];
  KroneckerForm& k = kronecker_;
  k.mixed = d12 != 0;
  const int pu = u_.degree, wu = 2 * pu + 1, nu = band_u_.n;
  k.a1.assign(size_t(wu) * nu, 0.0), k.a2 = k.a1, k.a3 = k.a1, k.a4 = k.a1;
  for (int i = 0; i < nu; ++i)
    for (int t = 0; t < wu; ++t) {
      const size_t from = size_t(i) * wu + t, to = size_t(t) * nu + i;
      k.a1[to] = d11 * band_u_.K[from] + r * band_u_.M[from];
      k.a2[to] = d22 * band_u_.M[from];
      k.a3[to] = d12 * band_u_.C[from];
      const int c = i + t - pu;  // C_u^T(i, c) = C_u(c, i), entry wu - 1 - t of row c
      k.a4[to] = c >= 0 && c < nu ? d12 * band_u_.C[size_t(c) * wu + (wu - 1 - t)] : 0.0;
    }
  const int pv = v_.degree, wv = 2 * pv + 1, nv = band_v_.n;
  k.cvt.assign(size_t(wv) * nv, 0.0);
  for (int j = 0; j < nv; ++j)
    for (int t = 0; t < wv; ++t) {
      const int c = j + t - pv;
      if (c >= 0 && c < nv) k.cvt[size_t(j) * wv + t] = band_v_.C[size_t(c) * wv + (wv - 1 - t)];
    }
}

TensorPoissonOperator::Band TensorPoissonOperator::band(const Direction& d) {
  Band b;
  const int p = d.degree, P = p + 1, width = 2 * p + 1;
  b.n = d.first.empty() ? 0 : d.first.back() + P;
  b.K.assign(size_t(b.n) * width, 0.0);
  b.M.assign(b.K.size(), 0.0);
  b.C.assign(b.K.size(), 0.0);
  for (int e = 0; e < d.elements; ++e)
    for (int a = 0; a < P; ++a)
      for (int c = 0; c < P; ++c) {
        const size_t to = size_t(d.first[e] + a) * width + (c - a + p), from = (size_t(e) * P + a) * P + c;
        b.K[to] += d.stiffness[from];
        b.M[to] += d.mass[from];
        b.C[to] += d.mixed[from];
      }
  return b;
}

int TensorPoissonOperator::uniform_size() const {
  const int n = u_.degree + 1;
  for (int k : {v_.degree + 1, u_.geometry_degree + 1, v_.geometry_degree + 1, u_.points, v_.points})
    if (k != n) return 0;
  return n;
}

template <class Sized>
void TensorPoissonOperator::dispatch(Sized sized) const {
  switch (uniform_size()) {
    case 2: return sized(std::integral_constant<int, 2>{});
    case 3: return sized(std::integral_constant<int, 3>{});
    case 4: return sized(std::integral_constant<int, 4>{});
    case 5: return sized(std::integral_constant<int, 5>{});
    case 6: return sized(std::integral_constant<int, 6>{});
    case 7: return sized(std::integral_constant<int, 7>{});
    default: return sized(std::integral_constant<int, 0>{});
  }
}

template <class Sized>
void TensorPoissonOperator::dispatch(const Direction& U, const Direction& V, Sized sized) const {
  int n = U.degree + 1, q = U.points;
  for (int k : {V.degree + 1, U.geometry_degree + 1, V.geometry_degree + 1})
    if (k != n) n = 0;
  if (V.points != q) q = 0;
  const auto with_points = [&](auto size) {
    switch (q) {
      case 3: return sized(size, std::integral_constant<int, 3>{});
      case 4: return sized(size, std::integral_constant<int, 4>{});
      case 5: return sized(size, std::integral_constant<int, 5>{});
      case 6: return sized(size, std::integral_constant<int, 6>{});
      default: return sized(size, std::integral_constant<int, 0>{});
    }
  };
  switch (n) {  // (the usual pairs: p + 1 functions with p + 1 or p + 2 points, p = 2..4)
    case 3: return with_points(std::integral_constant<int, 3>{});
    case 4: return with_points(std::integral_constant<int, 4>{});
    case 5: return with_points(std::integral_constant<int, 5>{});
    default: return with_points(std::integral_constant<int, 0>{});
  }
}

void TensorPoissonOperator::apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  if (x.size() != num_functions()) throw std::invalid_argument("TensorPoissonOperator::apply: wrong vector size");
  if (uniform_) {
    y.resize(num_functions());
    apply_within(x.data(), FunctionBox{0, n_u_, 0, n_v_}, y.data());
    return;
  }
  const bool rational = weights_.size() > 0;
  const Eigen::VectorXd scaled = rational ? Eigen::VectorXd(x.cwiseProduct(weights_)) : Eigen::VectorXd();
  const double* xw = rational ? scaled.data() : x.data();
  const double* w = rational ? weights_.data() : nullptr;
  y.setZero(num_functions());
  double* out = y.data();
  const long n = n_u_;
  dispatch([&](auto size) {
    product<decltype(size)::value>([xw, n](int i, int j) { return xw[i + n * j]; },
                                   [out, w, n](int i, int j, double v) { out[i + n * j] += w ? w[i + n * j] * v : v; },
                                   nullptr);
  });
}

bool TensorPoissonOperator::elements_touching(const FunctionBox& rows, std::array<int, 4>& elements) const {
  // An element's functions are first .. first + degree, and `first` does not decrease.
  auto range = [](const Direction& d, int from, int count, int& e0, int& e1) {
    e0 = static_cast<int>(std::lower_bound(d.first.begin(), d.first.end(), from - d.degree) - d.first.begin());
    e1 = static_cast<int>(std::upper_bound(d.first.begin(), d.first.end(), from + count - 1) - d.first.begin()) - 1;
    return count > 0 && e0 <= e1;
  };
  return range(u_, rows.first_u, rows.count_u, elements[0], elements[1]) &&
         range(v_, rows.first_v, rows.count_v, elements[2], elements[3]);
}

void TensorPoissonOperator::apply_rows(const double* x, const FunctionBox& given, const FunctionBox& rows, double* y) const {
  std::array<int, 4> elements;
  if (!elements_touching(rows, elements)) {
    std::fill(y, y + long(rows.count_u) * rows.count_v, 0.0);
    return;
  }
  // The touched elements' functions lie within a degree of the rows: x on that padded box
  // (zero outside `given`, times the weights when rational) and the products into another, so
  // that the kernels index without bounds checks.
  const int pu = u_.degree, pv = v_.degree, u0 = rows.first_u - pu, v0 = rows.first_v - pv;
  const long mu = rows.count_u + 2 * pu, mv = rows.count_v + 2 * pv;
  thread_local std::vector<double> in, out;
  in.assign(size_t(mu * mv), 0.0);
  const double* w = weights_.size() > 0 ? weights_.data() : nullptr;
  const long n = n_u_;
  // The box's columns a_from .. a_to - 1 lie in `given`.
  const int a_from = std::max(0, given.first_u - u0), a_to = int(std::min<long>(mu, given.first_u + given.count_u - u0));
  for (int b = 0; b < mv; ++b) {
    const int j = v0 + b, gj = j - given.first_v;
    if (gj < 0 || gj >= given.count_v || a_from >= a_to) continue;
    const long at = long(given.count_u) * gj - given.first_u + u0;  // x's index of the box's column 0
    double* to = in.data() + mu * b;
    if (w)
      for (int a = a_from; a < a_to; ++a) to[a] = x[at + a] * w[u0 + a + n * j];
    else
      std::copy(x + (at + a_from), x + (at + a_to), to + a_from);
  }
  if (uniform_) {  // (affine elements only: no weights; y is overwritten)
    kronecker_rows(in.data(), mu, rows, y);
    return;
  }
  out.assign(size_t(mu * mv), 0.0);
  // Function (i, j) at (i + mu j) - origin (an index: a pointer before the array's start
  // would be undefined behaviour).
  const long origin = u0 + mu * v0;
  const double* in_at = in.data();
  double* out_at = out.data();
  dispatch([&](auto size) {
    product<decltype(size)::value>([in_at, mu, origin](int i, int j) { return in_at[i + mu * j - origin]; },
                                   [out_at, mu, origin](int i, int j, double v) { out_at[i + mu * j - origin] += v; },
                                   &elements);
  });
  for (int b = 0; b < rows.count_v; ++b)
    for (int a = 0; a < rows.count_u; ++a) {
      const int i = rows.first_u + a, j = rows.first_v + b;
      const double v = out[(a + pu) + mu * (b + pv)];
      y[a + long(rows.count_u) * b] = w ? v * w[i + n * j] : v;
    }
}

void TensorPoissonOperator::apply_within(const double* x, const FunctionBox& given, double* y) const {
  // Bands of rows, each from the elements that touch it: a band of h rows recomputes p element
  // rows of its neighbours', so bands stay at least 16 (p + 1) rows tall.
  const int bands = std::clamp(given.count_v / (16 * (v_.degree + 1)), 1, 8 * omp_get_max_threads());
#pragma omp parallel for schedule(dynamic)
  for (int k = 0; k < bands; ++k) {
    const int b0 = static_cast<int>(long(given.count_v) * k / bands), b1 = static_cast<int>(long(given.count_v) * (k + 1) / bands);
    const FunctionBox rows{given.first_u, given.count_u, given.first_v + b0, b1 - b0};
    apply_rows(x, given, rows, y + long(given.count_u) * b0);
  }
}

namespace {

// The Kronecker form's two passes, W = 2p + 1 band entries per row when known (0: at run
// time), each a sum of shifted rows (vectorized along them): s_t = X B_t^T along v over the
// padded u range, then y = sum_t A_t s_t along u.
template <int W>
void kronecker_sized(const double* in, long mu, int wu_, int wv_, int first_u, int count_u, int first_v, int count_v,
                     int nu, const double* a1, const double* a2, const double* a3, const double* a4, const double* mv,
                     const double* kv, const double* cvt, const double* cv, bool mixed, double* y) {
  const int wu = W ? W : wu_, wv = W ? W : wv_;
  // One output row at a time: its v-pass rows stay in cache (a band-wide buffer would be
  // zeroed, written and read again: 2 x 134 MB per product at 4096^2).
  thread_local std::vector<double> s1, s2, s3, s4;
  s1.resize(mu), s2.resize(mu);
  if (mixed) s3.resize(mu), s4.resize(mu);
  double *o1 = s1.data(), *o2 = s2.data(), *o3 = mixed ? s3.data() : nullptr, *o4 = mixed ? s4.data() : nullptr;
  for (int jj = 0; jj < count_v; ++jj) {
    const size_t row = size_t(first_v + jj) * wv;
    std::fill(o1, o1 + mu, 0.0), std::fill(o2, o2 + mu, 0.0);
    if (mixed) std::fill(o3, o3 + mu, 0.0), std::fill(o4, o4 + mu, 0.0);
    for (int t = 0; t < wv; ++t) {
      const double* x = in + mu * (jj + t);
      const double m = mv[row + t], k = kv[row + t];
#pragma omp simd
      for (long a = 0; a < mu; ++a) o1[a] += m * x[a], o2[a] += k * x[a];
      if (mixed) {  // X C_v (C_v(c, j) = C_v^T(j, c)) and X C_v^T
        const double c3 = cvt[row + t], c4 = cv[row + t];
#pragma omp simd
        for (long a = 0; a < mu; ++a) o3[a] += c3 * x[a], o4[a] += c4 * x[a];
      }
    }
    double* out = y + long(count_u) * jj;
    std::fill(out, out + count_u, 0.0);
    for (int t = 0; t < wu; ++t) {
      const size_t at = size_t(t) * nu + first_u;
      const double *b1 = a1 + at, *b2 = a2 + at, *t1 = o1 + t, *t2 = o2 + t;
#pragma omp simd
      for (int i = 0; i < count_u; ++i) out[i] += b1[i] * t1[i] + b2[i] * t2[i];
      if (mixed) {
        const double *b3 = a3 + at, *b4 = a4 + at, *t3 = o3 + t, *t4 = o4 + t;
#pragma omp simd
        for (int i = 0; i < count_u; ++i) out[i] += b3[i] * t3[i] + b4[i] * t4[i];
      }
    }
  }
}

}  // namespace

void TensorPoissonOperator::kronecker_rows(const double* in, long mu, const FunctionBox& rows, double* y) const {
  const KroneckerForm& k = kronecker_;
  const int pu = u_.degree, pv = v_.degree;
  auto run = [&](auto width) {
    kronecker_sized<decltype(width)::value>(in, mu, 2 * pu + 1, 2 * pv + 1, rows.first_u, rows.count_u, rows.first_v,
                                            rows.count_v, band_u_.n, k.a1.data(), k.a2.data(), k.a3.data(), k.a4.data(),
                                            band_v_.M.data(), band_v_.K.data(), k.cvt.data(), band_v_.C.data(), k.mixed, y);
  };
  if (pu == pv && pu == 2) return run(std::integral_constant<int, 5>{});
  if (pu == pv && pu == 3) return run(std::integral_constant<int, 7>{});
  if (pu == pv && pu == 4) return run(std::integral_constant<int, 9>{});
  return run(std::integral_constant<int, 0>{});
}

template <int N, class Gather, class Scatter>
void TensorPoissonOperator::product(Gather gather, Scatter scatter, const std::array<int, 4>* elements) const {
  const bool rational = weights_.size() > 0;
  const int pu = N ? N : u_.degree + 1, pv = N ? N : v_.degree + 1, qu = N ? N : u_.points, qv = N ? N : v_.points;
  // An element whose factors are constant (an affine map there): K_e X = d11 Ku X Mv^T +
  // d22 Mu X Kv^T + d12 (Cu X Cv + Cu^T X Cv^T) + c |det| Mu X Mv^T, from the element's
  // univariate matrices (affine_factors), with no geometry and no points.
  const auto affine = [&](int eu, int ev, int fu, int fv, const std::array<double, 4>& f) {
    const double *Ku = &u_.stiffness[size_t(eu) * pu * pu], *Mu = &u_.mass[size_t(eu) * pu * pu], *Cu = &u_.mixed[size_t(eu) * pu * pu];
    const double *Kv = &v_.stiffness[size_t(ev) * pv * pv], *Mv = &v_.mass[size_t(ev) * pv * pv], *Cv = &v_.mixed[size_t(ev) * pv * pv];
    constexpr int M = N ? N : kMaxP;  // (sized to N when known: the stack stays small)
    double X[M][M], t1[M][M], t2[M][M], t3[M][M], t4[M][M];
    for (int b = 0; b < pv; ++b)
      for (int a = 0; a < pu; ++a) X[b][a] = gather(fu + a, fv + b);
    // Over v: t1 = X Mv^T, t2 = X Kv^T, t3 = X Cv, t4 = X Cv^T (column b of each, a fastest).
    for (int b = 0; b < pv; ++b)
      for (int a = 0; a < pu; ++a) {
        double s1 = 0, s2 = 0, s3 = 0, s4 = 0;
        for (int c = 0; c < pv; ++c) {
          s1 += X[c][a] * Mv[b * pv + c];
          s2 += X[c][a] * Kv[b * pv + c];
          s3 += X[c][a] * Cv[c * pv + b];
          s4 += X[c][a] * Cv[b * pv + c];
        }
        t1[b][a] = s1, t2[b][a] = s2, t3[b][a] = s3, t4[b][a] = s4;
      }
    const double d11 = stiffness_ * f[0], d12 = stiffness_ * f[1], d22 = stiffness_ * f[2], r = reaction_ * f[3];
    for (int b = 0; b < pv; ++b)
      for (int a = 0; a < pu; ++a) {
        double y = 0;
        for (int c = 0; c < pu; ++c)
          y += (d11 * Ku[a * pu + c] + r * Mu[a * pu + c]) * t1[b][c] + d22 * Mu[a * pu + c] * t2[b][c] +
               d12 * (Cu[a * pu + c] * t3[b][c] + Cu[c * pu + a] * t4[b][c]);
        scatter(fu + a, fv + b, y);
      }
  };
  for_each_element<N>([&](int, int, int fu, int fv, const double* bu, const double* du, const double* bv, const double* dv,
                          const Points& pts) {
    double c[kMaxP * kMaxP];
    Field s;
    for (int b = 0; b < pv; ++b)
      for (int a = 0; a < pu; ++a) c[a + pu * b] = gather(fu + a, fv + b);
    evaluate_field<N>(c, pu, pv, qu, qv, bu, du, bv, dv, s);
    // At each point the flux q = c_s D grad u and the reaction c_r m u, moved onto the test
    // functions' factors: grad R_a = w_a (grad N_a - N_a grad W / W) / W.
    double g1[kMaxPoints * kMaxPoints], g2[kMaxPoints * kMaxPoints], h[kMaxPoints * kMaxPoints];
    for (int k = 0; k < qu * qv; ++k) {
      double u = s.value[k], gu = s.du[k], gv = s.dv[k];
      double inv = 1;
      if (rational) {
        inv = 1 / pts.w.value[k];
        u *= inv;
        gu = (gu - u * pts.w.du[k]) * inv;
        gv = (gv - u * pts.w.dv[k]) * inv;
      }
      const double q1 = stiffness_ * (pts.d11[k] * gu + pts.d12[k] * gv);
      const double q2 = stiffness_ * (pts.d12[k] * gu + pts.d22[k] * gv);
      const double r = reaction_ * pts.measure[k] * u;
      if (rational) {
        g1[k] = q1 * inv, g2[k] = q2 * inv;
        h[k] = (r - (pts.w.du[k] * q1 + pts.w.dv[k] * q2) * inv) * inv;
      } else {
        g1[k] = q1, g2[k] = q2, h[k] = r;
      }
    }
    // r(a, b) = sum_ij Du(i,a) Bv(j,b) g1 + Bu(i,a) (Dv(j,b) g2 + Bv(j,b) h), over v first.
    double a1[kMaxP][kMaxPoints], a2[kMaxP][kMaxPoints];
    for (int b = 0; b < pv; ++b)
      for (int i = 0; i < qu; ++i) {
        double s1 = 0, s2 = 0;
        for (int j = 0; j < qv; ++j) {
          const int k = i + qu * j;
          s1 += bv[j * pv + b] * g1[k];
          s2 += dv[j * pv + b] * g2[k] + bv[j * pv + b] * h[k];
        }
        a1[b][i] = s1, a2[b][i] = s2;
      }
    for (int b = 0; b < pv; ++b)
      for (int a = 0; a < pu; ++a) {
        double r = 0;
        for (int i = 0; i < qu; ++i) r += du[i * pu + a] * a1[b][i] + bu[i * pu + a] * a2[b][i];
        scatter(fu + a, fv + b, r);
      }
  }, affine, nullptr, elements);
}

Eigen::VectorXd TensorPoissonOperator::diagonal() const {
  if (uniform_) {  // the Kronecker form's diagonal (det J > 0 was checked with the factors)
    const std::array<double, 4>& f = uniform_factors_;
    const double d11 = stiffness_ * f[0], d12 = stiffness_ * f[1], d22 = stiffness_ * f[2], r = reaction_ * f[3];
    const int wu = 2 * u_.degree + 1, wv = 2 * v_.degree + 1;
    Eigen::VectorXd diagonal(num_functions());
#pragma omp parallel for schedule(static)
    for (int j = 0; j < n_v_; ++j) {
      const size_t jv = size_t(j) * wv + v_.degree;
      for (int i = 0; i < n_u_; ++i) {
        const size_t iu = size_t(i) * wu + u_.degree;
        diagonal[i + long(n_u_) * j] = d11 * band_u_.K[iu] * band_v_.M[jv] + d22 * band_u_.M[iu] * band_v_.K[jv] +
                                       2 * d12 * band_u_.C[iu] * band_v_.C[jv] + r * band_u_.M[iu] * band_v_.M[jv];
      }
    }
    return diagonal;
  }
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(num_functions());
  double* out = diagonal.data();
  const bool rational = weights_.size() > 0;
  const int pu = u_.degree + 1, pv = v_.degree + 1, qu = u_.points, qv = v_.points;
  double min_det = std::numeric_limits<double>::infinity();
  for_each_element<0>([&](int, int, int fu, int fv, const double* bu, const double* du, const double* bv, const double* dv,
                          const Points& pts) {
    if (pts.min_det < min_det) {
#pragma omp critical(knotwork_tensor_operator_det)
      min_det = std::min(min_det, pts.min_det);
    }
    for (int b = 0; b < pv; ++b)
      for (int a = 0; a < pu; ++a) {
        const int f = (fu + a) + n_u_ * (fv + b);
        const double wa = rational ? weights_[f] : 1;
        double sum = 0;
        for (int j = 0; j < qv; ++j)
          for (int i = 0; i < qu; ++i) {
            const int k = i + qu * j;
            double n = bu[i * pu + a] * bv[j * pv + b], nu = du[i * pu + a] * bv[j * pv + b],
                   nv = bu[i * pu + a] * dv[j * pv + b];
            if (rational) {
              const double inv = 1 / pts.w.value[k];
              n *= wa * inv;
              nu = (wa * nu - n * pts.w.du[k]) * inv;
              nv = (wa * nv - n * pts.w.dv[k]) * inv;
            }
            sum += stiffness_ * (nu * (pts.d11[k] * nu + pts.d12[k] * nv) + nv * (pts.d12[k] * nu + pts.d22[k] * nv)) +
                   reaction_ * pts.measure[k] * n * n;
          }
        out[f] += sum;
      }
  });
  if (!(min_det > 0))
    throw std::invalid_argument("TensorPoissonOperator: the geometry's Jacobian is not positive at a quadrature point (det J = " +
                                std::to_string(min_det) + ")");
  return diagonal;
}

void TensorPoissonOperator::row_coefficients(int ev, RowCoefficients& out) const {
  const bool rational = weights_.size() > 0;
  const int qu = u_.points, qv = v_.points;
  const size_t along = size_t(u_.elements) * qu;
  for (int k = 0; k < 6; ++k) out.d[k].assign(rational || (k != 2 && k != 4) ? along * qv : 0, 0.0);
  out.element_row = ev;
  out.min_det = std::numeric_limits<double>::infinity();
  out.bad_element = -1;
  const std::array<int, 4> row{0, u_.elements - 1, ev, ev};
  const double cs = stiffness_, cr = reaction_;
  dispatch(u_, v_, [&](auto n, auto q) {
    for_each_element<decltype(n)::value, decltype(q)::value>(
        [&](int eu, int, int, int, const double*, const double*, const double*, const double*, const Points& pts) {
          if (pts.min_det < out.min_det) out.min_det = pts.min_det;
          if (!(pts.min_det > 0) && out.bad_element < 0) out.bad_element = eu;
          for (int j = 0; j < qv; ++j)
            for (int i = 0; i < qu; ++i) {
              const int k = i + qu * j;
              const size_t at = size_t(j) * along + size_t(eu) * qu + i;
              const double d11 = cs * pts.d11[k], d12 = cs * pts.d12[k], d22 = cs * pts.d22[k], m = cr * pts.measure[k];
              if (!rational) {
                out.d[0][at] = d11, out.d[1][at] = d12, out.d[3][at] = d22, out.d[5][at] = m;
                continue;
              }
              // grad R_a = w_a P (N_u' N_v, N_u N_v', N_u N_v) with P = [1/W, 0, -W_u/W^2; 0, 1/W, -W_v/W^2].
              const double a = 1 / pts.w.value[k], bu = -pts.w.du[k] * a * a, bv = -pts.w.dv[k] * a * a;
              out.d[0][at] = a * a * d11;
              out.d[1][at] = a * a * d12;
              out.d[3][at] = a * a * d22;
              out.d[2][at] = a * (d11 * bu + d12 * bv);
              out.d[4][at] = a * (d12 * bu + d22 * bv);
              out.d[5][at] = bu * (d11 * bu + d12 * bv) + bv * (d12 * bu + d22 * bv) + m * a * a;
            }
        },
        nullptr, nullptr, &row);
  });
}

Eigen::VectorXd TensorPoissonOperator::load(const Expression& source) const {
  if (net_->rows() == 0) throw std::logic_error("TensorPoissonOperator::load: an operator made without a geometry net");
  Eigen::VectorXd out = Eigen::VectorXd::Zero(num_functions());
  double* f_out = out.data();
  const bool rational = weights_.size() > 0;
  const int pu = u_.degree + 1, pv = v_.degree + 1, qu = u_.points, qv = v_.points;
  // One compiled program per thread (a program's registers are its own).
  const ExpressionBatch compiled(std::vector<Expression>{source});
  std::vector<std::optional<ExpressionBatch>> batches(omp_get_max_threads());
  // The first element (in the mesh's cell order) where f is not finite, and the point there.
  long bad_cell = std::numeric_limits<long>::max();
  double bad_x = 0, bad_y = 0;
  dispatch(u_, v_, [&](auto n, auto q) {
  for_each_element<decltype(n)::value, decltype(q)::value>([&](int eu, int ev, int fu, int fv, const double* bu, const double*,
                                                               const double* bv, const double*, const Points& pts) {
    std::optional<ExpressionBatch>& f = batches[omp_get_thread_num()];
    if (!f) f.emplace(compiled);
    f->evaluate(pts.x, pts.y, nullptr, qu * qv);
    const double* value = f->result(0);
    // F_a = w_a sum_q N_a (m f / W): the test functions' factors as in apply.
    double h[kMaxPoints * kMaxPoints];
    for (int k = 0; k < qu * qv; ++k) {
      if (!std::isfinite(value[k])) {
        const long cell = eu + long(u_.elements) * ev;
#pragma omp critical(knotwork_operator_bad_source)
        if (cell < bad_cell) bad_cell = cell, bad_x = pts.x[k], bad_y = pts.y[k];
      }
      h[k] = pts.measure[k] * value[k] / (rational ? pts.w.value[k] : 1.0);
    }
    for (int b = 0; b < pv; ++b) {
      double a2[kMaxPoints];
      for (int i = 0; i < qu; ++i) {
        double s = 0;
        for (int j = 0; j < qv; ++j) s += bv[j * pv + b] * h[i + qu * j];
        a2[i] = s;
      }
      for (int a = 0; a < pu; ++a) {
        double r = 0;
        for (int i = 0; i < qu; ++i) r += bu[i * pu + a] * a2[i];
        const int g = (fu + a) + n_u_ * (fv + b);
        f_out[g] += rational ? weights_[g] * r : r;
      }
    }
  });
  });
  if (bad_cell != std::numeric_limits<long>::max()) {
    // As the element loop words it (solver/assemble_poisson.cpp), the cell numbered as the mesh's.
    const std::vector<double> u = space_u_.breakpoints(), v = space_v_.breakpoints();
    const long eu = bad_cell % u_.elements, ev = bad_cell / u_.elements;
    std::ostringstream m;
    m << source.where() << ": source \"" << source.text() << "\" is not a finite number at (" << bad_x << ", " << bad_y
      << ") in " << describe_cell(int(bad_cell), u[eu], u[eu + 1], v[ev], v[ev + 1]);
    throw InputError(m.str());
  }
  return out;
}

bool TensorPoissonOperator::squared_errors(const Eigen::VectorXd& coefficients, const ExactSolution& exact, int points_u,
                                           int points_v, std::array<double, 2>& squares,
                                           Eigen::VectorXd* h1_per_element, CellRange cells) const {
  if (net_->rows() == 0) return false;  // (a coarse level's operator: no geometry to evaluate)
  if (coefficients.size() != num_functions())
    throw std::invalid_argument("TensorPoissonOperator::squared_errors: wrong vector size");
  // The error rule's tables (error_norms's default: degree + 2 points per direction).
  const Direction U = direction(space_u_, geometry_u_, points_u > 0 ? points_u : u_.degree + 2);
  const Direction V = direction(space_v_, geometry_v_, points_v > 0 ? points_v : v_.degree + 2);
  const bool rational = weights_.size() > 0;
  const Eigen::VectorXd scaled = rational ? Eigen::VectorXd(coefficients.cwiseProduct(weights_)) : Eigen::VectorXd();
  const double* cw = rational ? scaled.data() : coefficients.data();
  const int pu = U.degree + 1, pv = V.degree + 1, qu = U.points, qv = V.points;
  const ExpressionBatch compiled(std::vector<Expression>{exact.u, exact.u_x, exact.u_y});
  std::vector<std::optional<ExpressionBatch>> batches(omp_get_max_threads());
  // Per element row (one thread sums a row), then the rows in order: the totals do not depend
  // on the threads. Per element only what was asked for (16 bytes per element less at 4096^2).
  std::vector<double> l2_rows(V.elements, 0.0), h1_rows(V.elements, 0.0);
  double* h1 = nullptr;
  const long all = long(U.elements) * V.elements;
  const long first = cells.first, last = cells.last < 0 ? all : cells.last;
  if (h1_per_element) {
    h1_per_element->setZero(all);
    h1 = h1_per_element->data();
  }
  dispatch(U, V, [&](auto n, auto q) {
  constexpr int N = decltype(n)::value, Q = decltype(q)::value;
  for_each_element<N, Q>([&](int eu, int ev, int fu, int fv, const double* bu, const double* du, const double* bv,
                             const double* dv, const Points& pts) {
    const long element = eu + long(U.elements) * ev;
    if (element < first || element >= last) return;
    std::optional<ExpressionBatch>& f = batches[omp_get_thread_num()];
    if (!f) f.emplace(compiled);
    f->evaluate(pts.x, pts.y, nullptr, qu * qv);
    const double *u = f->result(0), *ux = f->result(1), *uy = f->result(2);
    double c[kMaxP * kMaxP];
    for (int b = 0; b < pv; ++b)
      for (int a = 0; a < pu; ++a) c[a + pu * b] = cw[(fu + a) + long(n_u_) * (fv + b)];
    Field s;
    evaluate_field<N, Q>(c, pu, pv, qu, qv, bu, du, bv, dv, s);
    double e0 = 0, e1 = 0;
    for (int k = 0; k < qu * qv; ++k) {
      double uh = s.value[k], gu = s.du[k], gv = s.dv[k];
      if (rational) {  // u_h = S / W, its parameter derivatives (S' - u_h W') / W
        const double inv = 1 / pts.w.value[k];
        uh *= inv;
        gu = (gu - uh * pts.w.du[k]) * inv;
        gv = (gv - uh * pts.w.dv[k]) * inv;
      }
      // grad u_h = J^-T (u_h,u, u_h,v).
      const double det = pts.xu[k] * pts.yv[k] - pts.xv[k] * pts.yu[k];
      const double gx = (pts.yv[k] * gu - pts.yu[k] * gv) / det, gy = (-pts.xv[k] * gu + pts.xu[k] * gv) / det;
      const double e = u[k] - uh, ex = ux[k] - gx, ey = uy[k] - gy;
      e0 += pts.measure[k] * e * e;
      e1 += pts.measure[k] * (ex * ex + ey * ey);
    }
    l2_rows[ev] += e0;
    h1_rows[ev] += e1;
    if (h1) h1[size_t(eu) + size_t(U.elements) * ev] = e1;
  }, nullptr, nullptr, nullptr, &U, &V);
  });
  squares = {0, 0};
  for (int ev = 0; ev < V.elements; ++ev) squares[0] += l2_rows[ev], squares[1] += h1_rows[ev];
  return true;
}

}  // namespace knotwork
