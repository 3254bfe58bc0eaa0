// Checks of a G1 basis that do not depend on how it was built: the G1 conditions on every
// function's edges (relative residual) and the rank of all functions' coefficients.
#include <Eigen/SVD>
#include <Eigen/SPQRSupport>
#include <Eigen/SparseCore>
#include <cmath>
#include <set>
#include <stdexcept>
#include <unordered_map>

#include "basis/g1/g1_basis.hpp"

namespace knotwork {

namespace {
constexpr double kTolerance = 1e-10;  // relative rank tolerance, as in the construction
// SuiteSparseQR works on 64-bit indices (its cholmod_l interface).
using LongSparse = Eigen::SparseMatrix<double, Eigen::ColMajor, long>;
}  // namespace

double g1_residual_max(const QuadMesh& mesh, const GluingData& gluing, const G1Basis& basis) {
  // Rows per edge; a function is checked on the edges of the faces it lives on (on every
  // other edge both sides of every row are zero).
  std::vector<std::vector<std::vector<std::pair<long, double>>>> rows(mesh.num_edges());
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (!mesh.edge(e).boundary()) rows[e] = g1_condition_rows(mesh, gluing, basis.k, basis.r, e);
  double worst = 0;
  std::unordered_map<long, double> x;
  for (const auto& f : basis.functions) {
    x.clear();
    double scale = 0;
    for (const auto& [c, v] : f.coefficients) {
      x[c] = v;
      scale = std::max(scale, std::abs(v));
    }
    if (scale == 0) return INFINITY;  // a zero function is no basis function
    std::set<int> edges;
    for (int face : support_faces(f, basis.k, basis.r))
      for (int side = 0; side < 4; ++side) edges.insert(mesh.face_edge(face, side));
    for (int e : edges)
      for (const auto& row : rows[e]) {
        double sum = 0, size = 0;
        for (const auto& [c, a] : row) {
          size += std::abs(a);
          const auto it = x.find(c);
          if (it != x.end()) sum += a * it->second;
        }
        if (size > 0) worst = std::max(worst, std::abs(sum) / (size * scale));
      }
  }
  return worst;
}

long g1_basis_rank(const G1Basis& basis, std::string* method) {
  const Eigen::Index m = basis.unknowns(), n = static_cast<Eigen::Index>(basis.functions.size());
  if (n == 0) return 0;
  if (static_cast<double>(m) * static_cast<double>(n) <= 2.5e7) {
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(m, n);
    for (Eigen::Index j = 0; j < n; ++j)
      for (const auto& [c, v] : basis.functions[j].coefficients) M(c, j) = v;
    Eigen::BDCSVD<Eigen::MatrixXd> svd(M);
    svd.setThreshold(kTolerance);
    if (method) *method = "SVD, singular values above 1e-10 * largest";
    return svd.rank();
  }
  // Too large for a dense SVD: SuiteSparseQR's rank-revealing sparse QR. Every function's
  // largest coefficient is 1, so the columns have 2-norms between 1 and sqrt(their size).
  LongSparse M(m, n);
  std::vector<Eigen::Triplet<double, long>> entries;
  for (Eigen::Index j = 0; j < n; ++j)
    for (const auto& [c, v] : basis.functions[j].coefficients) entries.emplace_back(c, j, v);
  M.setFromTriplets(entries.begin(), entries.end());
  M.makeCompressed();
  double largest_column = 0;
  for (Eigen::Index j = 0; j < n; ++j) largest_column = std::max(largest_column, M.col(j).norm());
  Eigen::SPQR<LongSparse> qr;
  qr.setPivotThreshold(kTolerance * largest_column);
  qr.compute(M);
  if (qr.info() != Eigen::Success) throw std::runtime_error("G1 basis rank: SuiteSparseQR failed");
  if (method) *method = "SuiteSparseQR, columns below 1e-10 * the largest column norm are dependent";
  return qr.rank();
}

}  // namespace knotwork
