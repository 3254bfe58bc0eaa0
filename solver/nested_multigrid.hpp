#pragma once
// Multigrid over nested spaces V_0 ⊂ V_1 ⊂ ... ⊂ V_k, the steps of an adaptive loop
// (studies/adaptive.cpp): each step's own matrix is a level, the family's prolongation
// (SplineSpace::prolongation_from_predecessor) connects it to the step before, and the
// starting space's matrix is factored. Smoothing is local: a level smooths only the functions
// its step changed (those not carried over unchanged from the step before), as in local
// multigrid for adaptive meshes (Bramble-Pasciak-Wang-Xu; for hierarchical splines, Hofreither,
// Mitter, Speleers), so that a V-cycle costs about the work of the changes, not of every level.
// Symmetric (forward Gauss-Seidel before, backward after): a preconditioner for CG.
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "solver/iterative_solver.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

class NestedMultigrid {
 public:
  NestedMultigrid();
  ~NestedMultigrid();
  // The next step's level: its free dofs (`layout`), its matrix over them (lower triangle, as
  // CHOLMOD reads it) and the prolongation from the previous step's functions to this step's
  // (all functions; null for the first level, which is factored). The prolongation is
  // restricted to the free dofs of the two steps: a free function of the previous step has no
  // part in this step's fixed functions. std::invalid_argument when its size does not match.
  void add_level(const DofLayout& layout, const Eigen::SparseMatrix<double>& lower, const Eigen::SparseMatrix<double>* prolongation);
  int levels() const;
  // The V-cycle from the finest level added so far. It shares the levels: adding one later does
  // not change what it applies.
  std::unique_ptr<Preconditioner> preconditioner() const;

  struct Level;

 private:
  std::vector<std::shared_ptr<const Level>> levels_;
  DofLayout last_layout_;
};

}  // namespace knotwork
