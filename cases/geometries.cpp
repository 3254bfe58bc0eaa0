#include "cases/geometries.hpp"

#include <cmath>

namespace knotwork {

NurbsPatch rectangle_patch(double x0, double y0, double x1, double y1) {
  NurbsPatch p;
  p.basis_u = BSplineBasis1D(1, {0, 0, 1, 1});
  p.basis_v = BSplineBasis1D(1, {0, 0, 1, 1});
  p.control_points.resize(4, 2);
  p.control_points << x0, y0, x1, y0, x0, y1, x1, y1;
  p.weights.setOnes(4);
  return p;
}

NurbsPatch quarter_annulus_patch(double r1, double r2) {
  NurbsPatch p;
  p.basis_u = BSplineBasis1D(1, {0, 0, 1, 1});
  p.basis_v = BSplineBasis1D(2, {0, 0, 0, 1, 1, 1});
  p.control_points.resize(6, 2);
  p.control_points << r1, 0, r2, 0, r1, r1, r2, r2, 0, r1, 0, r2;
  const double w = 1.0 / std::sqrt(2.0);
  p.weights.resize(6);
  p.weights << 1, 1, w, w, 1, 1;
  return p;
}

NurbsPatch lshape_patch() {
  NurbsPatch p;
  p.basis_u = BSplineBasis1D(1, {0, 0, 0.5, 1, 1});
  p.basis_v = BSplineBasis1D(1, {0, 0, 1, 1});
  p.control_points.resize(6, 2);
  p.control_points << 0, -1, 0, 0, 1, 0,  // v = 0: re-entrant polyline
      -1, -1, -1, 1, 1, 1;                // v = 1: outer polyline
  p.weights.setOnes(6);
  return p;
}

NurbsVolume box_volume(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper) {
  NurbsVolume v;
  v.bases.fill(BSplineBasis1D(1, {0, 0, 1, 1}));
  v.control_points.resize(8, 3);
  for (int k = 0; k < 8; ++k)
    for (int d = 0; d < 3; ++d) v.control_points(k, d) = (k >> d) & 1 ? upper[d] : lower[d];
  v.weights.setOnes(8);
  return v;
}

NurbsVolume fichera_box_volume() {
  NurbsVolume v;
  v.bases.fill(BSplineBasis1D(1, {0, 0, 0.5, 1, 1}));
  v.control_points.resize(27, 3);
  for (int k = 0; k < 27; ++k) v.control_points.row(k) << (k % 3) - 1.0, (k / 3 % 3) - 1.0, (k / 9) - 1.0;
  v.weights.setOnes(27);
  return v;
}

NurbsVolume thick_quarter_annulus_volume(double inner_radius, double outer_radius, double height) {
  const NurbsPatch ring = quarter_annulus_patch(inner_radius, outer_radius);
  NurbsVolume v;
  v.bases = {ring.basis_u, ring.basis_v, BSplineBasis1D(1, {0, 0, 1, 1})};
  const Eigen::Index n = ring.control_points.rows();
  v.control_points.resize(2 * n, 3);
  v.weights.resize(2 * n);
  for (int k = 0; k < 2; ++k) {
    v.control_points.middleRows(k * n, n) << ring.control_points, Eigen::VectorXd::Constant(n, k * height);
    v.weights.segment(k * n, n) = ring.weights;
  }
  return v;
}

}  // namespace knotwork
