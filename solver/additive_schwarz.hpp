#pragma once
// One preconditioner from several local ones (one-level additive Schwarz): z = sum_k R_k^T
// P_k^{-1} R_k r, R_k picking the dofs of block k. Symmetric positive definite when every
// P_k is and the blocks cover every dof; blocks may overlap (a multipatch space's interface
// functions belong to the patches on both sides).
#include <memory>
#include <vector>

#include "solver/iterative_solver.hpp"

namespace knotwork {

struct SchwarzBlock {
  // The block's local dof d is the global dof dofs[d]; -1: a local dof that is none (its input
  // is zero, its output dropped: P_k restricted to the block's real dofs, still SPD).
  std::vector<int> dofs;
  std::unique_ptr<Preconditioner> local;
};

// std::invalid_argument when a dof of 0..num_dofs-1 is in no block.
std::unique_ptr<Preconditioner> additive_schwarz(std::vector<SchwarzBlock> blocks, int num_dofs);

}  // namespace knotwork
