// The geometry's stiffness coefficients of one patch, fitted as products (fast_diagonalization).
#include "families/tensor/patch_separable_coefficients.hpp"

#include <Eigen/Geometry>

#include "basis/core/nurbs_volume.hpp"

#include <algorithm>

namespace knotwork {

// The stiffness coefficients at element midpoints, in parameter derivatives
// x_u = (dx/du_ref) / h_u: c11 = |x_v|^2 / det, c22 = |x_u|^2 / det; then their fit. Only
// every row against 32 sampled columns and every column against 32 sampled rows are
// evaluated: O(n) elements instead of n^2, and still exact for separable maps. From the
// patch itself, so that a part of the space (which holds a few rows) gets the whole fit.
SeparableCoefficients patch_separable_coefficients(const TensorDiscretization& patch, const PatchGeometryMap& geometry) {
  const int nu = patch.space_u.num_elements(), nv = patch.space_v.num_elements();
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
  const std::vector<double> h_u = lengths(patch.space_u), h_v = lengths(patch.space_v);
  const std::vector<int> rows = sample(nu), columns = sample(nv);
  std::vector<double> c11(static_cast<size_t>(nu) * nv, 1.0), c22(c11.size(), 1.0);
  GeometryAtPoints at;
  bool ok = true;
  auto measure = [&](int i, int j) {
    const size_t k = i + static_cast<size_t>(nu) * j;
    geometry.evaluate_element_at_rule(i, j, 1, 1, at);  // the one-point Gauss rule: the midpoint
    const double hu = h_u[i], hv = h_v[j];
    const double xu = at.jacobian(0, 0) / hu, xv = at.jacobian(0, 1) / hv;
    const double yu = at.jacobian(0, 2) / hu, yv = at.jacobian(0, 3) / hv;
    const double det = xu * yv - xv * yu;
    if (!(det > 0)) return void(ok = false);  // assembly refuses such maps before this is built
    c11[k] = (xv * xv + yv * yv) / det;
    c22[k] = (xu * xu + yu * yu) / det;
  };
  for (int i = 0; i < nu; ++i)
    for (int j : columns) measure(i, j);
  for (int j = 0; j < nv; ++j)
    for (int i : rows) measure(i, j);
  if (!ok) return {};
  return SeparableCoefficients::fit(nu, nv, c11, c22, rows, columns);
}

SeparableVolumeCoefficients volume_separable_coefficients(const TensorVolumeDiscretization& d) {
  std::array<std::vector<double>, 3> middle;
  std::array<int, 3> n;
  for (int k = 0; k < 3; ++k) {
    const auto& t = d.space[k].knots();
    for (int s : d.space[k].element_spans()) middle[k].push_back((t[s] + t[s + 1]) / 2);
    n[k] = static_cast<int>(middle[k].size());
  }
  return SeparableVolumeCoefficients::fit(n, [&](int i, int j, int k) {
    const Eigen::Matrix3d J = volume_point_derivatives(d.volume, {middle[0][i], middle[1][j], middle[2][k]}).jacobian;
    const double det = J.determinant();
    if (!(det > 0)) return std::array<double, 3>{1, 1, 1};
    return std::array<double, 3>{J.col(1).cross(J.col(2)).squaredNorm() / det, J.col(2).cross(J.col(0)).squaredNorm() / det,
                                 J.col(0).cross(J.col(1)).squaredNorm() / det};
  });
}

}  // namespace knotwork
