#include "cases/spline_space.hpp"

#include <algorithm>

#include "basis/core/input_error.hpp"

namespace knotwork {

double SplineSpace::mesh_size() const { return largest_cell_diagonal(mesh(), geometry()); }

void SpaceReport::export_functions(const std::string&, const std::string&) const {
  throw InputError("--export: the space " + description() + " has no function export");
}

KnotLines knot_lines_of_cells(const BezierMesh& mesh, const GeometryMap& geometry, int samples) {
  KnotLines k;
  Eigen::VectorXd u(samples), v(samples);
  GeometryAtPoints g;
  // A side from (ua, va) to (ub, vb) in the cell's reference square.
  auto side = [&](int cell, double ua, double va, double ub, double vb) {
    for (int s = 0; s < samples; ++s) {
      const double t = double(s) / (samples - 1);
      u[s] = (1 - t) * ua + t * ub;
      v[s] = (1 - t) * va + t * vb;
    }
    geometry.evaluate(cell, u, v, g);
    k.lines.push_back(g.x.leftCols(2));
    k.kind.push_back(2);
    k.multiplicity.push_back(1);
  };
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& b = mesh.cell(c);
    side(c, 0, 0, 1, 0);
    side(c, 0, 0, 0, 1);
    if (b.boundary[kSideTop] >= 0) side(c, 0, 1, 1, 1);
    if (b.boundary[kSideRight] >= 0) side(c, 1, 0, 1, 1);
  }
  return k;
}

double largest_cell_diagonal(const BezierMesh& mesh, const GeometryMap& geometry) {
  Eigen::VectorXd u(4), v(4);
  u << 0, 1, 1, 0;
  v << 0, 0, 1, 1;
  double h = 0;
  GeometryAtPoints g;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    geometry.evaluate(c, u, v, g);
    h = std::max({h, (g.x.row(0) - g.x.row(2)).norm(), (g.x.row(1) - g.x.row(3)).norm()});
  }
  return h;
}

}  // namespace knotwork
