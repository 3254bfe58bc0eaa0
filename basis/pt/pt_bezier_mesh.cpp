#include "basis/pt/pt_bezier_mesh.hpp"

#include <algorithm>

namespace knotwork {

BezierMesh pt_bezier_mesh(const RectangularPartition& mesh, const PtCellPolynomials& polys, int m, int n) {
  // Transpose (function -> cells) into (cell -> functions), functions in increasing order.
  std::vector<std::vector<std::pair<int, const std::vector<double>*>>> alive(mesh.num_cells());
  long entries = 0;
  for (size_t f = 0; f < polys.size(); ++f)
    for (const auto& [k, c] : polys[f]) {
      alive[k].emplace_back(static_cast<int>(f), &c);
      ++entries;
    }
  mpq_class X0 = mesh.cells()[0].x0, Y0 = mesh.cells()[0].y0, X1 = mesh.cells()[0].x1, Y1 = mesh.cells()[0].y1;
  for (const auto& c : mesh.cells()) {
    X0 = std::min(X0, c.x0), Y0 = std::min(Y0, c.y0);
    X1 = std::max(X1, c.x1), Y1 = std::max(Y1, c.y1);
  }
  BezierMesh out;
  out.reserve(mesh.num_cells(), entries);
  out.set_num_functions(static_cast<int>(polys.size()));
  out.set_boundary_names({"bottom", "right", "top", "left"});
  const int nb = (m + 1) * (n + 1);
  std::vector<int> ids;
  for (int k = 0; k < mesh.num_cells(); ++k) {
    const RationalBox& b = mesh.cells()[k];
    Eigen::MatrixXd C(alive[k].size(), nb);
    ids.clear();
    for (size_t a = 0; a < alive[k].size(); ++a) {
      ids.push_back(alive[k][a].first);
      for (int i = 0; i < nb; ++i) C(a, i) = (*alive[k][a].second)[i];
    }
    BezierCell cell;
    cell.u0 = b.x0.get_d(), cell.u1 = b.x1.get_d(), cell.v0 = b.y0.get_d(), cell.v1 = b.y1.get_d();
    cell.degree_u = m, cell.degree_v = n;
    if (b.y0 == Y0) cell.boundary[kSideBottom] = 0;
    if (b.x1 == X1) cell.boundary[kSideRight] = 1;
    if (b.y1 == Y1) cell.boundary[kSideTop] = 2;
    if (b.x0 == X0) cell.boundary[kSideLeft] = 3;
    out.add_cell(cell, ids, out.add_extraction(std::move(C)));
  }
  return out;
}

}  // namespace knotwork
