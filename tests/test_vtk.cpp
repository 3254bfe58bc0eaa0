#include <catch2/catch.hpp>
#include <vtkBezierQuadrilateral.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkGenericCell.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "families/tensor/tensor_case.hpp"
#include "studies/pipeline.hpp"
#include "cases/case_file.hpp"
#include "solver/error_norms.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/vtk_output.hpp"

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
  for (int p : {2, 3}) {
    Solved r = solve_shipped("quarter_annulus", p, 3);
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
