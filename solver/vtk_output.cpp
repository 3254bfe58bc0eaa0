#include "solver/vtk_output.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkHigherOrderHexahedron.h>
#include <vtkHigherOrderQuadrilateral.h>
#include <vtkIdTypeArray.h>
#include <vtkIntArray.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkNew.h>
#include <vtkSmartPointer.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <Eigen/LU>
#include <exception>
#include <fstream>
#include <optional>
#include <stdexcept>

#include "basis/core/bezier_ops.hpp"
#include "quadrature/bernstein.hpp"
#include "solver/error_norms.hpp"

namespace knotwork {

namespace {

vtkSmartPointer<vtkDoubleArray> scalar_array(const char* name, vtkIdType n, int components = 1) {
  auto a = vtkSmartPointer<vtkDoubleArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(n);
  return a;
}

// Raw appended data compressed by LZ4, which every VTK >= 8.1 and ParaView read. VTK's default,
// zlib, made writing the files of an adaptive loop (THB, p = 3, to 58 000 dofs) cost 1.8 times
// the loop's computation; LZ4 writes them 18 times faster, into files 1.7 times larger
// (docs/PERFORMANCE.md, "ParaView output").
void configure(vtkXMLWriter* writer) {
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writer->SetCompressorTypeToLZ4();
}

void write_grid(const std::string& path, vtkUnstructuredGrid* grid) {
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(grid);
  configure(writer);
  if (writer->Write() != 1) throw std::runtime_error(path + ": VTK could not write the file");
}

// The .pvtu summary of pieces written by several processes. VTK's parallel writer lists only
// the pieces its own process writes unless it runs under VTK's MPI controller, which knotwork
// does not build on; the summary is a short XML file with the arrays of the pieces (those of
// `grid`, this process's piece: every piece has the same arrays) and their file names.
void write_summary(const std::string& path, vtkUnstructuredGrid* grid, const std::vector<std::string>& pieces) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write the file");
  auto arrays = [&](vtkDataSetAttributes* data, const char* tag, const std::vector<std::pair<const char*, int>>& roles) {
    out << "    <" << tag;
    for (const auto& [role, attribute] : roles)
      if (vtkDataArray* a = data->GetAttribute(attribute); a && a->GetName()) out << " " << role << "=\"" << a->GetName() << "\"";
    out << ">\n";
    for (int i = 0; i < data->GetNumberOfArrays(); ++i) {
      vtkDataArray* a = data->GetArray(i);
      if (!a || a->GetDataType() != VTK_DOUBLE) throw std::logic_error("write_summary: arrays are doubles");
      out << "      <PDataArray type=\"Float64\" Name=\"" << a->GetName() << "\" NumberOfComponents=\""
          << a->GetNumberOfComponents() << "\"/>\n";
    }
    out << "    </" << tag << ">\n";
  };
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt64\">\n  <PUnstructuredGrid GhostLevel=\"0\">\n";
  arrays(grid->GetPointData(), "PPointData",
         {{"Scalars", vtkDataSetAttributes::SCALARS}, {"RationalWeights", vtkDataSetAttributes::RATIONALWEIGHTS}});
  arrays(grid->GetCellData(), "PCellData", {{"HigherOrderDegrees", vtkDataSetAttributes::HIGHERORDERDEGREES}});
  out << "    <PPoints>\n      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n    </PPoints>\n";
  for (const std::string& piece : pieces) out << "    <Piece Source=\"" << piece << "\"/>\n";
  out << "  </PUnstructuredGrid>\n</VTKFile>\n";
  if (!out.flush()) throw std::runtime_error(path + ": cannot write the file");
}

// This process's piece, and with a summary also the .pvtu.
void write_piece(const std::string& path, vtkUnstructuredGrid* grid, const PieceSummary* summary) {
  write_grid(path, grid);
  if (summary && !summary->path.empty()) write_summary(summary->path, grid, summary->pieces);
}

void add_cell_fields(vtkUnstructuredGrid* grid, const CellFields& fields, int nc, int first, int last) {
  for (const auto& [name, values] : fields) {
    if (values.size() != nc) throw std::invalid_argument("cell field " + name + ": one value per cell is needed");
    auto a = scalar_array(name.c_str(), last - first);
    for (int c = first; c < last; ++c) a->SetValue(c - first, values[c]);
    grid->GetCellData()->AddArray(a);
  }
}

// On a mesh of several patches, the "patch" cell array: the patch each cell lies on (its
// position in the domain, from 0), `quads` VTK cells per mesh cell. Decided on the whole mesh
// a process holds (a part: its patches and its halo), by a cell off patch 0: every piece of a
// parallel output of a connected multipatch domain then has the array (rank 0's part holds
// patch 0 and the halo of a later one; the others hold later patches).
void add_patch_field(vtkUnstructuredGrid* grid, const BezierMesh& mesh, int first, int last, int quads) {
  bool several = false;
  for (int c = 0; c < mesh.num_cells() && !several; ++c) several = mesh.cell(c).patch != 0;
  if (!several) return;
  auto a = scalar_array("patch", static_cast<vtkIdType>(last - first) * quads);
  for (int c = first; c < last; ++c)
    for (int k = 0; k < quads; ++k) a->SetValue(static_cast<vtkIdType>(c - first) * quads + k, mesh.cell(c).patch);
  grid->GetCellData()->AddArray(a);
}

// The "exact" and "error" point arrays, present when an exact solution is known.
struct ExactArrays {
  vtkSmartPointer<vtkDoubleArray> exact, error;
  std::optional<ExpressionEvaluator> u;
  ExactArrays(const ExactSolution* e, vtkIdType n) {
    if (!e) return;
    exact = scalar_array("exact", n);
    error = scalar_array("error", n);
    u.emplace(e->u);
  }
  explicit operator bool() const { return exact != nullptr; }
  // Thread-safe for distinct ids: the arrays are allocated up front.
  void set(vtkIdType id, double exact_value, double solution_value) {
    exact->SetValue(id, exact_value);
    error->SetValue(id, solution_value - exact_value);
  }
  void add_to(vtkUnstructuredGrid* grid) const {
    if (!exact) return;
    grid->GetPointData()->AddArray(exact);
    grid->GetPointData()->AddArray(error);
  }
};

}  // namespace

