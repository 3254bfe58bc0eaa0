// BoomerAMG through PETSc, built as a module of its own (libknotwork_amg.so) that knotwork
// loads on first use (solver/amg_loader.cpp): PETSc brings some 85 shared libraries (MPI,
// hypre, MUMPS, HDF5, ...), whose loading tripled the start-up time of every run.
#include <petscksp.h>

// AddressSanitizer's builds (gcc defines the first, clang answers the second).
#if defined(__SANITIZE_ADDRESS__)
#define KNOTWORK_LSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define KNOTWORK_LSAN 1
#endif
#endif
#ifdef KNOTWORK_LSAN
#include <sanitizer/lsan_interface.h>
#endif

#include "solver/amg_preconditioner.hpp"

#include <cstdlib>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace knotwork {

namespace {

// PETSc's error code as an exception with PETSc's own message.
void check(PetscErrorCode code, const char* what) {
  if (code == 0) return;
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  throw std::runtime_error(std::string("PETSc: ") + what + ": " + (text ? text : "error " + std::to_string(code)));
}

// OpenMPI (under PETSc) allocates in MPI_Init, frees part of it in MPI_Finalize and unloads its
// components, so LeakSanitizer reports blocks whose stacks end in unloaded modules, which no
// suppression can name. They are not knotwork's: in the sanitizer build (docs/RELIABILITY.md)
// what PETSc's initialisation and finalisation allocate is not leak-checked; everything after
// it (matrices, preconditioners: knotwork's to free) is.
#ifdef KNOTWORK_LSAN
struct NoLeakCheck {
  NoLeakCheck() { __lsan_disable(); }
  ~NoLeakCheck() { __lsan_enable(); }
};
#else
struct NoLeakCheck {
  NoLeakCheck() {}  // user-provided: a guard object is not an unused variable
};
#endif

void initialize_petsc() {
  static std::once_flag once;
  std::call_once(once, [] {
    const NoLeakCheck third_party;
    // No signal handlers: Ctrl-C and crashes stay the program's (and Python's) to handle.
    check(PetscOptionsSetValue(nullptr, "-no_signal_handler", nullptr), "options");
    check(PetscInitializeNoArguments(), "initialization");
    // Errors come back as codes (and exceptions here) instead of tracebacks on stderr.
    check(PetscPushErrorHandler(PetscReturnErrorHandler, nullptr), "error handler");
    std::atexit([] {
      const NoLeakCheck finalization;
      PetscFinalize();
    });
  });
}

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
    apply_options(options);
    check(PCSetUp(pc_), "BoomerAMG setup");
    check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, n, nullptr, &in_), "vector");
    check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, n, nullptr, &out_), "vector");
  }

  // The user's options, prefixed so that they reach this preconditioner only; every one
  // must be used by it (PETSc itself ignores what nobody reads).
  void apply_options(const std::string& options) {
    std::istringstream words(options);
    std::vector<std::pair<std::string, std::string>> given;
    for (std::string w; words >> w;) {
      if (w.size() < 2 || w[0] != '-' || (w[1] >= '0' && w[1] <= '9')) {
        if (given.empty() || !given.back().second.empty())
          throw std::invalid_argument("\"" + w + "\" is not a PETSc option (options start with '-')");
        given.back().second = w;
      } else {
        given.emplace_back(w.substr(1), "");
      }
    }
    for (const auto& [name, value] : given)
      check(PetscOptionsSetValue(nullptr, ("-knotwork_" + name).c_str(), value.empty() ? nullptr : value.c_str()),
            "options");
    PetscErrorCode code;
    {
      // PETSc's option parsing returns from an error (a value it cannot read) without freeing
      // the strings PetscOptionsBegin allocated: PETSc's leak, on the path where knotwork
      // refuses the options anyway.
      const NoLeakCheck petsc_error_path;
      code = PCSetFromOptions(pc_);
    }
    std::string unused;
    for (const auto& [name, value] : given) {
      PetscBool used = PETSC_FALSE;
      // The database stores names without the dash, and this lookup compares them as stored.
      PetscOptionsUsed(nullptr, ("knotwork_" + name).c_str(), &used);
      if (!used) unused += (unused.empty() ? "-" : ", -") + name;
      PetscOptionsClearValue(nullptr, ("-knotwork_" + name).c_str());
    }
    if (code != 0) {
      const char* text = nullptr;
      PetscErrorMessage(code, &text, nullptr);
      throw std::invalid_argument(std::string("PETSc could not read them: ") + (text ? text : "error"));
    }
    if (!unused.empty())
      throw std::invalid_argument(unused + ": not an option of PETSc's hypre BoomerAMG preconditioner (see -help of "
                                           "PCHYPRE: -pc_hypre_boomeramg_strong_threshold, _coarsen_type, "
                                           "_relax_type_all, _max_levels, ...)");
  }

  Mat matrix_ = nullptr;
  PC pc_ = nullptr;
  Vec in_ = nullptr, out_ = nullptr;
};

}  // namespace

}  // namespace knotwork

// The module's one entry point, found by name (dlsym); C++ exceptions pass through it.
extern "C" __attribute__((visibility("default"))) knotwork::Preconditioner* knotwork_boomeramg(
    const Eigen::SparseMatrix<double>& lower, const std::string& petsc_options) {
  return new knotwork::BoomerAmg(lower, petsc_options);
}
