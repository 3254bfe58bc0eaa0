#include "cases/spline_space.hpp"

#include <algorithm>
#include <cmath>
#include <exception>

#include "basis/core/input_error.hpp"
#include "quadrature/bernstein.hpp"

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

namespace {

// One side of a cell's (rational) Bezier form: its control points along the side (the side's
// Bezier curve) drawn as two points where they lie on the segment between its ends (the curve
// is then that segment: it stays in their convex hull and joins the ends), else sampled at
// `samples` points. Straight sides are most of an adaptive mesh's on a polygonal domain; two
// points draw them exactly and make the file 4-5 times smaller than nine.
Eigen::MatrixX2d draw_side(const BezierGeometryCell& g, int first, int stride, int degree, int samples) {
  const auto point = [&](int k) -> Eigen::RowVector2d { return g.points.row(first + k * stride).leftCols<2>(); };
  const Eigen::RowVector2d a = point(0), b = point(degree);
  const Eigen::RowVector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  // Rounding of the Bezier form (products of extraction and subdivision matrices): relative
  // to the coordinates' size, so that a side of a cell 1e-9 wide near a corner is still seen
  // as straight. A curvature below 1e-12 of the domain's size is invisible in any view.
  double scale = std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff());
  for (int k = 1; k < degree; ++k) scale = std::max(scale, point(k).cwiseAbs().maxCoeff());
  const double tolerance = 1e-12 * std::max(scale, 1e-300);
  bool straight = length2 > 0;
  for (int k = 1; straight && k < degree; ++k) {
    const Eigen::RowVector2d d = point(k) - a;
    const double along = d.dot(ab) / length2;                   // the projection, in [0, 1] on the segment
    const double off = std::abs(d.x() * ab.y() - d.y() * ab.x()) / std::sqrt(length2);  // the distance to its line
    straight = off <= tolerance && along * std::sqrt(length2) >= -tolerance &&
               (along - 1) * std::sqrt(length2) <= tolerance;
  }
  if (straight) {
    Eigen::MatrixX2d line(2, 2);
    line << a, b;
    return line;
  }
  Eigen::MatrixX2d line(samples, 2);
  double values[32], derivatives[32];
  for (int s = 0; s < samples; ++s) {
    bernstein_values_and_derivatives(degree, double(s) / (samples - 1), values, derivatives);
    Eigen::RowVector2d weighted = Eigen::RowVector2d::Zero();
    double weight = 0;
    for (int k = 0; k <= degree; ++k) {
      const double wb = values[k] * g.weights[first + k * stride];
      weighted += wb * point(k);
      weight += wb;
    }
    line.row(s) = weighted / weight;
  }
  return line;
}

}  // namespace

KnotLines knot_lines_of_cells(const BezierMesh& mesh, const GeometryMap& geometry, int samples) {
  // Each cell draws its bottom and left sides, and its top and right ones on the boundary,
  // from its exact Bezier form (an adaptive loop draws them at every step, on up to 10^5 cells:
  // evaluating the map at nine points per side was half of a THB step's output).
  const int nc = mesh.num_cells();
  std::vector<long> first_side(nc + 1, 0);
  for (int c = 0; c < nc; ++c) {
    const BezierCell& b = mesh.cell(c);
    first_side[c + 1] = first_side[c] + 2 + (b.boundary[kSideTop] >= 0) + (b.boundary[kSideRight] >= 0);
  }
  KnotLines k;
  k.lines.resize(first_side[nc]);
  k.kind.assign(first_side[nc], 2);
  k.multiplicity.assign(first_side[nc], 1);
  std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic, 256)
  for (int c = 0; c < nc; ++c) {
    try {
      const BezierGeometryCell g = geometry.bezier_cell(c);
      const int p = g.degree_u, q = g.degree_v, row = p + 1;
      long i = first_side[c];
      k.lines[i++] = draw_side(g, 0, 1, p, samples);    // bottom
      k.lines[i++] = draw_side(g, 0, row, q, samples);  // left
      const BezierCell& b = mesh.cell(c);
      if (b.boundary[kSideTop] >= 0) k.lines[i++] = draw_side(g, row * q, 1, p, samples);
      if (b.boundary[kSideRight] >= 0) k.lines[i++] = draw_side(g, p, row, q, samples);
    } catch (...) {
#pragma omp critical(knot_lines_of_cells_failure)
      if (!failure) failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
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
