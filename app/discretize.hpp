#pragma once
#include <memory>

#include "basis/tensor_patch.hpp"
#include "cases/case_file.hpp"
#include "solver/geometry_map.hpp"

namespace knotwork {

// A case turned into what the solver needs: the BezierMesh and the geometry on its cells.
struct Discretization {
  TensorDiscretization tensor;
  std::unique_ptr<GeometryMap> geometry;
  const BezierMesh& mesh() const { return tensor.mesh; }
};

// Throws InputError naming the case file and [space] when the space cannot be built.
Discretization discretize(const CaseDescription& c);

// Largest physical cell diameter (longest cell diagonal), the h of convergence tables.
double mesh_size(const Discretization& d);

// "tensor NURBS, degree 2x2, C^1" style description of the space.
std::string describe_space(const CaseDescription& c);

}  // namespace knotwork
