// Family "pt": PT-splines over a T-mesh of the geometry's parameter domain, as a BezierMesh.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <stdexcept>

#include "app/discretize.hpp"
#include "basis/pt_bezier_mesh.hpp"
#include "solver/input_error.hpp"

namespace knotwork {

namespace {

// The geometry's breakpoints, exactly (doubles are dyadic rationals), and which interior
// ones are C0 (multiplicity >= degree): the space must only be C0 there.
struct GeometryLines {
  std::vector<mpq_class> breaks[2];
  C0Lines c0;
};

GeometryLines geometry_lines(const NurbsPatch& g) {
  GeometryLines out;
  for (int d = 0; d < 2; ++d) {
    const BSplineBasis1D& b = d == 0 ? g.basis_u : g.basis_v;
    const auto bp = b.breakpoints();
    const auto mult = b.multiplicities();
    for (size_t i = 0; i < bp.size(); ++i) {
      out.breaks[d].push_back(mpq_class(bp[i]));
      if (i > 0 && i + 1 < bp.size() && mult[i] >= b.degree()) (d == 0 ? out.c0.x : out.c0.y).push_back(mpq_class(bp[i]));
    }
  }
  return out;
}

// Short decimal when it is exact (0.5), else the fraction (1/3).
std::string text(const mpq_class& q) {
  char b[40];
  std::snprintf(b, sizeof b, "%.12g", q.get_d());
  return mpq_class(std::stod(b)) == q ? std::string(b) : q.get_str();
}

}  // namespace

std::vector<RationalBox> pt_start_cells(const CaseDescription& c) {
  const GeometryLines lines = geometry_lines(c.geometry);
  std::vector<RationalBox> start = c.pt.cells;
  const std::string where = c.path + ": [space] " + (c.pt.tmesh_file.empty() ? "cells" : "tmesh: " + c.pt.tmesh_file);
  if (start.empty()) {
    for (size_t j = 0; j + 1 < lines.breaks[1].size(); ++j)
      for (size_t i = 0; i + 1 < lines.breaks[0].size(); ++i)
        start.push_back({lines.breaks[0][i], lines.breaks[1][j], lines.breaks[0][i + 1], lines.breaks[1][j + 1]});
  } else {
    mpq_class X0 = start[0].x0, Y0 = start[0].y0, X1 = start[0].x1, Y1 = start[0].y1;
    for (const auto& b : start) {
      X0 = std::min(X0, b.x0), Y0 = std::min(Y0, b.y0);
      X1 = std::max(X1, b.x1), Y1 = std::max(Y1, b.y1);
    }
    if (X0 != lines.breaks[0].front() || X1 != lines.breaks[0].back() || Y0 != lines.breaks[1].front() ||
        Y1 != lines.breaks[1].back())
      throw InputError(where + ": the cells cover [" + text(X0) + ", " + text(X1) + "] x [" + text(Y0) + ", " + text(Y1) +
                       "], not the geometry's parameter domain [" + text(lines.breaks[0].front()) + ", " +
                       text(lines.breaks[0].back()) + "] x [" + text(lines.breaks[1].front()) + ", " +
                       text(lines.breaks[1].back()) + "]");
  }
  const int ex = c.space.elements_per_span[0], ey = c.space.elements_per_span[1];
  // The T-mesh checks compare every pair of cells and the basis is built in exact
  // arithmetic: 4096 cells take 2.3 s, so 20000 would take minutes and more far longer.
  if (static_cast<double>(start.size()) * ex * ey > 20000)
    throw InputError(c.path + ": [space] elements: " + std::to_string(static_cast<long>(start.size()) * ex * ey) +
                     " cells, more than the 20000 a PT-spline space is built for here");
  std::vector<RationalBox> cells;
  for (const auto& b : start)
    for (int j = 0; j < ey; ++j)
      for (int i = 0; i < ex; ++i)
        cells.push_back({b.x0 + (b.x1 - b.x0) * i / ex, b.y0 + (b.y1 - b.y0) * j / ey, b.x0 + (b.x1 - b.x0) * (i + 1) / ex,
                         b.y0 + (b.y1 - b.y0) * (j + 1) / ey});
  for (auto& b : cells)
    for (mpq_class* v : {&b.x0, &b.y0, &b.x1, &b.y1}) v->canonicalize();
  try {
    cells = insert_segments(std::move(cells), c.pt.segments);
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": [space] segments: " + e.what());
  }
  // A cell must not straddle a knot line of the geometry: the map is one polynomial per cell.
  for (const auto& b : cells)
    for (int d = 0; d < 2; ++d)
      for (const mpq_class& t : lines.breaks[d])
        if ((d == 0 ? b.x0 : b.y0) < t && t < (d == 0 ? b.x1 : b.y1))
          throw InputError(where + ": the cell [" + text(b.x0) + ", " + text(b.y0) + ", " + text(b.x1) + ", " + text(b.y1) +
                           "] straddles the geometry's knot line " + (d == 0 ? "u = " : "v = ") + text(t) +
                           "; split it there");
  return cells;
}

Discretization discretize_pt(const CaseDescription& c, const std::vector<RationalBox>& cells) {
  Discretization d;
  const GeometryLines lines = geometry_lines(c.geometry);
  try {
    d.tmesh = std::make_unique<RectangularPartition>(cells);
    d.pt = std::make_unique<PtSplineBasis>(
        pt_spline_basis(*d.tmesh, c.space.degree[0], c.space.degree[1], c.pt.extension, lines.c0));
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": [space]: " + e.what());
  }
  make_boundary_traces_independent(*d.pt, *d.tmesh);
  make_numerically_independent(*d.pt, *d.tmesh);
  // Exact Bernstein coefficients, rounded once: assembly sees functions that are C^(m-1) to
  // the last bit, whatever the T-mesh.
  d.local_mesh = std::make_unique<BezierMesh>(
      pt_bezier_mesh(*d.tmesh, to_double(pt_cell_polynomials_exact(*d.pt, *d.tmesh)), d.pt->m, d.pt->n));
  d.pt->bernstein.reset();  // the exact factors are large on big meshes and not needed again
  d.geometry = std::make_unique<PatchGeometryMap>(*d.local_mesh, c.geometry);
  return d;
}

}  // namespace knotwork