namespace {

// A polynomial cell's field in its Bernstein basis: C^T times the coefficients of its functions.
Eigen::VectorXd bernstein_coefficients(const BezierMesh& mesh, const Eigen::VectorXd& coeffs, int cell) {
  const auto ids = mesh.functions(cell);
  Eigen::VectorXd local(static_cast<Eigen::Index>(ids.size()));
  for (size_t a = 0; a < ids.size(); ++a) local[a] = coeffs[ids[a]];
  return mesh.extraction(cell).transpose() * local;
}

// The physical points at the nodes, from the cell's own (rational) Bezier form: the nodes'
// Bernstein values (collocation) times the weighted control points, over W = collocation * w.
// The form is exact (an analytic map's interpolates it at these very nodes), so this is the map
// at the nodes without evaluating the patch's B-splines and their derivatives again.
Eigen::MatrixXd nodes_of(const Eigen::MatrixXd& collocation, const BezierGeometryCell& g, const Eigen::VectorXd& W) {
  const Eigen::MatrixXd weighted = g.points.array().colwise() * g.weights.array();
  return (collocation * weighted).array().colwise() / W.array();
}

// A rational Bezier hexahedron's equispaced nodes (i/p, j/q, k/r), node i + (p+1) (j + (q+1) k),
// and the collocation of its Bernstein polynomials there: what turns values at the nodes into
// the Bezier coefficients of the interpolant (as bernstein_interpolation_inverse does for quads).
struct HexahedronNodes {
  int p = -1, q = -1, r = -1;
  Eigen::VectorXd u, v, w;
  Eigen::MatrixXd collocation;  // nodes x Bernstein polynomials
  void set(int pu, int pv, int pw) {
    if (pu == p && pv == q && pw == r) return;
    p = pu, q = pv, r = pw;
    const int n[3] = {p + 1, q + 1, r + 1}, nb = n[0] * n[1] * n[2];
    u.resize(nb), v.resize(nb), w.resize(nb);
    for (int k = 0; k < nb; ++k) u[k] = double(k % n[0]) / p, v[k] = double((k / n[0]) % n[1]) / q, w[k] = double(k / (n[0] * n[1])) / r;
    double bu[16], bv[16], bw[16], d[16];
    collocation.resize(nb, nb);
    for (int k = 0; k < nb; ++k) {
      bernstein_values_and_derivatives(p, u[k], bu, d);
      bernstein_values_and_derivatives(q, v[k], bv, d);
      bernstein_values_and_derivatives(r, w[k], bw, d);
      for (int c = 0; c <= r; ++c)
        for (int b = 0; b <= q; ++b)
          for (int a = 0; a <= p; ++a) collocation(k, a + n[0] * (b + n[1] * c)) = bu[a] * bv[b] * bw[c];
    }
  }
};

}  // namespace

