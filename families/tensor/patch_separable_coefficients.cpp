// The geometry's stiffness coefficients of one patch, fitted as products (fast_diagonalization).
#include "families/tensor/patch_separable_coefficients.hpp"

#include <Eigen/Geometry>

#include "basis/core/nurbs_volume.hpp"
#include "solver/expression.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace knotwork {

namespace {

// The problem's reaction c at a point: its constant, or its expression.
class ReactionAt {
 public:
  explicit ReactionAt(const PoissonProblem* problem) {
    if (!problem) return;
    if (!problem->coefficients.reaction.empty())
      expression_.emplace(problem->coefficients.reaction);
    else
      constant_ = problem->reaction;
  }
  bool any() const { return expression_ || constant_ != 0; }
  double operator()(double x, double y, double z) { return expression_ ? (*expression_)(x, y, z) : constant_; }

 private:
  std::optional<ExpressionEvaluator> expression_;
  double constant_ = 0;
};

// The reaction's samples c det J |cell| at cells (one index per direction), and the shift
// they give against the fitted masses: sum c det J |cell| / sum prod_d mass_d |cell|, the
// ratio of A 1 to (M (x) M ...) 1 in the mean.
template <int D>
struct ReactionSamples {
  std::vector<std::array<int, D>> cell;
  std::vector<double> volume, value;
  void add(const std::array<int, D>& at, double cell_volume, double c_det) {
    cell.push_back(at);
    volume.push_back(cell_volume);
    value.push_back(c_det * cell_volume);
  }
  double shift(const std::array<const std::vector<double>*, D>& mass) const {
    double reaction = 0, model = 0;
    for (size_t s = 0; s < cell.size(); ++s) {
      double m = volume[s];
      for (int d = 0; d < D; ++d) m *= mass[d]->empty() ? 1.0 : (*mass[d])[cell[s][d]];
      reaction += value[s];
      model += m;
    }
    return model > 0 && reaction > 0 ? reaction / model : 0.0;
  }
};

}  // namespace

namespace {

// The parameter derivatives (x_u x_v; y_u y_v) and the point at an element's midpoint.
struct MidpointGeometry {
  Eigen::Matrix2d jacobian;
  double x = 0, y = 0;
};

// The stiffness coefficients at element midpoints, in parameter derivatives:
// c11 = |x_v|^2 / det, c22 = |x_u|^2 / det; then their fit. Only every row against 32 sampled
// columns and every column against 32 sampled rows are evaluated: O(n) elements instead of n^2,
// and still exact for separable maps. `at(i, j)` gives element (i, j)'s midpoint geometry.
template <class Midpoint>
SeparableCoefficients fit_at_midpoints(const BSplineBasis1D& space_u, const BSplineBasis1D& space_v, Midpoint at,
                                       const PoissonProblem* problem) {
  const int nu = space_u.num_elements(), nv = space_v.num_elements();
  auto sample = [](int n) {
    std::vector<int> v;
    const int m = std::min(n, 32);
    for (int k = 0; k < m; ++k) v.push_back(m == 1 ? 0 : static_cast<int>((static_cast<long>(k) * (n - 1)) / (m - 1)));
    return v;
  };
  auto lengths = [](const BSplineBasis1D& b) {
    std::vector<double> h;
    for (int s : b.element_spans()) h.push_back(b.knots()[s + 1] - b.knots()[s]);
    return h;
  };
  const std::vector<double> h_u = lengths(space_u), h_v = lengths(space_v);
  const std::vector<int> rows = sample(nu), columns = sample(nv);
  std::vector<double> c11(static_cast<size_t>(nu) * nv, 1.0), c22(c11.size(), 1.0);
  bool ok = true;
  ReactionAt reaction(problem);
  ReactionSamples<2> samples;
  auto measure = [&](int i, int j) {
    const size_t k = i + static_cast<size_t>(nu) * j;
    const MidpointGeometry g = at(i, j, h_u[i], h_v[j]);
    const double xu = g.jacobian(0, 0), xv = g.jacobian(0, 1), yu = g.jacobian(1, 0), yv = g.jacobian(1, 1);
    const double det = xu * yv - xv * yu;
    if (!(det > 0)) return void(ok = false);  // assembly refuses such maps before this is built
    c11[k] = (xv * xv + yv * yv) / det;
    c22[k] = (xu * xu + yu * yu) / det;
    if (reaction.any()) samples.add({i, j}, h_u[i] * h_v[j], reaction(g.x, g.y, 0) * det);
  };
  for (int i = 0; i < nu; ++i)
    for (int j : columns) measure(i, j);
  for (int j = 0; j < nv; ++j)
    for (int i : rows) measure(i, j);
  if (!ok) return {};
  SeparableCoefficients fitted = SeparableCoefficients::fit(nu, nv, c11, c22, rows, columns);
  fitted.shift = samples.shift({&fitted.a2, &fitted.b1});
  return fitted;
}

}  // namespace

// From the patch's own grid map, so that a part of the space (which holds a few rows) gets the
// whole fit: x_u = (dx/du_ref) / h_u at the one-point Gauss rule.
SeparableCoefficients patch_separable_coefficients(const TensorDiscretization& patch, const PatchGeometryMap& geometry,
                                                   const PoissonProblem* problem) {
  GeometryAtPoints at;
  return fit_at_midpoints(
      patch.space_u, patch.space_v,
      [&](int i, int j, double hu, double hv) {
        geometry.evaluate_element_at_rule(i, j, 1, 1, at);
        MidpointGeometry g;
        g.jacobian << at.jacobian(0, 0) / hu, at.jacobian(0, 1) / hv, at.jacobian(0, 2) / hu, at.jacobian(0, 3) / hv;
        g.x = at.x(0, 0);
        g.y = at.x(0, 1);
        return g;
      },
      problem);
}

