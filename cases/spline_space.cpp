#include "cases/spline_space.hpp"

#include <algorithm>

#include "basis/core/input_error.hpp"

namespace knotwork {

double SplineSpace::mesh_size() const { return largest_cell_diagonal(mesh(), geometry()); }

void SpaceReport::export_functions(const std::string&, const std::string&) const {
  throw InputError("--export: the space " + description() + " has no function export");
}

std::function<KnotLines()> SpaceReport::knot_lines_later() const {
  KnotLines lines = knot_lines();
  if (lines.lines.empty()) return {};
  return [lines = std::move(lines)] { return lines; };
}

KnotLines knot_lines_of_cells(const BezierMesh& mesh, const GeometryMap& geometry, int samples) {
  // Each cell draws its bottom and left sides, and its top and right ones on the boundary.
  // The sides are listed first, then sampled in parallel (an adaptive loop draws them at every
  // step, on up to 10^5 cells).
  struct Side {
    int cell;
    double ua, va, ub, vb;
  };
  std::vector<Side> sides;
  sides.reserve(2 * static_cast<size_t>(mesh.num_cells()));
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& b = mesh.cell(c);
    sides.push_back({c, 0, 0, 1, 0});
    sides.push_back({c, 0, 0, 0, 1});
    if (b.boundary[kSideTop] >= 0) sides.push_back({c, 0, 1, 1, 1});
    if (b.boundary[kSideRight] >= 0) sides.push_back({c, 1, 0, 1, 1});
  }
  const long n = static_cast<long>(sides.size());
  KnotLines k;
  k.lines.resize(n);
  k.kind.assign(n, 2);
  k.multiplicity.assign(n, 1);
#pragma omp parallel
  {
    Eigen::VectorXd u(samples), v(samples);
    GeometryAtPoints g;
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) {
      const Side& e = sides[i];
      for (int s = 0; s < samples; ++s) {
        const double t = double(s) / (samples - 1);
        u[s] = (1 - t) * e.ua + t * e.ub;
        v[s] = (1 - t) * e.va + t * e.vb;
      }
      geometry.evaluate(e.cell, u, v, g);
      k.lines[i] = g.x.leftCols(2);
    }
  }
  return k;
}

double largest_cell_diagonal(const BezierMesh& mesh, const GeometryMap& geometry) {
  double h = 0;
  GeometryAtPoints g;
  if (geometry.parametric_dimension() == 3) {  // a hexahedron's four diagonals, corner k to corner 7 - k
    Eigen::VectorXd u(8), v(8), w(8);
    for (int k = 0; k < 8; ++k) u[k] = k & 1, v[k] = (k >> 1) & 1, w[k] = (k >> 2) & 1;
    for (int c = 0; c < mesh.num_cells(); ++c) {
      geometry.evaluate_volume(c, u, v, w, g);
      for (int k = 0; k < 4; ++k) h = std::max(h, (g.x.row(k) - g.x.row(7 - k)).norm());
    }
    return h;
  }
  Eigen::VectorXd u(4), v(4);
  u << 0, 1, 1, 0;
  v << 0, 0, 1, 1;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    geometry.evaluate(c, u, v, g);
    h = std::max({h, (g.x.row(0) - g.x.row(2)).norm(), (g.x.row(1) - g.x.row(3)).norm()});
  }
  return h;
}

}  // namespace knotwork