void write_bezier_vtu(const std::string& path, const BezierMesh& mesh, const GeometryMap& geometry,
                      const Eigen::VectorXd& coeffs, const ExactSolution* exact, const CellFields& cell_fields,
                      double exact_offset, CellRange range, const PieceSummary* summary) {
  prepare_bezier_vtu(path, mesh, geometry, coeffs, exact, cell_fields, exact_offset, range, summary)();
}

PreparedWrite prepare_bezier_vtu(const std::string& path, const BezierMesh& mesh, const GeometryMap& geometry,
                                 const Eigen::VectorXd& coeffs, const ExactSolution* exact, const CellFields& cell_fields,
                                 double exact_offset, CellRange range, const PieceSummary* summary) {
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  const int first = range.first, last = range.last < 0 ? mesh.num_cells() : range.last, nc = last - first;
  // The geometry's Bezier cells (of the cell's degree, or the map's where that is higher), then
  // cell c's points are [start[c], start[c + 1]): the cells are filled in parallel, each into
  // its own range.
  std::vector<BezierGeometryCell> bezier(nc);
  std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic, 64)
  for (int c = 0; c < nc; ++c) {
    try {
      bezier[c] = geometry.bezier_cell(first + c);
    } catch (...) {
#pragma omp critical(write_bezier_vtu_failure)
      if (!failure) failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
  std::vector<vtkIdType> start(nc + 1, 0);
  for (int c = 0; c < nc; ++c) start[c + 1] = start[c] + bezier[c].points.rows();
  const vtkIdType total = start[nc];
  points->SetNumberOfPoints(total);
  auto weights = scalar_array("RationalWeights", total);
  auto degrees = scalar_array("HigherOrderDegrees", nc, 3);
  auto solution = scalar_array("solution", total);
  ExactArrays ex(exact, total);
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfValues(nc + 1);
  connectivity->SetNumberOfValues(total);
  for (int c = 0; c <= nc; ++c) offsets->SetValue(c, start[c]);
  std::optional<ExpressionBatch> compiled_exact;  // compiled once; each thread runs its own copy
  if (exact) compiled_exact.emplace(std::vector<Expression>{exact->u});
#pragma omp parallel
  {
    std::optional<ExpressionBatch> exact_u;
    if (exact) exact_u.emplace(*compiled_exact);
    int last_p = -1, last_q = -1;
    Eigen::MatrixXd inverse, collocation;
    Eigen::VectorXd nu, nv;
    HexahedronNodes hexahedron;
#pragma omp for schedule(dynamic, 64)
    for (int c = 0; c < nc; ++c) {
      try {
        const BezierGeometryCell& g = bezier[c];
        if (g.degree_w > 0) {  // a hexahedron: the same steps in three directions
          const int p = g.degree_u, q = g.degree_v, r = g.degree_w;
          hexahedron.set(p, q, r);
          const BezierCell& cell = mesh.cell(first + c);
          const bool polynomial = !mesh.is_rational() && cell.degree_u == p && cell.degree_v == q && cell.degree_w == r &&
                                  (g.weights.array() == 1.0).all();
          const Eigen::VectorXd W = hexahedron.collocation * g.weights;
          auto to_bezier = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
            return bernstein_interpolant(p, q, r, W.cwiseProduct(v)).col(0).cwiseQuotient(g.weights);
          };
          Eigen::VectorXd fu, fe;
          if (polynomial) {
            fu = bernstein_coefficients(mesh, coeffs, first + c);
          } else {
            fu = to_bezier(evaluate_volume_solution(mesh, geometry, coeffs, first + c, hexahedron.u, hexahedron.v,
                                                    hexahedron.w).col(0));
          }
          if (exact) {
            const Eigen::MatrixXd x = nodes_of(hexahedron.collocation, g, W);
            exact_u->evaluate(x.col(0).data(), x.col(1).data(), x.col(2).data(), x.rows());
            fe = to_bezier(Eigen::Map<const Eigen::VectorXd>(exact_u->result(0), x.rows()).array() - exact_offset);
          }
          const int order[3] = {p, q, r};
          for (int k = 0; k <= r; ++k)
            for (int j = 0; j <= q; ++j)
              for (int i = 0; i <= p; ++i) {
                const int b = i + (p + 1) * (j + (q + 1) * k);
                const vtkIdType id = start[c] + vtkHigherOrderHexahedron::PointIndexFromIJK(i, j, k, order);
                connectivity->SetValue(id, id);
                points->SetPoint(id, g.points(b, 0), g.points(b, 1), g.points(b, 2));
                weights->SetValue(id, g.weights[b]);
                solution->SetValue(id, fu[b]);
                if (ex) ex.set(id, fe[b], fu[b]);
              }
          const double deg[3] = {double(p), double(q), double(r)};
          degrees->SetTuple(c, deg);
          continue;
        }
        const int p = g.degree_u, q = g.degree_v, nb = (p + 1) * (q + 1);
        if (p != last_p || q != last_q) {
          inverse = bernstein_interpolation_inverse(p, q);
          collocation = inverse.inverse();
          nu.resize(nb);
          nv.resize(nb);
          for (int j = 0; j <= q; ++j)
            for (int i = 0; i <= p; ++i) {
              nu[i + (p + 1) * j] = double(i) / p;
              nv[i + (p + 1) * j] = double(j) / q;
            }
          last_p = p;
          last_q = q;
        }
        // Field coefficients f with sum w_b B_b f_b / W = value at every node. A polynomial
        // solution on a polynomial cell of the geometry's degree is its own Bezier form,
        // C^T times its coefficients: no evaluation (which was half of an adaptive step's output).
        const BezierCell& cell = mesh.cell(first + c);
        const bool polynomial = !mesh.is_rational() && cell.degree_u == p && cell.degree_v == q &&
                                (g.weights.array() == 1.0).all();
        const Eigen::VectorXd W = collocation * g.weights;
        auto to_bezier = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
          return (inverse * W.cwiseProduct(v)).cwiseQuotient(g.weights);
        };
        Eigen::VectorXd fu, fe;
        if (polynomial) fu = bernstein_coefficients(mesh, coeffs, first + c);
        else fu = to_bezier(evaluate_solution(mesh, geometry, coeffs, first + c, nu, nv).col(0));
        if (exact) {
          const Eigen::MatrixXd x = nodes_of(collocation, g, W);
          exact_u->evaluate(x.col(0).data(), x.col(1).data(), x.cols() == 3 ? x.col(2).data() : nullptr, x.rows());
          fe = to_bezier(Eigen::Map<const Eigen::VectorXd>(exact_u->result(0), x.rows()).array() - exact_offset);
        }
        const int order[2] = {p, q};
        for (int j = 0; j <= q; ++j)
          for (int i = 0; i <= p; ++i) {
            const int b = i + (p + 1) * j;
            const vtkIdType local = vtkHigherOrderQuadrilateral::PointIndexFromIJK(i, j, order);
            const vtkIdType id = start[c] + local;
            connectivity->SetValue(id, id);
            points->SetPoint(id, g.points(b, 0), g.points(b, 1), g.points.cols() == 3 ? g.points(b, 2) : 0.0);
            weights->SetValue(id, g.weights[b]);
            solution->SetValue(id, fu[b]);
            if (ex) ex.set(id, fe[b], fu[b]);
          }
        const double deg[3] = {double(p), double(q), 1.0};
        degrees->SetTuple(c, deg);
      } catch (...) {
#pragma omp critical(write_bezier_vtu_failure)
        if (!failure) failure = std::current_exception();
      }
    }
  }
  if (failure) std::rethrow_exception(failure);
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  grid->SetPoints(points);
  grid->SetCells(geometry.parametric_dimension() == 3 ? VTK_BEZIER_HEXAHEDRON : VTK_BEZIER_QUADRILATERAL, cells);
  grid->GetPointData()->SetRationalWeights(weights);
  grid->GetCellData()->SetHigherOrderDegrees(degrees);
  grid->GetPointData()->SetScalars(solution);
  ex.add_to(grid);
  add_cell_fields(grid, cell_fields, mesh.num_cells(), first, last);
  add_patch_field(grid, mesh, first, last, 1);
  std::optional<PieceSummary> copy;
  if (summary) copy = *summary;
  return [path, grid, copy] { write_piece(path, grid, copy ? &*copy : nullptr); };
}

