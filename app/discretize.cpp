#include "app/discretize.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "cases/geometries.hpp"
#include "solver/input_error.hpp"

namespace knotwork {

namespace {

// Refuses discretizations that cannot fit in memory before allocating anything: cell
// function lists, the matrix (lower triangle, one copy per thread during assembly) and the
// Cholesky factor, estimated as nnz(A) * log2(n) entries (measured with AMD on 2D IGA
// matrices: 0.73-0.75 * log2(n), docs/PERFORMANCE.md; the estimate keeps a margin).
void check_memory(const CaseDescription& c) {
  const auto& s = c.space;
  double cells = 1, functions = 1;
  for (int d = 0; d < 2; ++d) {
    const BSplineBasis1D& g = d == 0 ? c.geometry.basis_u : c.geometry.basis_v;
    const double elements = double(g.num_elements()) * s.elements_per_span[d] + s.extra_knots[d].size();
    cells *= elements;
    functions *= elements + s.degree[d];
  }
  const double per_cell = double(s.degree[0] + 1) * (s.degree[1] + 1);
  const double coupling = double(2 * s.degree[0] + 1) * (2 * s.degree[1] + 1) / 2;
  const double nnz = functions * coupling;
  const double factor = nnz * std::max(1.0, std::log2(functions));
  const double bytes = cells * per_cell * 4 + nnz * 12 * 3 + factor * 8;
  const double physical = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
  if (physical > 0 && bytes > 0.9 * physical) {
    char msg[200];
    std::snprintf(msg, sizeof msg, "about %.0f GB needed for %.3g cells of degree %dx%d, more than this machine's %.0f GB",
                  bytes / 1e9, cells, s.degree[0], s.degree[1], physical / 1e9);
    throw InputError(c.path + ": [space] elements: " + msg);
  }
}

}  // namespace

namespace {

// The knot-segment space of a case: a tensor-product start on the geometry's knot spans
// (cut into `elements` parts; geometry knots of low continuity become knot lines of the
// needed multiplicity, e.g. the L-shape's C0 fold), then the listed segments.
// A collection given explicitly ([space] collection): its domain must be the geometry's
// parameter domain; semi-regularity is checked here and enforced before solving.
void discretize_explicit_collection(const CaseDescription& c, Discretization& d) {
  const std::string where = c.path + ": [space] collection: " + c.collection_file;
  try {
    d.segments = std::make_unique<SemiRegularCollection>(
        SemiRegularCollection::from_splines(c.space.degree[0], c.space.degree[1], c.collection));
  } catch (const std::invalid_argument& e) {
    throw InputError(where + ": " + e.what());
  }
  const auto box = d.segments->domain();
  const double u0 = c.geometry.basis_u.domain_begin(), u1 = c.geometry.basis_u.domain_end();
  const double v0 = c.geometry.basis_v.domain_begin(), v1 = c.geometry.basis_v.domain_end();
  if (box[0] != u0 || box[2] != u1 || box[1] != v0 || box[3] != v1) {
    char msg[240];
    std::snprintf(msg, sizeof msg, "the supports cover [%g,%g]x[%g,%g], not the geometry's parameter domain [%g,%g]x[%g,%g]",
                  box[0], box[2], box[1], box[3], u0, u1, v0, v1);
    throw InputError(where + ": " + msg);
  }
  d.simple_knots = interior_knots_simple(c.collection);
  for (const auto& v : d.segments->violations()) d.violations.push_back(v.reason);
  try {
    d.local_mesh = std::make_unique<BezierMesh>(d.segments->bezier_mesh());
  } catch (const std::runtime_error& e) {
    throw InputError(where + ": the supports do not induce a partition: " + e.what());
  }
  d.geometry = std::make_unique<PatchGeometryMap>(*d.local_mesh, c.geometry);
}

void discretize_knot_segments(const CaseDescription& c, Discretization& d) {
  if (!c.collection_file.empty()) return discretize_explicit_collection(c, d);
  const int dx = c.space.degree[0], dy = c.space.degree[1];
  std::array<std::vector<double>, 2> breaks;
  std::array<std::vector<int>, 2> mults;  // per interior breakpoint
  for (int dir = 0; dir < 2; ++dir) {
    const BSplineBasis1D& g = dir == 0 ? c.geometry.basis_u : c.geometry.basis_v;
    const int deg = dir == 0 ? dx : dy;
    const auto bp = g.breakpoints();
    const auto mult = g.multiplicities();
    for (size_t i = 0; i + 1 < bp.size(); ++i) {
      for (int e = 0; e < c.space.elements_per_span[dir]; ++e) {
        breaks[dir].push_back(bp[i] + (bp[i + 1] - bp[i]) * e / c.space.elements_per_span[dir]);
        if (breaks[dir].size() == 1) continue;
        // A geometry knot keeps min(its continuity, d-1); new knots are C^(d-1).
        const int continuity = e == 0 ? std::min(g.degree() - mult[i], deg - 1) : deg - 1;
        mults[dir].push_back(deg - continuity);
        d.simple_knots = d.simple_knots && deg - continuity == 1;
      }
    }
    breaks[dir].push_back(bp.back());
  }
  try {
    d.segments = std::make_unique<SemiRegularCollection>(
        SemiRegularCollection::tensor_product(dx, dy, breaks[0], breaks[1], mults[0], mults[1]));
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": [space]: " + e.what());
  }
  for (size_t i = 0; i < c.segments.size(); ++i) {
    try {
      d.insertions.push_back(d.segments->insert(c.segments[i]));
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": [space] segments[" + std::to_string(i) + "]: " + e.what());
    }
    d.simple_knots = d.simple_knots && c.segments[i].multiplicity == 1;
  }
  d.local_mesh = std::make_unique<BezierMesh>(d.segments->bezier_mesh());
  d.geometry = std::make_unique<PatchGeometryMap>(*d.local_mesh, c.geometry);
}

}  // namespace

