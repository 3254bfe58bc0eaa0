#pragma once
// Filling a BezierMesh whose cells often repeat the same extraction matrix (the cells away
// from level changes of THB, repeated configurations of a T-mesh): each distinct matrix is
// stored once and shared by the cells that have it.
#include <unordered_map>

#include "basis/core/bezier_mesh.hpp"

namespace knotwork {

class PooledExtractions {
 public:
  explicit PooledExtractions(BezierMesh& mesh) : mesh_(mesh) {}
  // The pool id of a matrix equal to `matrix` (same shape, same bits), added when new.
  int add(Eigen::MatrixXd matrix) {
    const size_t h = hash(matrix);
    return add(std::move(matrix), h);
  }
  // The same with the matrix's hash(), computed beforehand (in parallel, by the caller).
  int add(Eigen::MatrixXd matrix, size_t hash);
  static size_t hash(const Eigen::MatrixXd& matrix);

 private:
  BezierMesh& mesh_;
  // hash -> the ids of the matrices kept by the mesh with that hash.
  std::unordered_multimap<size_t, int> ids_;
};

}  // namespace knotwork
