// A G1 basis as the solver sees it: the BezierMesh of its 4-split cells (extraction from the
// face B-splines to each cell's Bernstein polynomials), and the per-cell Bernstein
// coefficients of a function given on the face B-splines (the geometry's coordinates).
#include <map>
#include <set>
#include <stdexcept>

#include "basis/core/bezier_ops.hpp"
#include "basis/core/bspline_basis.hpp"
#include "basis/g1/g1_basis.hpp"

namespace knotwork {

std::vector<int> support_faces(const G1BasisFunction& f, int k, int r) {
  const long per_face = static_cast<long>(2 * k - r + 1) * (2 * k - r + 1);
  std::set<int> faces;
  for (const auto& [c, v] : f.coefficients)
    if (v != 0) faces.insert(static_cast<int>(c / per_face));
  return {faces.begin(), faces.end()};
}

BezierMesh g1_bezier_mesh(const QuadMesh& mesh, const G1Basis& basis) {
  const int k = basis.k, r = basis.r, n = 2 * k - r + 1;
  const auto extraction = bezier_extraction(BSplineBasis1D(k, g1_face_knots(k, r)));  // two elements, (k+1) x (k+1)
  const int first[2] = {0, n - k - 1};                                  // first function alive per half

  // Per face: the functions living on it, with their coefficients there.
  const long per_face = static_cast<long>(n) * n;
  std::vector<std::map<int, std::vector<std::pair<int, double>>>> on_face(mesh.num_faces());
  for (size_t j = 0; j < basis.functions.size(); ++j)
    for (const auto& [c, v] : basis.functions[j].coefficients)
      on_face[c / per_face][static_cast<int>(j)].emplace_back(static_cast<int>(c % per_face), v);

  BezierMesh out;
  out.reserve(4 * mesh.num_faces(), 0);
  out.set_num_functions(static_cast<int>(basis.functions.size()));
  out.set_boundary_names({"boundary"});
  const int B = (k + 1) * (k + 1);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int ht = 0; ht < 2; ++ht)
      for (int hs = 0; hs < 2; ++hs) {
        BezierCell cell;
        cell.patch = f;
        cell.index_u = hs;
        cell.index_v = ht;
        cell.u0 = 0.5 * hs;
        cell.u1 = cell.u0 + 0.5;
        cell.v0 = 0.5 * ht;
        cell.v1 = cell.v0 + 0.5;
        cell.degree_u = cell.degree_v = k;
        // Face sides: corner 0 -> 1 is t = 0, 1 -> 2 is s = 1, 2 -> 3 is t = 1, 3 -> 0 is s = 0.
        const bool touches[4] = {ht == 0, hs == 1, ht == 1, hs == 0};
        const CellSide sides[4] = {kSideBottom, kSideRight, kSideTop, kSideLeft};
        for (int c = 0; c < 4; ++c)
          if (touches[c] && mesh.edge(mesh.face_edge(f, c)).boundary()) cell.boundary[sides[c]] = 0;
        std::vector<int> ids;
        std::vector<Eigen::RowVectorXd> rows;
        for (const auto& [j, coefficients] : on_face[f]) {
          Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(B);
          for (const auto& [local, v] : coefficients) {
            const int i = local / n - first[hs], jj = local % n - first[ht];
            if (i < 0 || i > k || jj < 0 || jj > k) continue;
            for (int c = 0; c <= k; ++c)
              for (int a = 0; a <= k; ++a) row(a + (k + 1) * c) += v * extraction[hs](i, a) * extraction[ht](jj, c);
          }
          if (row.cwiseAbs().maxCoeff() == 0) continue;
          ids.push_back(j);
          rows.push_back(std::move(row));
        }
        Eigen::MatrixXd C(static_cast<Eigen::Index>(rows.size()), B);
        for (size_t i = 0; i < rows.size(); ++i) C.row(static_cast<Eigen::Index>(i)) = rows[i];
        out.add_cell(cell, ids, out.add_extraction(std::move(C)));
      }
  return out;
}

std::vector<Eigen::MatrixXd> g1_cell_bernstein(const BezierMesh& mesh, const Eigen::MatrixXd& c) {
  std::vector<Eigen::MatrixXd> out(mesh.num_cells());
  for (int cell = 0; cell < mesh.num_cells(); ++cell) {
    const auto ids = mesh.functions(cell);
    const Eigen::MatrixXd& C = mesh.extraction(cell);
    out[cell] = Eigen::MatrixXd::Zero(C.cols(), c.cols());
    for (size_t a = 0; a < ids.size(); ++a) out[cell] += C.row(static_cast<Eigen::Index>(a)).transpose() * c.row(ids[a]);
  }
  return out;
}

}  // namespace knotwork
