#include "cases/spline_space.hpp"

#include <algorithm>

#include "solver/input_error.hpp"

namespace knotwork {

double SplineSpace::mesh_size() const { return largest_cell_diagonal(mesh(), geometry()); }

void SplineSpace::export_functions(const std::string&, const std::string&) const {
  throw InputError("--export: the space " + description() + " has no function export");
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
