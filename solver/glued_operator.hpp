#pragma once
// The Poisson operator of several patches glued by identified functions (a C0-conforming
// multipatch space): the sum of each patch's operator, its functions mapped into the shared
// numbering, K = sum_k P_k^T K_k P_k. Products, diagonal and load are the pieces' gathered and
// added; the assembled matrix is each piece's written matrix (Kronecker form or sum
// factorization) added into the shared pattern, where the element loop would integrate every
// cell again (docs/SOLVERS.md, "On any other map: by sum factorization").
#include <memory>
#include <vector>

#include "solver/matrix_free.hpp"

namespace knotwork {

class GluedPoissonOperator final : public MatrixFreePoisson {
 public:
  // pieces[k] acts on its own functions 0 .. n_k - 1; function f of piece k is global[k][f] of
  // num_functions (one-to-one within a piece), or -1: a function the glued space does not hold
  // (a process's part holds a neighbouring patch for the cells its own functions live on; the
  // rows of those functions are whole, the others' are not). Throws std::invalid_argument on
  // sizes that do not match or numbers out of range.
  GluedPoissonOperator(int num_functions, std::vector<std::unique_ptr<MatrixFreePoisson>> pieces,
                       std::vector<std::vector<int>> global);
  int num_functions() const override { return num_functions_; }
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override;
  Eigen::VectorXd diagonal() const override;
  Eigen::VectorXd load(const Expression& source) const override;
  // A function on k pieces couples with at most k times a piece's most.
  int max_row_nonzeros() const override { return max_row_nonzeros_; }
  bool all_elements_affine() const override;
  bool assembles_lower() const override;
  const char* assembly_method() const override;
  // The pieces' lower triangles, each over its functions that are free in `layout`, added into
  // the pattern lower_pattern_matrix gives a mesh of all the pieces' cells (the couplings of
  // functions that share a cell: within one piece). Piece after piece; within a piece the
  // columns in parallel (the numbering is one-to-one there: no two entries meet).
  Eigen::SparseMatrix<double> lower_matrix(const DofLayout& layout) const override;
  // The couplings: every piece's of the function, mapped and merged (where every piece gives
  // its own).
  bool gives_pattern() const override;
  Eigen::SparseMatrix<double> lower_pattern(const DofLayout& layout) const override;
  void coupled_functions(int function, std::vector<int>& out) const override;

 private:
  int num_functions_ = 0, max_row_nonzeros_ = 0;
  std::vector<std::unique_ptr<MatrixFreePoisson>> pieces_;
  std::vector<std::vector<int>> global_;
  // Every function's places (piece, its function there), in CSR: place_start_[f] ..
  std::vector<int> place_start_;
  std::vector<std::pair<int, int>> places_;
};

}  // namespace knotwork
