// Written here: PETSc's PCMG would take the levels, but not a smoother restricted to the
// functions a step changed, and knotwork's CG runs serially without PETSc.
#include "solver/nested_multigrid.hpp"

#include <Eigen/SparseCholesky>
#include <cmath>
#include <stdexcept>
#include <string>

namespace knotwork {

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

struct NestedMultigrid::Level {
  // The rows of the symmetric matrix over the level's free dofs that the cycle reads: those of
  // the smoothed dofs (row k is dof smoothed[k]'s), whole. The others are never read: a level
  // keeps about 40% of its matrix (docs/ADAPTIVITY.md).
  RowMatrix A;
  Eigen::VectorXd inverse_diagonal;  // 1 / A_ii of the smoothed dofs
  RowMatrix P;                       // free dofs of this level x free dofs of the coarser one
  std::vector<int> smoothed;         // the dofs the step changed, in increasing order
  std::shared_ptr<const Level> coarser;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> coarsest;  // the first level's factor
};

namespace {

// The V-cycle on `level` for residual r: e ~ A^-1 r.
void v_cycle(const NestedMultigrid::Level& L, const Eigen::VectorXd& r, Eigen::VectorXd& e) {
  if (!L.coarser) {
    e = L.coarsest.solve(r);
    return;
  }
  const RowMatrix& A = L.A;
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* value = A.valuePtr();
  const int m = static_cast<int>(L.smoothed.size());
  e.setZero(r.size());
  // Forward Gauss-Seidel over the changed dofs, from e = 0.
  for (int row = 0; row < m; ++row) {
    const int i = L.smoothed[row];
    double s = r[i];
    for (int k = outer[row]; k < outer[row + 1]; ++k) s -= value[k] * e[inner[k]];
    e[i] += s * L.inverse_diagonal[row];
  }
  // The residual r - A e, where e lives on the smoothed dofs only (A symmetric: their rows).
  Eigen::VectorXd rest = r;
  for (int row = 0; row < m; ++row) {
    const double ei = e[L.smoothed[row]];
    for (int k = outer[row]; k < outer[row + 1]; ++k) rest[inner[k]] -= value[k] * ei;
  }
  Eigen::VectorXd coarse_e;
  v_cycle(*L.coarser, L.P.transpose() * rest, coarse_e);
  e.noalias() += L.P * coarse_e;
  // Backward Gauss-Seidel over the same dofs, in reverse order: the cycle is symmetric.
  for (int row = m - 1; row >= 0; --row) {
    const int i = L.smoothed[row];
    double s = r[i];
    for (int k = outer[row]; k < outer[row + 1]; ++k) s -= value[k] * e[inner[k]];
    e[i] += s * L.inverse_diagonal[row];
  }
}

class NestedVCycle final : public Preconditioner {
 public:
  explicit NestedVCycle(std::shared_ptr<const NestedMultigrid::Level> finest) : finest_(std::move(finest)) {}
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override { v_cycle(*finest_, r, z); }

 private:
  std::shared_ptr<const NestedMultigrid::Level> finest_;
};

}  // namespace

NestedMultigrid::NestedMultigrid() = default;
NestedMultigrid::~NestedMultigrid() = default;

int NestedMultigrid::levels() const { return static_cast<int>(levels_.size()); }

void NestedMultigrid::add_level(const DofLayout& layout, const Eigen::SparseMatrix<double>& lower,
                                const Eigen::SparseMatrix<double>* prolongation) {
  const int n = layout.num_free();
  if (lower.rows() != n || lower.cols() != n)
    throw std::invalid_argument("nested multigrid: a matrix of " + std::to_string(lower.rows()) + " rows for " + std::to_string(n) +
                                " free dofs");
  auto level = std::make_shared<Level>();
  if (!levels_.empty() && !prolongation) throw std::invalid_argument("nested multigrid: a finer level needs its prolongation");
  if (levels_.empty()) {
    level->coarsest.compute(lower.selfadjointView<Eigen::Lower>());
    if (level->coarsest.info() != Eigen::Success)
      throw std::runtime_error("nested multigrid: the starting space's matrix is not positive definite");
  } else {
    const Eigen::SparseMatrix<double>& Pall = *prolongation;
    if (Pall.rows() != static_cast<Eigen::Index>(layout.dof.size()) ||
        Pall.cols() != static_cast<Eigen::Index>(last_layout_.dof.size()))
      throw std::invalid_argument("nested multigrid: a prolongation of " + std::to_string(Pall.rows()) + " x " +
                                  std::to_string(Pall.cols()) + " between spaces of " + std::to_string(layout.dof.size()) +
                                  " and " + std::to_string(last_layout_.dof.size()) + " functions");
    // P over the free dofs, and which dofs the step changed: a dof is unchanged when its row is a
    // single 1 in a column that has no other entry (the same function before and after).
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(Pall.nonZeros());
    std::vector<int> row_count(n, 0), column_count(last_layout_.num_free(), 0);
    std::vector<int> row_column(n, -1);
    std::vector<double> row_value(n, 0);
    for (int col = 0; col < Pall.outerSize(); ++col) {
      const int c = last_layout_.dof[col];
      if (c < 0) continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(Pall, col); it; ++it) {
        const int r = layout.dof[it.row()];
        if (r < 0) continue;  // a fixed function of this step: no part of a free one (to rounding)
        entries.emplace_back(r, c, it.value());
        ++row_count[r];
        ++column_count[c];
        row_column[r] = c;
        row_value[r] = it.value();
      }
    }
    level->P.resize(n, last_layout_.num_free());
    level->P.setFromTriplets(entries.begin(), entries.end());
    for (int r = 0; r < n; ++r) {
      const bool unchanged = row_count[r] == 1 && column_count[row_column[r]] == 1 && std::abs(row_value[r] - 1) <= 1e-12;
      if (!unchanged) level->smoothed.push_back(r);
    }
    // The smoothed rows of the whole matrix, copied from it made once.
    {
      const RowMatrix whole = lower.selfadjointView<Eigen::Lower>();
      const int m = static_cast<int>(level->smoothed.size());
      Eigen::Index entries_kept = 0;
      for (int i : level->smoothed) entries_kept += whole.outerIndexPtr()[i + 1] - whole.outerIndexPtr()[i];
      level->A.resize(m, n);
      level->A.reserve(entries_kept);
      level->inverse_diagonal.resize(m);
      for (int row = 0; row < m; ++row) {
        const int i = level->smoothed[row];
        level->A.startVec(row);
        double diagonal = 0;
        for (RowMatrix::InnerIterator it(whole, i); it; ++it) {
          level->A.insertBack(row, it.col()) = it.value();
          if (it.col() == i) diagonal = it.value();
        }
        if (!(diagonal > 0)) throw std::runtime_error("nested multigrid: a matrix with a diagonal entry that is not positive");
        level->inverse_diagonal[row] = 1 / diagonal;
      }
      level->A.finalize();
    }
    level->coarser = levels_.back();
  }
  levels_.push_back(std::move(level));
  last_layout_ = layout;
}

std::unique_ptr<Preconditioner> NestedMultigrid::preconditioner() const {
  if (levels_.empty()) throw std::logic_error("nested multigrid: no level");
  return std::make_unique<NestedVCycle>(levels_.back());
}

}  // namespace knotwork