Discretization discretize_collection(const CaseDescription& c, const SemiRegularCollection& collection) {
  Discretization d;
  d.segments = std::make_unique<SemiRegularCollection>(collection);
  d.local_mesh = std::make_unique<BezierMesh>(d.segments->bezier_mesh());
  d.geometry = std::make_unique<PatchGeometryMap>(*d.local_mesh, c.geometry);
  return d;
}

Discretization discretize(const CaseDescription& c) {
  if (c.family != "pt") check_memory(c);
  Discretization d;
  if (c.family == "knot_segments") {
    discretize_knot_segments(c, d);
    return d;
  }
  if (c.family == "pt") return discretize_pt(c, pt_start_cells(c));
  try {
    d.tensor = build_tensor_discretization(c.geometry, c.space);
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": [space]: " + e.what());
  }
  d.geometry = std::make_unique<NurbsGeometryMap>(d.tensor);
  return d;
}

PoissonSolution solve_case(const CaseDescription& c, const Discretization& d, Ordering ordering,
                           const std::function<void(const std::string&)>& progress) {
  if (!d.violations.empty()) {
    const std::string more =
        d.violations.size() > 1 ? " (and " + std::to_string(d.violations.size() - 1) + " more; knotwork basis lists them)" : "";
    if (!c.allow_non_semi_regular)
      throw InputError(c.path + ": [space] collection: " + c.collection_file + " is not semi-regular: " +
                       d.violations.front() + more + "; refusing to solve (--allow-non-semi-regular solves anyway)");
    std::fprintf(stderr, "knotwork: warning: %s: the collection is not semi-regular (%s%s); solving anyway as asked: "
                         "the functions may be linearly dependent and the matrix singular\n",
                 c.collection_file.c_str(), d.violations.front().c_str(), more.c_str());
  }
  PoissonSolveOptions so;
  so.quadrature = c.quadrature;
  so.ordering = ordering;
  so.progress = progress;
  try {
    return solve_poisson(d.mesh(), *d.geometry, c.problem, so);
  } catch (const GeometryError& e) {
    throw InputError(c.path + ": [geometry]: " + e.what());
  }
}

CaseDescription unit_square_benchmark_case(int p, int n) {
  CaseDescription c;
  c.path = "bench";
  c.name = "bench";
  c.geometry = rectangle_patch(0, 0, 1, 1);
  c.space.degree = {p, p};
  c.space.elements_per_span = {n, n};
  c.problem.exact = differentiate_exact_solution(Expression::parse("sin(pi*x)*sin(pi*y)", "bench"));
  c.problem.source = c.problem.exact->minus_laplacian;
  c.problem.boundary.assign(4, BoundaryCondition{});
  return c;
}

double mesh_size(const Discretization& d) {
  Eigen::VectorXd u(4), v(4);
  u << 0, 1, 1, 0;
  v << 0, 0, 1, 1;
  double h = 0;
  GeometryAtPoints g;
  for (int c = 0; c < d.mesh().num_cells(); ++c) {
    d.geometry->evaluate(c, u, v, g);
    h = std::max({h, (g.x.row(0) - g.x.row(2)).norm(), (g.x.row(1) - g.x.row(3)).norm()});
  }
  return h;
}

std::string describe_space(const CaseDescription& c) {
  const auto& s = c.space;
  if (c.family == "pt") {
    const char* ext = pt_extension_name(c.pt.extension);
    std::string start = !c.pt.tmesh_file.empty() ? "T-mesh " + c.pt.tmesh_file
                        : !c.pt.cells.empty()    ? std::to_string(c.pt.cells.size()) + " given cells"
                                                 : "tensor start";
    if (!c.pt.segments.empty()) start += " + " + std::to_string(c.pt.segments.size()) + " segments";
    return "PT-splines, degree " + std::to_string(s.degree[0]) + "x" + std::to_string(s.degree[1]) + ", " + start +
           ", extension " + ext;
  }
  if (c.family == "knot_segments" && !c.collection_file.empty())
    return "knot segments (Weller), degree " + std::to_string(s.degree[0]) + "x" + std::to_string(s.degree[1]) +
           ", collection of " + std::to_string(c.collection.size()) + " B-splines from " + c.collection_file;
  if (c.family == "knot_segments")
    return "knot segments (Weller), degree " + std::to_string(s.degree[0]) + "x" + std::to_string(s.degree[1]) +
           ", " + std::to_string(c.segments.size()) + " segments";
  const int ru = s.continuity[0] < 0 ? s.degree[0] - 1 : s.continuity[0];
  const int rv = s.continuity[1] < 0 ? s.degree[1] - 1 : s.continuity[1];
  std::string r = std::string(s.rational ? "NURBS" : "B-spline") + ", degree " +
                  std::to_string(s.degree[0]) + "x" + std::to_string(s.degree[1]) + ", C^" +
                  std::to_string(ru);
  if (rv != ru) r += "/C^" + std::to_string(rv);
  return r + " at new knots";
}

}  // namespace knotwork
