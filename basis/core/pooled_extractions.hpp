#pragma once
// Filling a BezierMesh whose cells often repeat the same extraction matrix (the cells away
// from level changes of THB, repeated configurations of a T-mesh): each distinct matrix is
// stored once and shared by the cells that have it.
#include <string_view>
#include <unordered_map>

#include "basis/core/bezier_mesh.hpp"

namespace knotwork {

class PooledExtractions {
 public:
  explicit PooledExtractions(BezierMesh& mesh) : mesh_(mesh) {}
  // The pool id of a matrix equal to `matrix` (same shape, same bits), added when new.
  int add(Eigen::MatrixXd matrix);

 private:
  BezierMesh& mesh_;
  // The bytes of the matrices kept by the mesh (their buffers stay put while it lives) -> id.
  std::unordered_map<std::string_view, int> ids_;
};

}  // namespace knotwork
