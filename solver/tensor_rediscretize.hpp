#pragma once
// The coarse levels of a multigrid without a matrix (solver/tensor_multigrid.cpp): the same
// Poisson operator on the spaces with every other breakpoint dropped, and the matrix of an
// operator read back from products where a level must be factored or multiplied out.
#include <Eigen/SparseCore>
#include <memory>

#include "solver/tensor_operator.hpp"

namespace knotwork {

// The operator of the same problem on the space halved along u and/or v (halved_basis), with
// the geometry's net (and the space's weights, when rational) moved to the coarse elements by
// knot removal: least squares against the refinement matrix, kept only when it reproduces the
// fine net (the geometry lives on the coarse elements). A patch whose elements share one set of
// factors (a map affine on the whole patch) keeps them, with no net. Null when a direction
// asked for does not halve or the geometry does not live there.
std::unique_ptr<TensorPoissonOperator> rediscretized_operator(const TensorPoissonOperator& fine, bool halve_u,
                                                              bool halve_v);

// The whole matrix of `op` over the functions of `free` (numbered as the box), from
// (2p_u + 1)(2p_v + 1) products with indicator vectors: functions more than a degree apart
// never share an element, so each product carries one entry per row.
Eigen::SparseMatrix<double, Eigen::RowMajor> matrix_by_probing(const TensorPoissonOperator& op,
                                                               const TensorPoissonOperator::FunctionBox& free);

}  // namespace knotwork
