#include "basis/core/bezier_mesh_checks.hpp"

#include <Eigen/QR>
#include <algorithm>

namespace knotwork {

double partition_of_unity_error(const BezierMesh& mesh) {
  double worst = 0;
  Eigen::VectorXd wb;
  Eigen::MatrixXd C;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    rational_cell_extraction(mesh, c, wb, C);
    worst = std::max(worst, (C.colwise().sum().array() - 1.0).abs().maxCoeff());
  }
  return worst;
}

long bezier_rank(const BezierMesh& mesh) {
  const long n = mesh.num_functions();
  long columns = 0;
  for (int c = 0; c < mesh.num_cells(); ++c) columns += mesh.extraction(c).cols();
  if (n * columns > 40'000'000L) return -1;
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(columns, n);
  long offset = 0;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const Eigen::MatrixXd& C = mesh.extraction(c);
    const auto ids = mesh.functions(c);
    for (size_t a = 0; a < ids.size(); ++a) G.block(offset, ids[a], C.cols(), 1) = C.row(a).transpose();
    offset += C.cols();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(G);
  qr.setThreshold(1e-10);
  return qr.rank();
}

}  // namespace knotwork
