#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>

namespace knotwork {

// Fill-reducing ordering for the Cholesky factorization (CHOLMOD's names). kCholmodDefault
// leaves CHOLMOD's own strategy (AMD, then METIS too when AMD's fill is high; best kept).
// kAuto: what was measured best for the mesh (resolve_ordering): AMD on planar domains and
// surfaces, METIS on volumes (docs/VOLUMES.md: 0.6x the fill, 2.4x faster factorizations).
enum class Ordering { kAmd, kMetis, kNesdis, kCholmodDefault, kAuto };
// kAuto made concrete for a mesh whose cells are hexahedra (`volume`) or not.
inline Ordering resolve_ordering(Ordering o, bool volume) {
  return o != Ordering::kAuto ? o : volume ? Ordering::kMetis : Ordering::kAmd;
}
// "auto" | "amd" | "metis" | "nesdis" | "default"; throws InputError
Ordering parse_ordering(const std::string& name);
std::string to_string(Ordering o);

struct CholeskyStats {
  double analyze_seconds = 0, factorize_seconds = 0, solve_seconds = 0;
  double factor_nonzeros = 0;  // nonzeros of L
  double flops = 0;            // of the numeric factorization
  double peak_bytes = 0;       // CHOLMOD's own peak memory
  int analyses = 0;            // symbolic analyses performed so far
  // Relative size (max norm) of the correction one step of iterative refinement made to the
  // last solution: it grows with cond(A) (measured on a Gram matrix: 1.7e-10 at cond 1.5e12,
  // 2.4e-9 at 1.6e14, 0.05 at 1.4e15), so it says how many digits the solution has.
  double refinement_correction = 0;
};

// Above this refinement correction the solution has fewer than ~2 correct digits: the
// matrix is numerically singular (e.g. nearly dependent basis functions), and solve throws.
constexpr double kNumericallySingularCorrection = 1e-2;

// SPD solve with SuiteSparse CHOLMOD's supernodal Cholesky, through Eigen's CholmodSupport.
// The matrix is given by its lower triangle. The symbolic analysis (ordering, elimination
// tree, supernodes) is kept and reused while the sparsity pattern stays the same.
class SparseCholesky {
 public:
  explicit SparseCholesky(Ordering ordering = Ordering::kAmd);  // kAuto: AMD
  ~SparseCholesky();
  // Throws std::runtime_error if the matrix is not positive definite.
  void factorize(const Eigen::SparseMatrix<double>& lower);
  // The solution after one step of iterative refinement (residual in double precision).
  // CHOLMOD factors a numerically singular matrix without complaint and returns a wrong
  // solution; the refinement step exposes it: throws std::runtime_error when its relative
  // correction exceeds kNumericallySingularCorrection.
  Eigen::VectorXd solve(const Eigen::VectorXd& b);
  // The pivots of the last factorization, L_kk^2 (= D_k of LDL^T), at the matrix's own row
  // numbering (the fill-reducing permutation undone).
  Eigen::VectorXd pivots() const;
  const CholeskyStats& stats() const { return stats_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  CholeskyStats stats_;
};

}  // namespace knotwork
