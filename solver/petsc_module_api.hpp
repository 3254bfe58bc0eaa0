#pragma once
// The table of functions the PETSc module exports (knotwork_petsc_api, found by dlsym) and
// the loader calls: between solver/petsc_loader.cpp and the module's sources only.
#include <Eigen/SparseCore>

#include "solver/iterative_solver.hpp"
#include "solver/petsc_module.hpp"

namespace knotwork {

struct PetscModuleApi {
  ParallelWorld (*world)();
  void (*reduce)(double* values, int n, bool maximum);
  std::optional<RankFailure> (*agree_on_failure)(int kind, const std::string& message);
  DistributedSystem* (*make_system)(int num_free, int first_row, int last_row);
  void (*broadcast)(std::string& text);
  Preconditioner* (*boomeramg)(const Eigen::SparseMatrix<double>& lower, const std::string& petsc_options);
  std::vector<double> (*gather_all)(const std::vector<double>& mine);
};

}  // namespace knotwork
