#include "basis/core/bezier_mesh.hpp"

#include <algorithm>
#include <stdexcept>

namespace knotwork {

int BezierMesh::add_extraction(Eigen::MatrixXd matrix) {
  pool_.push_back(std::move(matrix));
  return static_cast<int>(pool_.size()) - 1;
}

void BezierMesh::add_cell(const BezierCell& cell, std::span<const int> functions,
                          int extraction) {
  const Eigen::MatrixXd& C = pool_.at(extraction);
  if (C.rows() != static_cast<Eigen::Index>(functions.size()) ||
      C.cols() != (cell.degree_u + 1) * (cell.degree_v + 1))
    throw std::logic_error("BezierMesh::add_cell: extraction matrix size does not match");
  cells_.push_back(cell);
  extraction_of_cell_.push_back(extraction);
  ids_.insert(ids_.end(), functions.begin(), functions.end());
  offsets_.push_back(static_cast<int>(ids_.size()));
  max_active_ = std::max(max_active_, static_cast<int>(functions.size()));
  max_degree_ = std::max({max_degree_, cell.degree_u, cell.degree_v});
}

void rational_cell_extraction(const BezierMesh& mesh, int c, Eigen::VectorXd& wb,
                              Eigen::MatrixXd& C_hat) {
  const Eigen::MatrixXd& C = mesh.extraction(c);
  if (!mesh.is_rational()) {
    wb.setOnes(C.cols());
    C_hat = C;
    return;
  }
  const auto ids = mesh.functions(c);
  thread_local Eigen::VectorXd w;
  w.resize(static_cast<Eigen::Index>(ids.size()));
  for (size_t i = 0; i < ids.size(); ++i) w[i] = mesh.weights()[ids[i]];
  wb.noalias() = C.transpose() * w;
  C_hat.noalias() = w.asDiagonal() * C * wb.cwiseInverse().asDiagonal();
}

}  // namespace knotwork
