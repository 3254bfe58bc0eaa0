// Family "pt": PT-splines over a T-mesh of the geometry's parameter domain, as a BezierMesh;
// refined locally by halving marked cells of the T-mesh and building the space anew.
#include <algorithm>
#include <cmath>
#include <cstdio>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <optional>
#include <stdexcept>
#include <string>

#include "basis/pt/pt_bezier_mesh.hpp"
#include "families/pt/pt_case.hpp"
#include "families/pt/pt_space.hpp"
#include "basis/pt/pt_spline.hpp"
#include "basis/tmesh/knot_polylines.hpp"
#include "cases/resource_limits.hpp"
#include "cases/basis_tool.hpp"
#include "cases/spline_space.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

std::unique_ptr<BasisTool> pt_basis_tool(CLI::App& basis);  // pt_basis_tool.cpp

namespace {

// The basis is built in exact arithmetic: on the adaptive L-shape at degree 3 (2026-12-03,
// docs/records/performance-2026-11-22-to-12-04.md) T-meshes of 57 557 to 118 210 cells took 22-51 s each, the larger
// times when the first insertion orders fall short and a lengthened one is needed; 120000
// cells keep a build near a minute.
constexpr int kMaxPtCells = 120000;

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

std::vector<RationalBox> pt_start_cells(const CaseDescription& c, int level) {
  const PtSection& pt = pt_section(c);
  const GeometryLines lines = geometry_lines(c.geometry);
  std::vector<RationalBox> start = pt.cells;
  const std::string where = c.path + ": [space] " + (pt.tmesh_file.empty() ? "cells" : "tmesh: " + pt.tmesh_file);
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
  const int ex = pt.space.elements_per_span[0] << level, ey = pt.space.elements_per_span[1] << level;
  if (static_cast<double>(start.size()) * ex * ey > kMaxPtCells)
    throw InputError(c.path + ": [space] elements: " + std::to_string(static_cast<long>(start.size()) * ex * ey) +
                     " cells, more than the " + std::to_string(kMaxPtCells) + " a PT-spline space is built for here");
  std::vector<RationalBox> cells;
  for (const auto& b : start)
    for (int j = 0; j < ey; ++j)
      for (int i = 0; i < ex; ++i)
        cells.push_back({b.x0 + (b.x1 - b.x0) * i / ex, b.y0 + (b.y1 - b.y0) * j / ey, b.x0 + (b.x1 - b.x0) * (i + 1) / ex,
                         b.y0 + (b.y1 - b.y0) * (j + 1) / ey});
  for (auto& b : cells)
    for (mpq_class* v : {&b.x0, &b.y0, &b.x1, &b.y1}) v->canonicalize();
  try {
    cells = insert_segments(std::move(cells), pt.segments);
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

namespace {

// A peak of 0.92 GB for the whole adaptive run to 111 972 functions (p = 3, L-shape, 118 210
// cells at the end, 2026-12-03): 7.8 kB per cell, reached inside the last build (the
// solve after it peaked at 0.69 GB); 12 kB per cell plus the Galerkin part stays on the safe side.
void check_pt_memory(const CaseDescription& c, size_t cells) {
  const auto [m, n] = pt_section(c).space.degree;
  const double bytes = 12e3 * double(cells) + galerkin_bytes(double(cells), double(cells) + (m + 1) * (n + 1), m, n);
  check_memory(c.path + ": [space]", bytes, std::to_string(cells) + " T-mesh cells of PT-splines");
}

class PtSpace final : public SplineSpace, public SpaceReport {
 public:
  const SpaceReport& presentation() const override { return *this; }
  // PT-splines on the given T-mesh of the case's parameter domain, ready to solve: the
  // geometry's C0 knot lines are C0 lines of the space. Throws InputError naming the case.
  // The exact basis and T-mesh are built, turned into the mesh and dropped: the space keeps
  // the mesh, the cells and the facts it reports. (Kept, they were held through every solve:
  // dropping them lowered the adaptive run's peak to 15 000 dofs from 189 to 179 MB.)
  PtSpace(const CaseDescription& c, std::vector<RationalBox> cells, int elements, const ProgressFunction& progress = {})
      : case_(std::make_shared<const CaseDescription>(c)), elements_(elements) {
    check_pt_memory(c, cells.size());
    // Exact arithmetic throughout: minutes on the largest meshes, so each stage says so.
    auto say = [&](const std::string& s) {
      if (progress) progress("PT-splines: " + s);
    };
    say("extension and local B-splines on " + std::to_string(cells.size()) + " cells (exact)");
    const PtSection& pt = pt_section(c);
    const GeometryLines lines = geometry_lines(c.geometry);
    std::optional<RectangularPartition> tmesh;
    std::optional<PtSplineBasis> basis;
    try {
      tmesh.emplace(std::move(cells));
      basis.emplace(pt_spline_basis(*tmesh, pt.space.degree[0], pt.space.degree[1], pt.extension, lines.c0));
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": [space]: " + e.what());
    }
    say("independence of " + std::to_string(basis->functions.size()) + " functions (exact rank)");
    make_boundary_traces_independent(*basis, *tmesh);
    make_numerically_independent(*basis, *tmesh);
    say("Bezier extraction (exact, rounded once)");
    // Exact Bernstein coefficients, rounded once: assembly sees functions that are C^(m-1) to
    // the last bit, whatever the T-mesh.
    mesh_ = pt_bezier_mesh(*basis, *tmesh);
    m_ = basis->m, n_ = basis->n;
    c0_ = basis->c0;
    extension_ = basis->extension;
    minimal_refused_ = basis->minimal_refused;
    basis.reset();
    cells_ = std::move(*tmesh).take_cells();
    tmesh.reset();
    mesh_.set_interfaces(interfaces_from_parameter_boxes(mesh_));
    geometry_ = std::make_unique<PatchGeometryMap>(mesh_, c.geometry);
#ifdef __GLIBC__
    // Millions of short-lived exact numbers leave the heap's free pages scattered among the
    // ones kept; giving them back lowered the adaptive run's peak to 15 000 dofs from 212 to
    // 189 MB (2026-12-03).
    malloc_trim(0);
#endif
  }
  const BezierMesh& mesh() const override { return mesh_; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::string description() const override {
    const PtSection& pt = pt_section(*case_);
    std::string start = !pt.tmesh_file.empty() ? "T-mesh " + pt.tmesh_file
                        : !pt.cells.empty()    ? std::to_string(pt.cells.size()) + " given cells"
                                                 : "tensor start";
    if (!pt.segments.empty()) start += " + " + std::to_string(pt.segments.size()) + " segments";
    return "PT-splines, degree " + std::to_string(pt.space.degree[0]) + "x" + std::to_string(pt.space.degree[1]) + ", " +
           start + ", extension " + pt_extension_name(pt.extension);
  }
  std::vector<int> degree() const override { return {m_, n_}; }
  std::vector<ReportField> report() const override {
    return {{.key = "elements", .value = long(elements_), .column = true, .width = 9},
            {.key = "extension_used", .value = std::string(pt_extension_name(extension_))}};
  }
  // The minimal extension was refused and a full one used: never silently.
  std::vector<std::string> notes() const override {
    if (minimal_refused_.empty()) return {};
    return {"the minimal PT extension was refused (" + minimal_refused_ + "); the " + pt_extension_name(extension_) +
            " full extension is used instead (less local)"};
  }
  std::unique_ptr<SplineSpace> refine(const std::vector<int>& marked, const std::vector<CellSplit>& split,
                                      int* extended, const ProgressFunction& progress) && override {
    // The BezierMesh cells are the T-mesh cells, in order: halve the marked ones.
    std::vector<RationalBox> cells = std::move(cells_);
    for (size_t k = 0; k < marked.size(); ++k) {
      RationalBox& a = cells[marked[k]];
      RationalBox b = a;
      if (split[k] == CellSplit::kAcrossU) a.x1 = b.x0 = (a.x0 + a.x1) / 2;
      else a.y1 = b.y0 = (a.y0 + a.y1) / 2;
      cells.push_back(b);
    }
    if (extended) *extended = 0;
    // This space is consumed: its mesh goes before the next one is built (on the adaptive
    // L-shape the extraction is 2.1 kB per bicubic cell, about 1.2 kB once pooled).
    geometry_.reset();
    mesh_ = BezierMesh();
    return std::make_unique<PtSpace>(*case_, std::move(cells), elements_, progress);
  }
  // PT-spline knots are simple, except along the C0 lines.
  KnotLines knot_lines() const override {
    const RectangularPartition tmesh(cells_);
    KnotPolylines k = knot_polylines(tmesh, case_->geometry, [&](bool vertical, double at, double, double) {
      for (const auto& t : vertical ? c0_.x : c0_.y)
        if (t.get_d() == at) return vertical ? m_ : n_;
      return 1;
    });
    return {std::move(k.lines), std::move(k.kind), std::move(k.multiplicity)};
  }

  const C0Lines& c0() const { return c0_; }
  const std::vector<RationalBox>& cells() const { return cells_; }

 private:
  std::shared_ptr<const CaseDescription> case_;  // a copy: the space does not need the caller's case to live on
  int elements_;
  int m_ = 0, n_ = 0;
  C0Lines c0_;
  PtExtension extension_ = PtExtension::kHorizontal;
  std::string minimal_refused_;
  std::vector<RationalBox> cells_;  // the T-mesh's, in the mesh's cell order
  BezierMesh mesh_;
  std::unique_ptr<PatchGeometryMap> geometry_;
};

}  // namespace

const C0Lines* pt_c0_lines_of(const SplineSpace& space) {
  const auto* pt = dynamic_cast<const PtSpace*>(&space);
  return pt ? &pt->c0() : nullptr;
}

const std::vector<RationalBox>* pt_cells_of(const SplineSpace& space) {
  const auto* pt = dynamic_cast<const PtSpace*>(&space);
  return pt ? &pt->cells() : nullptr;
}

SpaceFamily pt_family() {
  SpaceFamily f;
  f.name = "pt";
  f.read_case = read_pt_case;
  f.space_keys = pt_space_keys();
  f.add_basis_tool = pt_basis_tool;
  f.build = [](const CaseDescription& c, int level, const ProgressFunction& progress) -> std::unique_ptr<SplineSpace> {
    return std::make_unique<PtSpace>(c, pt_start_cells(c, level), pt_section(c).space.elements_per_span[0] << level,
                                     progress);
  };
  f.local_refinement = true;
  f.override_options = [](CaseDescription& c, int degree, int elements) {
    override_patch_space(pt_section(c).space, degree, elements);
  };
  f.check_converge = [](const CaseDescription& c, int levels) {
    check_uniform_levels(pt_section(c).space, levels);
    // Each level quadruples the cells: refuse a study whose finest level cannot be built.
    const double finest = double(pt_start_cells(c, 0).size()) * std::pow(4.0, levels - 1);
    if (finest > kMaxPtCells)
      throw InputError("--levels: the finest level would have " + std::to_string(static_cast<long>(finest)) +
                       " T-mesh cells, more than the " + std::to_string(kMaxPtCells) +
                       " a PT-spline space is built for here");
    check_pt_memory(c, static_cast<size_t>(finest));
  };
  return f;
}

}  // namespace knotwork