void write_bezier_surface_vtu(const std::string& path, const BezierSurface& s) {
  vtkNew<vtkUnstructuredGrid> grid;
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  const int nc = static_cast<int>(s.points.size());
  vtkIdType total = 0;
  for (int c = 0; c < nc; ++c) total += s.points[c].rows();
  points->SetNumberOfPoints(total);
  auto weights = scalar_array("RationalWeights", total);
  auto degrees = scalar_array("HigherOrderDegrees", nc, 3);
  std::vector<vtkSmartPointer<vtkDoubleArray>> fields;
  for (const auto& [name, values] : s.point_fields) {
    if (static_cast<int>(values.size()) != nc) throw std::invalid_argument("point field " + name + ": one vector per cell is needed");
    fields.push_back(scalar_array(name.c_str(), total));
  }
  grid->Allocate(nc);
  vtkIdType offset = 0;
  std::vector<vtkIdType> ids;
  for (int c = 0; c < nc; ++c) {
    const int p = s.degree[c], nb = (p + 1) * (p + 1);
    if (s.points[c].rows() != nb) throw std::invalid_argument("cell " + std::to_string(c) + ": (p+1)^2 control points needed");
    const int order[2] = {p, p};
    ids.assign(nb, 0);
    for (int j = 0; j <= p; ++j)
      for (int i = 0; i <= p; ++i) {
        const int b = i + (p + 1) * j;
        const int local = vtkHigherOrderQuadrilateral::PointIndexFromIJK(i, j, order);
        const vtkIdType id = offset + local;
        ids[local] = id;
        points->SetPoint(id, s.points[c](b, 0), s.points[c](b, 1), s.points[c](b, 2));
        weights->SetValue(id, 1.0);
        for (size_t f = 0; f < fields.size(); ++f) fields[f]->SetValue(id, s.point_fields[f].second[c](b));
      }
    grid->InsertNextCell(VTK_BEZIER_QUADRILATERAL, nb, ids.data());
    const double deg[3] = {double(p), double(p), 1.0};
    degrees->SetTuple(c, deg);
    offset += nb;
  }
  grid->SetPoints(points);
  grid->GetPointData()->SetRationalWeights(weights);
  grid->GetCellData()->SetHigherOrderDegrees(degrees);
  for (size_t f = 0; f < fields.size(); ++f) {
    if (f == 0)
      grid->GetPointData()->SetScalars(fields[f]);
    else
      grid->GetPointData()->AddArray(fields[f]);
  }
  add_cell_fields(grid, s.cell_fields, nc, 0, nc);
  write_grid(path, grid);
}

