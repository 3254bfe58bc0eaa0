// BoomerAMG through PETSc as the preconditioner of knotwork's own CG, in the PETSc module
// (libknotwork_petsc.so, solver/petsc_module.hpp) that knotwork loads on first use.
#include <petscksp.h>

#include "solver/amg_preconditioner.hpp"
#include "solver/petsc_common.hpp"

#include <cstdlib>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace knotwork {

namespace {

class BoomerAmg final : public Preconditioner {
 public:
  BoomerAmg(const Eigen::SparseMatrix<double>& lower, const std::string& options) {
    try {
      build(lower, options);
    } catch (...) {  // a refused option or a PETSc error: what was made is freed (no destructor runs)
      release();
      throw;
    }
  }
  ~BoomerAmg() override { release(); }
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override {
    z.resize(r.size());
    check(VecPlaceArray(in_, r.data()), "vector");
    check(VecPlaceArray(out_, z.data()), "vector");
    const PetscErrorCode code = PCApply(pc_, in_, out_);
    VecResetArray(in_);
    VecResetArray(out_);
    check(code, "BoomerAMG");
  }

 private:
  void release() {
    VecDestroy(&in_);
    VecDestroy(&out_);
    PCDestroy(&pc_);
    MatDestroy(&matrix_);
  }

  void build(const Eigen::SparseMatrix<double>& lower, const std::string& options) {
    initialize_petsc();
    const PetscInt n = lower.rows();
    // The full matrix, row by row (PETSc's AIJ is CSR): the lower triangle and its mirror.
    std::vector<PetscInt> count(n, 0);
    for (Eigen::Index j = 0; j < lower.outerSize(); ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(lower, j); it; ++it) {
        ++count[it.row()];
        if (it.row() != j) ++count[j];
      }
    std::vector<PetscInt> row_start(n + 1, 0);
    for (PetscInt i = 0; i < n; ++i) row_start[i + 1] = row_start[i] + count[i];
    std::vector<PetscInt> column(row_start[n]);
    std::vector<PetscScalar> value(row_start[n]);
    std::vector<PetscInt> next(row_start.begin(), row_start.end() - 1);
    // Columns in increasing order in each row: column j's entries (rows i >= j) go to row i
    // at column j, visited in increasing j; the mirrored ones of column j go to row j after.
    for (Eigen::Index j = 0; j < lower.outerSize(); ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(lower, j); it; ++it) {
        const PetscInt i = it.row();
        column[next[i]] = j, value[next[i]++] = it.value();
        if (i != j) column[next[j]] = i, value[next[j]++] = it.value();
      }
    check(MatCreate(PETSC_COMM_SELF, &matrix_), "matrix");
    check(MatSetSizes(matrix_, n, n, n, n), "matrix");
    check(MatSetType(matrix_, MATSEQAIJ), "matrix");
    check(MatSeqAIJSetPreallocationCSR(matrix_, row_start.data(), column.data(), value.data()), "matrix values");
    check(PCCreate(PETSC_COMM_SELF, &pc_), "preconditioner");
    check(PCSetType(pc_, PCHYPRE), "PCHYPRE");
    check(PCHYPRESetType(pc_, "boomeramg"), "BoomerAMG");
    check(PCSetOperators(pc_, matrix_, matrix_), "operators");
    check(PCSetOptionsPrefix(pc_, "knotwork_"), "options prefix");
    const ScopedOptions given("knotwork_", options);
    given.read([&] { return PCSetFromOptions(pc_); });
    if (const std::string unused = given.unused(); !unused.empty())
      throw std::invalid_argument(unused + ": not an option of PETSc's hypre BoomerAMG preconditioner (see -help of "
                                           "PCHYPRE: -pc_hypre_boomeramg_strong_threshold, _coarsen_type, "
                                           "_relax_type_all, _max_levels, ...)");
    check(PCSetUp(pc_), "BoomerAMG setup");
    check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, n, nullptr, &in_), "vector");
    check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, n, nullptr, &out_), "vector");
  }

  Mat matrix_ = nullptr;
  PC pc_ = nullptr;
  Vec in_ = nullptr, out_ = nullptr;
};

}  // namespace

Preconditioner* make_boomeramg(const Eigen::SparseMatrix<double>& lower, const std::string& petsc_options) {
  return new BoomerAmg(lower, petsc_options);
}

}  // namespace knotwork
