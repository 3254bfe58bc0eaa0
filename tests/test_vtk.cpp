#include <catch2/catch.hpp>
#include <vtkBezierQuadrilateral.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkGenericCell.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <array>
#include <cmath>
#include <limits>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "families/tensor/tensor_case.hpp"
#include "studies/pipeline.hpp"
#include "studies/studies.hpp"
#include "cases/case_file.hpp"
#include "solver/error_norms.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/vtk_output.hpp"
#include "basis/core/bezier_ops.hpp"
#include <Eigen/Geometry>

using namespace knotwork;
namespace fs = std::filesystem;

namespace {

struct Solved {
  CaseDescription c;
  std::unique_ptr<SplineSpace> d;
  PoissonSolution s;
};

Solved solve_shipped(const std::string& name, int p, int n, bool rational = true) {
  Solved r;
  r.c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
  patch_space(r.c).degree = {p, p};
  patch_space(r.c).elements_per_span = {n, n};
  patch_space(r.c).rational = rational;
  r.d = build_space(r.c);
  r.s = solve_poisson(r.d->mesh(), r.d->geometry(), r.c.problem, PoissonSolveOptions{});
  return r;
}

vtkSmartPointer<vtkUnstructuredGrid> read(const std::string& path) {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  return reader->GetOutput();
}

std::string temp_dir() {
  char tmpl[] = "/tmp/knotwork-test-vtk-XXXXXX";
  return mkdtemp(tmpl);
}

}  // namespace

TEST_CASE("Bezier .vtu round trip: cell types, degrees, active attributes, exact values", "[vtk]") {
  const std::string dir = temp_dir();
  // The quarter annulus is rational (the solution interpolated at each cell's nodes); the
  // L-shape polynomial (the solution's Bezier coefficients written as they are).
  for (const char* name : {"quarter_annulus", "lshape"})
  for (int p : {2, 3}) {
    INFO(name << ", p = " << p);
    Solved r = solve_shipped(name, p, 3);
    const std::string path = dir + "/bezier.vtu";
    write_bezier_vtu(path, r.d->mesh(), r.d->geometry(), r.s.coefficients, &*r.c.problem.exact);
    {  // ParaView 5.11 uses the arrays only if they are the active attributes in the header.
      std::ifstream in(path);
      std::string head(4096, '\0');
      in.read(head.data(), head.size());
      REQUIRE(head.find("RationalWeights=\"RationalWeights\"") != std::string::npos);
      REQUIRE(head.find("HigherOrderDegrees=\"HigherOrderDegrees\"") != std::string::npos);
    }
    auto grid = read(path);
    REQUIRE(grid->GetNumberOfCells() == r.d->mesh().num_cells());
    REQUIRE(grid->GetPointData()->GetRationalWeights() != nullptr);
    vtkDataArray* deg = grid->GetCellData()->GetHigherOrderDegrees();
    REQUIRE(deg != nullptr);
    vtkDataArray* sol = grid->GetPointData()->GetArray("solution");
    vtkDataArray* err = grid->GetPointData()->GetArray("error");
    REQUIRE(sol != nullptr);
    REQUIRE(err != nullptr);
    vtkNew<vtkGenericCell> cell;
    for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
      REQUIRE(grid->GetCellType(c) == VTK_BEZIER_QUADRILATERAL);
      REQUIRE(deg->GetComponent(c, 0) == p);
      REQUIRE(deg->GetComponent(c, 1) == p);
      // Evaluate the cell with VTK's own rational Bezier interpolation and compare with
      // the geometry and the discrete solution at the same reference points.
      grid->GetCell(c, cell);
      Eigen::VectorXd u(3), v(3);
      u << 0.0, 0.37, 1.0;
      v << 0.0, 0.81, 0.5;
      GeometryAtPoints at;
      r.d->geometry().evaluate(static_cast<int>(c), u, v, at);
      const Eigen::MatrixX3d uh = evaluate_solution(r.d->mesh(), r.d->geometry(), r.s.coefficients, static_cast<int>(c), u, v);
      for (int k = 0; k < 3; ++k) {
        double pc[3] = {u[k], v[k], 0}, x[3], w[64];
        int sub = 0;
        cell->EvaluateLocation(sub, pc, x, w);
        REQUIRE(std::abs(x[0] - at.x(k, 0)) < 1e-13);
        REQUIRE(std::abs(x[1] - at.x(k, 1)) < 1e-13);
        double value = 0;
        for (vtkIdType i = 0; i < cell->GetNumberOfPoints(); ++i) value += w[i] * sol->GetTuple1(cell->GetPointId(i));
        REQUIRE(std::abs(value - uh(k, 0)) < 1e-12);
        if (k == 0) {  // (0, 0) is a node of the cell: there the "exact" field is u itself
          ExpressionEvaluator u_exact(r.c.problem.exact->u);
          double exact_value = 0;
          for (vtkIdType i = 0; i < cell->GetNumberOfPoints(); ++i)
            exact_value += w[i] * grid->GetPointData()->GetArray("exact")->GetTuple1(cell->GetPointId(i));
          // Interpolation at the nodes and VTK's evaluation there: a few dozen roundings of
          // values of size |u| (the tensor Bernstein interpolation inverse of p <= 3 has inf-norm 32).
          const double u0 = u_exact(at.x(0, 0), at.x(0, 1));
          REQUIRE(std::abs(exact_value - u0) < 1e3 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(u0)));
        }
      }
    }
  }
  fs::remove_all(dir);
}

