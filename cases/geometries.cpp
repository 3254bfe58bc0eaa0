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

}  // namespace knotwork