SeparableCoefficients patch_separable_coefficients(const NurbsPatch& patch, const BSplineBasis1D& space_u,
                                                   const BSplineBasis1D& space_v, const PoissonProblem* problem) {
  const std::vector<int> su = space_u.element_spans(), sv = space_v.element_spans();
  const std::vector<double>&tu = space_u.knots(), &tv = space_v.knots();
  return fit_at_midpoints(
      space_u, space_v,
      [&](int i, int j, double, double) {
        const PatchPointDerivatives d =
            patch_point_derivatives(patch, (tu[su[i]] + tu[su[i] + 1]) / 2, (tv[sv[j]] + tv[sv[j] + 1]) / 2);
        return MidpointGeometry{d.jacobian, d.x[0], d.x[1]};
      },
      problem);
}

double separability_spread(const NurbsPatch& patch, const std::vector<Expression>& diffusion, int k) {
  const std::vector<double>&tu = patch.basis_u.knots(), &tv = patch.basis_v.knots();
  const double u0 = tu.front(), u1 = tu.back(), v0 = tv.front(), v1 = tv.back();
  const size_t n = size_t(k) * k;
  std::vector<double> c11(n), c12(n), c22(n), x(n), y(n);
  std::vector<Eigen::Matrix2d> jacobian(n);
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) {
      const size_t m = i + size_t(k) * j;
      const PatchPointDerivatives d = patch_point_derivatives(patch, u0 + (i + 0.5) * (u1 - u0) / k, v0 + (j + 0.5) * (v1 - v0) / k);
      jacobian[m] = d.jacobian;
      x[m] = d.x[0], y[m] = d.x[1];
    }
  std::optional<ExpressionBatch> a;
  if (!diffusion.empty()) {
    a.emplace(diffusion);
    a->evaluate(x.data(), y.data(), nullptr, long(n));
  }
  for (size_t m = 0; m < n; ++m) {
    const Eigen::Matrix2d& J = jacobian[m];
    const double det = J.determinant();
    Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
    if (a && diffusion.size() == 1) A *= a->result(0)[m];
    if (a && diffusion.size() == 3) A << a->result(0)[m], a->result(1)[m], a->result(1)[m], a->result(2)[m];
    if (!(det > 0) || !(A.determinant() > 0) || !(A(0, 0) > 0)) return std::numeric_limits<double>::infinity();
    // |det J| J^-1 A J^-T = adj(J) A adj(J)^T / det J.
    Eigen::Matrix2d adjugate;
    adjugate << J(1, 1), -J(0, 1), -J(1, 0), J(0, 0);
    const Eigen::Matrix2d C = adjugate * A * adjugate.transpose() / det;
    c11[m] = C(0, 0), c12[m] = C(0, 1), c22[m] = C(1, 1);
  }
  const SeparableCoefficients fitted = SeparableCoefficients::fit(k, k, c11, c22);
  double largest = 0, smallest = std::numeric_limits<double>::infinity();
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) {
      const size_t m = i + size_t(k) * j;
      // P^-1/2 C P^-1/2 = [a, b; b, c]: its eigenvalues (a + c)/2 +- sqrt(((a - c)/2)^2 + b^2).
      const double p1 = fitted.a1[i] * fitted.b1[j], p2 = fitted.a2[i] * fitted.b2[j];
      const double a = c11[m] / p1, c = c22[m] / p2, b = c12[m] / std::sqrt(p1 * p2);
      const double mean = (a + c) / 2, radius = std::hypot((a - c) / 2, b);
      largest = std::max(largest, mean + radius);
      smallest = std::min(smallest, mean - radius);
    }
  return smallest > 0 ? largest / smallest : std::numeric_limits<double>::infinity();
}

SeparableVolumeCoefficients volume_separable_coefficients(const TensorVolumeDiscretization& d, const PoissonProblem* problem) {
  std::array<std::vector<double>, 3> middle, length;
  std::array<int, 3> n;
  for (int k = 0; k < 3; ++k) {
    const auto& t = d.space[k].knots();
    for (int s : d.space[k].element_spans()) {
      middle[k].push_back((t[s] + t[s + 1]) / 2);
      length[k].push_back(t[s + 1] - t[s]);
    }
    n[k] = static_cast<int>(middle[k].size());
  }
  ReactionAt reaction(problem);
  ReactionSamples<3> samples;
  SeparableVolumeCoefficients fitted = SeparableVolumeCoefficients::fit(n, [&](int i, int j, int k) {
    const VolumePointDerivatives at = volume_point_derivatives(d.volume, {middle[0][i], middle[1][j], middle[2][k]});
    const Eigen::Matrix3d& J = at.jacobian;
    const double det = J.determinant();
    if (!(det > 0)) return std::array<double, 3>{1, 1, 1};
    if (reaction.any())
      samples.add({i, j, k}, length[0][i] * length[1][j] * length[2][k], reaction(at.x[0], at.x[1], at.x[2]) * det);
    return std::array<double, 3>{J.col(1).cross(J.col(2)).squaredNorm() / det, J.col(2).cross(J.col(0)).squaredNorm() / det,
                                 J.col(0).cross(J.col(1)).squaredNorm() / det};
  });
  fitted.shift = samples.shift({&fitted.mu[0], &fitted.mu[1], &fitted.mu[2]});
  return fitted;
}

}  // namespace knotwork