TEST_CASE("Sampled .vtu round trip and .pvd collection", "[vtk]") {
  const std::string dir = temp_dir();
  Solved r = solve_shipped("square_sinsin", 2, 4);
  write_sampled_vtu(dir + "/s.vtu", r.d->mesh(), r.d->geometry(), r.s.coefficients, &*r.c.problem.exact, 3);
  auto grid = read(dir + "/s.vtu");
  REQUIRE(grid->GetNumberOfCells() == 16 * 9);
  REQUIRE(grid->GetCellType(0) == VTK_QUAD);
  vtkDataArray* ex = grid->GetPointData()->GetArray("exact");
  REQUIRE(ex != nullptr);
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); i += 7) {
    double x[3];
    grid->GetPoint(i, x);
    REQUIRE(std::abs(ex->GetTuple1(i) - std::sin(M_PI * x[0]) * std::sin(M_PI * x[1])) < 1e-14);
  }
  write_pvd(dir + "/c.pvd", {{0, "a.vtu"}, {1, "b.vtu"}});
  std::ifstream in(dir + "/c.pvd");
  std::stringstream text;
  text << in.rdbuf();
  REQUIRE(text.str().find("type=\"Collection\"") != std::string::npos);
  REQUIRE(text.str().find("file=\"b.vtu\"") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("B-spline space on a NURBS geometry: Bezier output interpolates the solution", "[vtk]") {
  // rational = false: the solution is polynomial, the cells rational, so the Bezier fields
  // are interpolants: exact at the cell's equispaced nodes, close in between.
  const std::string dir = temp_dir();
  Solved r = solve_shipped("quarter_annulus", 2, 4, false);
  write_bezier_vtu(dir + "/b.vtu", r.d->mesh(), r.d->geometry(), r.s.coefficients, &*r.c.problem.exact);
  auto grid = read(dir + "/b.vtu");
  vtkDataArray* sol = grid->GetPointData()->GetArray("solution");
  vtkNew<vtkGenericCell> cell;
  grid->GetCell(5, cell);
  Eigen::VectorXd u(1), v(1);
  u << 0.5;
  v << 0.5;
  const Eigen::MatrixX3d uh = evaluate_solution(r.d->mesh(), r.d->geometry(), r.s.coefficients, 5, u, v);
  double pc[3] = {0.5, 0.5, 0}, x[3], w[64];
  int sub = 0;
  cell->EvaluateLocation(sub, pc, x, w);
  double value = 0;
  for (vtkIdType i = 0; i < cell->GetNumberOfPoints(); ++i) value += w[i] * sol->GetTuple1(cell->GetPointId(i));
  REQUIRE(std::abs(value - uh(0, 0)) < 1e-12);  // (1/2, 1/2) is one of the nodes
  fs::remove_all(dir);
}

TEST_CASE("Multipatch output: each cell's patch as cell data, the interfaces as lines, and none on one patch", "[vtk][multipatch]") {
  const std::string dir = temp_dir();
  // cases/geometries/lshape_3patches: patch 0 is [-1,0]x[-1,0], 1 is [-1,0]x[0,1], 2 is [0,1]^2;
  // the interfaces are y = 0 for -1 <= x <= 0, and x = 0 for 0 <= y <= 1.
  const CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/multipatch_lshape.toml");
  const RunOutcome r = run_study(c, Ordering::kAmd, &dir, {});
  const double x0[3] = {-1, -1, 0}, y0[3] = {-1, 0, 0};
  for (const char* name : {"solution.vtu", "solution_sampled.vtu"}) {
    INFO(name);
    auto grid = read(dir + "/" + name);
    vtkDataArray* patch = grid->GetCellData()->GetArray("patch");
    REQUIRE(patch != nullptr);
    std::array<int, 3> count{0, 0, 0};
    for (vtkIdType k = 0; k < grid->GetNumberOfCells(); ++k) {
      const int p = static_cast<int>(patch->GetTuple1(k));
      REQUIRE((p >= 0 && p < 3));
      ++count[p];
      // The cell's corners (the first four points of a Bezier or linear quad) lie in its patch.
      // They are grid points k/16 of unit squares (4 elements, 4 samples), exact in binary: 1e-14
      // only absorbs the geometry's evaluation.
      vtkIdType n;
      const vtkIdType* ids;
      grid->GetCellPoints(k, n, ids);
      for (int corner = 0; corner < 4; ++corner) {
        double x[3];
        grid->GetPoint(ids[corner], x);
        REQUIRE(x[0] >= x0[p] - 1e-14);
        REQUIRE(x[0] <= x0[p] + 1 + 1e-14);
        REQUIRE(x[1] >= y0[p] - 1e-14);
        REQUIRE(x[1] <= y0[p] + 1 + 1e-14);
      }
    }
    CHECK(count[0] == count[1]);
    CHECK(count[1] == count[2]);
  }
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName((dir + "/interfaces.vtp").c_str());
  reader->Update();
  vtkPolyData* lines = reader->GetOutput();
  REQUIRE(lines->GetNumberOfCells() == 2);
  vtkDataArray* number = lines->GetCellData()->GetArray("interface");
  REQUIRE(number != nullptr);
  for (vtkIdType k = 0; k < 2; ++k) {
    CHECK(number->GetTuple1(k) == k + 1);
    vtkIdType n;
    const vtkIdType* ids;
    lines->GetCellPoints(k, n, ids);
    REQUIRE(n >= 2);
    double a[3], b[3];
    lines->GetPoint(ids[0], a);
    lines->GetPoint(ids[n - 1], b);
    const bool horizontal = std::abs(a[1]) < 1e-14 && std::abs(b[1]) < 1e-14;
    const bool vertical = std::abs(a[0]) < 1e-14 && std::abs(b[0]) < 1e-14;
    CHECK(horizontal != vertical);
    CHECK(std::hypot(a[0] - b[0], a[1] - b[1]) == Approx(1).epsilon(1e-14));
    for (vtkIdType i = 0; i < n; ++i) {
      double x[3];
      lines->GetPoint(ids[i], x);
      CHECK(std::abs(horizontal ? x[1] : x[0]) < 1e-14);
    }
  }
  fs::remove_all(dir);
  // One patch: no patch array and no interfaces file.
  const std::string one = temp_dir();
  run_study(load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/square_sinsin.toml"), Ordering::kAmd, &one, {});
  CHECK(read(one + "/solution.vtu")->GetCellData()->GetArray("patch") == nullptr);
  CHECK(!fs::exists(one + "/interfaces.vtp"));
  fs::remove_all(one);
}

namespace {

// A volume case solved through the pipeline (cases/README.md: [geometry] type = "box" or
// "thick_quarter_annulus").
Solved solve_volume(const std::string& geometry, int p, int n, bool rational) {
  Solved r;
  r.c = load_case_text("[geometry]\ntype = \"" + geometry + "\"\n[space]\ndegree = " + std::to_string(p) +
                           "\nelements = " + std::to_string(n) + "\nrational = " + (rational ? "true" : "false") +
                           "\n[problem]\nexact = \"sin(x) * exp(y / 2) * (1 + z * z / 3)\"\n",
                       "volume.toml");
  r.d = build_space(r.c);
  r.s = solve_poisson(r.d->mesh(), r.d->geometry(), r.c.problem, PoissonSolveOptions{});
  return r;
}

// The inf-norm of the univariate Bernstein interpolation inverse at p + 1 equispaced nodes.
double interpolation_norm(int p) {
  return bernstein_interpolation_inverse(p, 0).cwiseAbs().rowwise().sum().maxCoeff();
}

}  // namespace

TEST_CASE("Bezier hexahedra (VTK type 79) read back by VTK evaluate to the geometry and the solution", "[vtk][volume]") {
  // Through VTK's own rational Bezier hexahedron (its node order, its weights): the box and a
  // B-spline solution (the solution's own Bezier coefficients), the thick quarter annulus with
  // the isoparametric NURBS space (the solution is a rational Bezier function of the cell's
  // weights: exact everywhere) and with B-splines on it (an interpolant: exact at the nodes).
  // Rounding: the interpolation multiplies the values' rounding by at most the product of the
  // univariate inverses' norms, and VTK's sum over the (p+1)^3 nodes adds one rounding per term.
  const std::string dir = temp_dir();
  constexpr double eps = std::numeric_limits<double>::epsilon();
  struct Variant {
    const char* geometry;
    bool rational, exact_inside;
  };
  for (const Variant& variant : {Variant{"box", false, true}, Variant{"thick_quarter_annulus", true, true},
                                 Variant{"thick_quarter_annulus", false, false}}) {
    const int p = 2;
    INFO(variant.geometry << ", rational = " << variant.rational);
    Solved r = solve_volume(variant.geometry, p, 2, variant.rational);
    const std::string path = dir + "/hexahedra.vtu";
    write_bezier_vtu(path, r.d->mesh(), r.d->geometry(), r.s.coefficients, &*r.c.problem.exact);
    auto grid = read(path);
    REQUIRE(grid->GetNumberOfCells() == r.d->mesh().num_cells());
    vtkDataArray* deg = grid->GetCellData()->GetHigherOrderDegrees();
    vtkDataArray* sol = grid->GetPointData()->GetArray("solution");
    REQUIRE(deg != nullptr);
    REQUIRE(sol != nullptr);
    REQUIRE(grid->GetPointData()->GetRationalWeights() != nullptr);
    vtkNew<vtkGenericCell> cell;
    // Nodes of the degree-2 cells (corners, an edge's middle, the centre) and points between.
    Eigen::VectorXd u(6), v(6), w(6);
    u << 0, 1, 0.5, 0.5, 0.13, 0.71;
    v << 0, 1, 0, 0.5, 0.62, 0.29;
    w << 0, 1, 1, 0.5, 0.35, 0.93;
    const int points = variant.exact_inside ? 6 : 4;
    const double bound = 4 * 27 * std::pow(interpolation_norm(p), 3) * eps;
    for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
      REQUIRE(grid->GetCellType(c) == VTK_BEZIER_HEXAHEDRON);
      for (int d = 0; d < 3; ++d) REQUIRE(deg->GetComponent(c, d) == p);
      grid->GetCell(c, cell);
      GeometryAtPoints at;
      r.d->geometry().evaluate_volume(static_cast<int>(c), u, v, w, at);
      const Eigen::MatrixXd uh = evaluate_volume_solution(r.d->mesh(), r.d->geometry(), r.s.coefficients, static_cast<int>(c), u, v, w);
      const double scale_x = at.x.cwiseAbs().maxCoeff(), scale_u = std::max(1.0, uh.col(0).cwiseAbs().maxCoeff());
      for (int k = 0; k < points; ++k) {
        double pc[3] = {u[k], v[k], w[k]}, x[3], weights[64];
        int sub = 0;
        cell->EvaluateLocation(sub, pc, x, weights);
        for (int d = 0; d < 3; ++d) REQUIRE(std::abs(x[d] - at.x(k, d)) <= bound * scale_x);
        double value = 0;
        for (vtkIdType i = 0; i < cell->GetNumberOfPoints(); ++i) value += weights[i] * sol->GetTuple1(cell->GetPointId(i));
        REQUIRE(std::abs(value - uh(k, 0)) <= bound * scale_u);
      }
    }
  }
  // The sampled fallback: s^3 linear hexahedra per cell, with the exact solution at each point.
  Solved r = solve_volume("thick_quarter_annulus", 2, 2, true);
  write_sampled_vtu(dir + "/sampled.vtu", r.d->mesh(), r.d->geometry(), r.s.coefficients, &*r.c.problem.exact, 3);
  auto grid = read(dir + "/sampled.vtu");
  REQUIRE(grid->GetNumberOfCells() == r.d->mesh().num_cells() * 27);
  REQUIRE(grid->GetCellType(0) == VTK_HEXAHEDRON);
  vtkDataArray* ex = grid->GetPointData()->GetArray("exact");
  REQUIRE(ex != nullptr);
  // (The file's values come from the vectorized evaluator, libmvec's sin and exp within 4 ulp
  // each: a few dozen ulps of the value apart from the scalar one's at most.)
  ExpressionEvaluator exact(r.c.problem.exact->u);
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); i += 7) {
    double x[3];
    grid->GetPoint(i, x);
    const double value = exact(x[0], x[1], x[2]);
    REQUIRE(std::abs(ex->GetTuple1(i) - value) <= 64 * eps * std::abs(value));
  }
  // Every linear hexahedron is positively oriented (VTK's corner order): its volume is > 0.
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); c += 5) {
    double corner[8][3];
    vtkCell* hexahedron = grid->GetCell(c);
    for (int k = 0; k < 8; ++k) grid->GetPoint(hexahedron->GetPointId(k), corner[k]);
    const Eigen::Vector3d a(corner[1][0] - corner[0][0], corner[1][1] - corner[0][1], corner[1][2] - corner[0][2]);
    const Eigen::Vector3d b(corner[3][0] - corner[0][0], corner[3][1] - corner[0][1], corner[3][2] - corner[0][2]);
    const Eigen::Vector3d h(corner[4][0] - corner[0][0], corner[4][1] - corner[0][1], corner[4][2] - corner[0][2]);
    REQUIRE(a.cross(b).dot(h) > 0);
  }
  fs::remove_all(dir);
}