void write_sampled_vtu(const std::string& path, const BezierMesh& mesh, const GeometryMap& geometry,
                       const Eigen::VectorXd& coeffs, const ExactSolution* exact, int samples, double exact_offset,
                       CellRange range, const PieceSummary* summary) {
  const int first = range.first, last = range.last < 0 ? mesh.num_cells() : range.last;
  // Quadrilaterals cut into s^2 linear quads, hexahedra into s^3 linear hexahedra.
  const bool hexahedra = geometry.parametric_dimension() == 3;
  const int s = samples, m = s + 1, nc = last - first, per_cell = hexahedra ? m * m * m : m * m;
  const int pieces = hexahedra ? s * s * s : s * s;
  const vtkIdType total = static_cast<vtkIdType>(nc) * per_cell;
  vtkNew<vtkUnstructuredGrid> grid;
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(total);
  auto solution = scalar_array("solution", total);
  auto gradient = scalar_array("solution_gradient", total, 3);
  ExactArrays ex(exact, total);
  CellSamples cs;
  grid->Allocate(static_cast<vtkIdType>(nc) * pieces);
  for (int c = 0; c < nc; ++c) {
    sample_cell(mesh, geometry, coeffs, first + c, s, ex ? &*ex.u : nullptr, exact_offset, cs);
    const Eigen::MatrixXd& x = cs.at.x;
    const bool surface = x.cols() == 3;
    const vtkIdType base = static_cast<vtkIdType>(c) * per_cell;
    for (int k = 0; k < per_cell; ++k) {
      points->SetPoint(base + k, x(k, 0), x(k, 1), surface ? x(k, 2) : 0.0);
      solution->SetValue(base + k, cs.uh(k, 0));
      const double grad[3] = {cs.uh(k, 1), cs.uh(k, 2), surface ? cs.uh(k, 3) : 0.0};
      gradient->SetTuple(base + k, grad);
      if (ex) ex.set(base + k, cs.exact[k], cs.uh(k, 0));
    }
    const auto id = [&](int i, int j, int k) { return base + i + m * (j + m * k); };
    for (int k = 0; k < (hexahedra ? s : 1); ++k)
      for (int j = 0; j < s; ++j)
        for (int i = 0; i < s; ++i) {
          // VTK's corner order: counterclockwise at the bottom (k), then the same above it.
          const vtkIdType q[8] = {id(i, j, k),         id(i + 1, j, k),         id(i + 1, j + 1, k),
                                  id(i, j + 1, k),     id(i, j, k + 1),         id(i + 1, j, k + 1),
                                  id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
          if (hexahedra) grid->InsertNextCell(VTK_HEXAHEDRON, 8, q);
          else grid->InsertNextCell(VTK_QUAD, 4, q);
        }
  }
  grid->SetPoints(points);
  grid->GetPointData()->SetScalars(solution);
  grid->GetPointData()->AddArray(gradient);
  ex.add_to(grid);
  add_patch_field(grid, mesh, first, last, pieces);
  write_piece(path, grid, summary);
}

void write_polylines_vtp(const std::string& path, const std::vector<Eigen::MatrixX2d>& lines,
                         const std::vector<std::pair<std::string, std::vector<int>>>& line_fields) {
  prepare_polylines_vtp(path, lines, line_fields)();
}

PreparedWrite prepare_polylines_vtp(const std::string& path, const std::vector<Eigen::MatrixX2d>& lines,
                                    const std::vector<std::pair<std::string, std::vector<int>>>& line_fields) {
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkCellArray> cells;
  for (const auto& l : lines) {
    std::vector<vtkIdType> ids;
    for (Eigen::Index k = 0; k < l.rows(); ++k) ids.push_back(points->InsertNextPoint(l(k, 0), l(k, 1), 0.0));
    cells->InsertNextCell(static_cast<vtkIdType>(ids.size()), ids.data());
  }
  poly->SetPoints(points);
  poly->SetLines(cells);
  for (const auto& [name, values] : line_fields) {
    if (values.size() != lines.size()) throw std::invalid_argument("line field " + name + ": one value per line is needed");
    vtkNew<vtkIntArray> a;
    a->SetName(name.c_str());
    for (int v : values) a->InsertNextValue(v);
    poly->GetCellData()->AddArray(a);
  }
  return [path, poly] {
    vtkNew<vtkXMLPolyDataWriter> writer;
    writer->SetFileName(path.c_str());
    writer->SetInputData(poly);
    configure(writer);
    if (writer->Write() != 1) throw std::runtime_error(path + ": VTK could not write the file");
  };
}

void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& entries) {
  std::vector<PvdEntry> e;
  for (const auto& [time, file] : entries) e.push_back({time, 0, file});
  write_pvd(path, e);
}

void write_pvd(const std::string& path, const std::vector<PvdEntry>& entries) {
  std::ofstream out(path);
  out << "<?xml version=\"1.0\"?>\n"
         "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (const auto& [time, part, file] : entries)
    out << "    <DataSet timestep=\"" << time << "\" group=\"\" part=\"" << part << "\" file=\"" << file << "\"/>\n";
  out << "  </Collection>\n</VTKFile>\n";
  if (!out) throw std::runtime_error(path + ": could not write the collection file");
}

}  // namespace knotwork
