// The G1 geometry fitted to a quad mesh: weighted least squares of the basis against the
// mesh's bilinear (or a target shape's) points, solved by SuiteSparseQR (no normal
// equations: the boundary weights would square the conditioning).
#include <Eigen/SPQRSupport>
#include <Eigen/SparseCore>
#include <cmath>
#include <stdexcept>

#include "basis/core/bspline_basis.hpp"
#include "basis/g1/g1_basis.hpp"

namespace knotwork {

namespace {
// SuiteSparseQR works on 64-bit indices (its cholmod_l interface).
using LongSparse = Eigen::SparseMatrix<double, Eigen::ColMajor, long>;
}  // namespace

Eigen::MatrixX3d g1_fit_bilinear(const QuadMesh& mesh, const G1Basis& basis, double* deviation) {
  return g1_fit(
      mesh, basis,
      [&](int f, double s, double t) -> Eigen::Vector3d {
        const auto& v = mesh.face(f);
        return (1 - s) * (1 - t) * mesh.vertex(v[0]) + s * (1 - t) * mesh.vertex(v[1]) + s * t * mesh.vertex(v[2]) +
               (1 - s) * t * mesh.vertex(v[3]);
      },
      deviation);
}

Eigen::MatrixX3d g1_fit(const QuadMesh& mesh, const G1Basis& basis,
                        const std::function<Eigen::Vector3d(int face, double s, double t)>& target_point,
                        double* deviation) {
  const int k = basis.k, r = basis.r, n = 2 * k - r + 1;
  // Greville abscissae: a B-spline combination with these as coefficients is the identity,
  // so the bilinear face has the bilinear map at (xi_i, xi_j) as its coefficients.
  const std::vector<double> xi = greville_abscissae(g1_face_knots(k, r), k);
  Eigen::MatrixX3d target(basis.unknowns(), 3);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) target.row(g1_unknown(f, i, j, k, r)) = target_point(f, xi[i], xi[j]).transpose();
  Eigen::SparseMatrix<double> M(basis.unknowns(), static_cast<Eigen::Index>(basis.functions.size()));
  std::vector<Eigen::Triplet<double>> entries;
  for (size_t j = 0; j < basis.functions.size(); ++j)
    for (const auto& [u, x] : basis.functions[j].coefficients) entries.emplace_back(u, static_cast<int>(j), x);
  M.setFromTriplets(entries.begin(), entries.end());
  // The boundary curve (row 0 of every boundary side) weighs 10^6 times more: a straight
  // side of the mesh stays straight wherever the space allows it (the target is on the
  // segment), instead of trading boundary accuracy for interior accuracy.
  Eigen::VectorXd weight = Eigen::VectorXd::Ones(basis.unknowns());
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const auto& E = mesh.edge(e);
    if (!E.boundary()) continue;
    for (int a = 0; a < n; ++a) weight(g1_corner_unknown(E.face[0], E.corner[0], a, 0, k, r)) = 1e6;
  }
  // Least squares by SuiteSparseQR on the weighted rows (not the normal equations, which would
  // square the condition number and the 10^6 weight with it).
  const Eigen::VectorXd root = weight.cwiseSqrt();
  LongSparse A = LongSparse(root.asDiagonal() * M);
  A.makeCompressed();
  Eigen::SPQR<LongSparse> solver;
  solver.compute(A);
  if (solver.info() != Eigen::Success) throw std::runtime_error("G1 least-squares fit: SuiteSparseQR failed");
  if (solver.rank() < A.cols())
    throw std::runtime_error("G1 least-squares fit: the basis functions' coefficients are rank deficient (rank " +
                             std::to_string(solver.rank()) + " of " + std::to_string(A.cols()) + ")");
  Eigen::MatrixX3d c(A.cols(), 3);
  for (int d = 0; d < 3; ++d) {
    const Eigen::VectorXd b = root.cwiseProduct(target.col(d));
    c.col(d) = solver.solve(b);
  }
  if (deviation) *deviation = (M * c - target).rowwise().norm().maxCoeff();
  return c;
}

}  // namespace knotwork
