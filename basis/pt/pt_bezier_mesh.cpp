#include "basis/pt/pt_bezier_mesh.hpp"

#include <algorithm>
#include <numeric>

#include "basis/core/pooled_extractions.hpp"

namespace knotwork {

namespace {

// The Bezier cell of a T-mesh cell, with the rectangle's sides as boundary ids.
class CellMaker {
 public:
  CellMaker(const RectangularPartition& mesh, int m, int n) : cells_(mesh.cells()), m_(m), n_(n) {
    X0 = cells_[0].x0, Y0 = cells_[0].y0, X1 = cells_[0].x1, Y1 = cells_[0].y1;
    for (const auto& c : cells_) {
      X0 = std::min(X0, c.x0), Y0 = std::min(Y0, c.y0);
      X1 = std::max(X1, c.x1), Y1 = std::max(Y1, c.y1);
    }
  }
  BezierCell operator()(int k) const {
    const RationalBox& b = cells_[k];
    BezierCell cell;
    cell.u0 = b.x0.get_d(), cell.u1 = b.x1.get_d(), cell.v0 = b.y0.get_d(), cell.v1 = b.y1.get_d();
    cell.degree_u = m_, cell.degree_v = n_;
    if (b.y0 == Y0) cell.boundary[kSideBottom] = 0;
    if (b.x1 == X1) cell.boundary[kSideRight] = 1;
    if (b.y1 == Y1) cell.boundary[kSideTop] = 2;
    if (b.x0 == X0) cell.boundary[kSideLeft] = 3;
    return cell;
  }

 private:
  const std::vector<RationalBox>& cells_;
  int m_, n_;
  mpq_class X0, Y0, X1, Y1;
};

BezierMesh empty_mesh(int functions) {
  BezierMesh out;
  out.set_num_functions(functions);
  out.set_boundary_names({"bottom", "right", "top", "left"});
  return out;
}

}  // namespace

BezierMesh pt_bezier_mesh(const RectangularPartition& mesh, const PtCellPolynomials& polys, int m, int n) {
  // Transpose (function -> cells) into (cell -> functions), functions in increasing order.
  std::vector<std::vector<std::pair<int, const std::vector<double>*>>> alive(mesh.num_cells());
  long entries = 0;
  for (size_t f = 0; f < polys.size(); ++f)
    for (const auto& [k, c] : polys[f]) {
      alive[k].emplace_back(static_cast<int>(f), &c);
      ++entries;
    }
  BezierMesh out = empty_mesh(static_cast<int>(polys.size()));
  out.reserve(mesh.num_cells(), entries);
  const CellMaker make_cell(mesh, m, n);
  const int nb = (m + 1) * (n + 1);
  std::vector<int> ids;
  for (int k = 0; k < mesh.num_cells(); ++k) {
    Eigen::MatrixXd C(alive[k].size(), nb);
    ids.clear();
    for (size_t a = 0; a < alive[k].size(); ++a) {
      ids.push_back(alive[k][a].first);
      for (int i = 0; i < nb; ++i) C(a, i) = (*alive[k][a].second)[i];
    }
    out.add_cell(make_cell(k), ids, out.add_extraction(std::move(C)));
  }
  return out;
}

BezierMesh pt_bezier_mesh(const PtSplineBasis& basis, const RectangularPartition& mesh) {
  BezierMesh out = empty_mesh(static_cast<int>(basis.functions.size()));
  out.reserve(mesh.num_cells(), 0);
  const CellMaker make_cell(mesh, basis.m, basis.n);
  // Where the T-mesh repeats itself the cells' coefficients do too, up to the order of their
  // functions: with the rows in a canonical order (by their coefficients, the functions
  // permuted alike) equal matrices are pooled. On the adaptive L-shape at degree 3 (16 380
  // cells) 9 065 of them are distinct.
  PooledExtractions pooled(out);
  std::vector<int> order, ids;
  pt_detail::for_each_cell_polynomials_rounded(
      basis, mesh, [&](int k, const std::vector<int>& functions, Eigen::MatrixXd& C) {
        const auto rows = static_cast<int>(C.rows()), cols = static_cast<int>(C.cols());
        order.resize(rows);
        std::iota(order.begin(), order.end(), 0);
        std::sort(order.begin(), order.end(), [&](int a, int b) {
          for (int i = 0; i < cols; ++i)
            if (C(a, i) != C(b, i)) return C(a, i) < C(b, i);
          return functions[a] < functions[b];
        });
        Eigen::MatrixXd sorted(rows, cols);
        ids.clear();
        for (int r = 0; r < rows; ++r) {
          sorted.row(r) = C.row(order[r]);
          ids.push_back(functions[order[r]]);
        }
        out.add_cell(make_cell(k), ids, pooled.add(std::move(sorted)));
      });
  return out;
}

}  // namespace knotwork
