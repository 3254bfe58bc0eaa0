#pragma once
// A case's assembled linear system over all its basis functions, before the Dirichlet functions
// are eliminated: what a researcher takes into their own linear algebra (a conditioning study,
// an eigenvalue problem, a comparison with another code). Python's knotwork.system.
#include <Eigen/SparseCore>
#include <vector>

#include "studies/pipeline.hpp"

namespace knotwork {

// Rows and columns are the space's basis functions, in its own numbering (Space.functions,
// the coefficients `run` returns).
struct AssembledSystem {
  // The form's matrix, a(phi_j, phi_i) = (A grad phi_j, grad phi_i) + (c phi_j, phi_i), with
  // Nitsche's boundary terms when the case imposes Dirichlet data weakly; and the mass matrix
  // (phi_j, phi_i). Both whole and symmetric, compressed by rows.
  Eigen::SparseMatrix<double, Eigen::RowMajor> stiffness, mass;
  // (f, phi_i), the Neumann terms, and Nitsche's data terms.
  Eigen::VectorXd load;
  // The functions the Dirichlet projection fixes (ascending; none with Nitsche's method or on
  // a closed surface) and their projected values.
  std::vector<int> dirichlet;
  Eigen::VectorXd dirichlet_values;
  // A closed surface without a reaction term: the stiffness has the constants in its kernel,
  // and `run` solves with f's mean removed and the solution's mean fixed to zero.
  bool zero_mean = false;
};

// Throws InputError naming the case (a degenerate geometry: "[geometry]"), as solve_case does.
AssembledSystem assemble_system(const CaseDescription& c, const SplineSpace& space, const ProgressFunction& progress = {});

}  // namespace knotwork
