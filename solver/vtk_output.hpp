#pragma once
#include <Eigen/Core>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "solver/expression.hpp"
#include "basis/core/geometry_map.hpp"
#include "solver/poisson_problem.hpp"

namespace knotwork {

// ParaView output. Point data: "solution", and with an exact solution also "exact" and
// "error" (= solution - exact). Cell data, on a mesh of several patches: "patch" (the cell's
// patch, its position in the domain from 0).

// Exact Bezier quadrilaterals (VTK type 77): each cell's geometry control points, its
// rational weights (point data "RationalWeights") and degrees (cell data
// "HigherOrderDegrees"), both set as active attributes so ParaView 5.11 uses them.
// Fields are given as Bezier coefficients that interpolate them at the cell's
// equispaced nodes: exact for the solution whenever it lies in the cell's (rational)
// Bezier space, i.e. for isoparametric spaces; an interpolant otherwise.
// Per-cell scalar fields (e.g. an error indicator), one value per BezierMesh cell.
using CellFields = std::vector<std::pair<std::string, Eigen::VectorXd>>;

// Pieces of one output written by several processes (mpirun): each writes the cells of its
// CellRange to its own .vtu, and one of them also the .pvtu summary at `path` naming all the
// pieces (`pieces`: file names relative to the summary).
struct PieceSummary {
  std::string path;
  std::vector<std::string> pieces;
};

// Planar domains and surfaces in R^3 alike; `exact_offset` is subtracted from the exact
// solution (the mean removed by zero-mean problems). `cells`: a piece's cells only (cell
// fields still hold one value per cell of the mesh), with `summary` for the one that writes it.
void write_bezier_vtu(const std::string& path, const BezierMesh& mesh, const GeometryMap& geometry,
                      const Eigen::VectorXd& coefficients, const ExactSolution* exact,
                      const CellFields& cell_fields = {}, double exact_offset = 0, CellRange cells = {},
                      const PieceSummary* summary = nullptr);

// Polynomial Bezier quadrilaterals in R^3 given by their Bernstein coefficients (surfaces,
// or planar domains, with no geometry map behind them): per cell its degree (both
// directions), control points ((p+1)^2 rows x 3, Bernstein index a + (p+1) b) and, per named
// point field, the field's Bernstein coefficients on the cell. Exact: nothing is sampled.
struct BezierSurface {
  std::vector<int> degree;
  std::vector<Eigen::MatrixXd> points;
  std::vector<std::pair<std::string, std::vector<Eigen::VectorXd>>> point_fields;
  CellFields cell_fields;
};
void write_bezier_surface_vtu(const std::string& path, const BezierSurface& surface);

// The robust fallback: every cell cut into samples x samples linear quads with exact
// values at their corners.
void write_sampled_vtu(const std::string& path, const BezierMesh& mesh, const GeometryMap& geometry,
                       const Eigen::VectorXd& coefficients, const ExactSolution* exact, int samples,
                       double exact_offset = 0, CellRange cells = {}, const PieceSummary* summary = nullptr);

// A file's dataset built, not yet written: calling it compresses and writes the file. It owns
// its data (the mesh and solution may change after prepare_*), so that a loop can write one
// step's files on another thread while it computes the next (knotwork adapt).
using PreparedWrite = std::function<void()>;
PreparedWrite prepare_bezier_vtu(const std::string& path, const BezierMesh& mesh, const GeometryMap& geometry,
                                 const Eigen::VectorXd& coefficients, const ExactSolution* exact,
                                 const CellFields& cell_fields = {}, double exact_offset = 0, CellRange cells = {},
                                 const PieceSummary* summary = nullptr);

// Polylines in the plane (.vtp), e.g. the knot lines of a mesh, each with integer cell data
// (one array per name, one value per line).
void write_polylines_vtp(const std::string& path, const std::vector<Eigen::MatrixX2d>& lines,
                         const std::vector<std::pair<std::string, std::vector<int>>>& line_fields);
PreparedWrite prepare_polylines_vtp(const std::string& path, const std::vector<Eigen::MatrixX2d>& lines,
                                    const std::vector<std::pair<std::string, std::vector<int>>>& line_fields);

// A ParaView collection (.pvd): (time value, file name relative to the .pvd) per entry.
void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& entries);
// With several datasets per time step: (time value, part, file name).
struct PvdEntry {
  double time;
  int part;
  std::string file;
};
void write_pvd(const std::string& path, const std::vector<PvdEntry>& entries);

}  // namespace knotwork
