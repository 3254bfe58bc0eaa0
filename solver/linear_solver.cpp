#include "solver/linear_solver.hpp"

#include <Eigen/CholmodSupport>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "basis/core/input_error.hpp"

namespace knotwork {

Ordering parse_ordering(const std::string& name) {
  if (name == "auto") return Ordering::kAuto;
  if (name == "amd") return Ordering::kAmd;
  if (name == "metis") return Ordering::kMetis;
  if (name == "nesdis") return Ordering::kNesdis;
  if (name == "default") return Ordering::kCholmodDefault;
  throw InputError("--ordering: unknown value '" + name + "' (expected auto, amd, metis, nesdis or default)");
}

std::string to_string(Ordering o) {
  switch (o) {
    case Ordering::kAmd: return "amd";
    case Ordering::kMetis: return "metis";
    case Ordering::kNesdis: return "nesdis";
    case Ordering::kAuto: return "auto";
    default: return "default";
  }
}

namespace {
// Eigen's supernodal LL^T with its CHOLMOD factor in view, for the pivots.
struct SupernodalLlt : Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
  const cholmod_factor* factor() const { return m_cholmodFactor; }
};
}  // namespace

struct SparseCholesky::Impl {
  SupernodalLlt llt;
  std::vector<int> outer, inner;  // pattern of the last analysis
  Eigen::SparseMatrix<double> lower;  // the last matrix factored, for the residual
};

SparseCholesky::SparseCholesky(Ordering ordering) : impl_(std::make_unique<Impl>()) {
  cholmod_common& cm = impl_->llt.cholmod();
  if (ordering == Ordering::kCholmodDefault) return;
  cm.nmethods = 1;  // one ordering, chosen by measurement (docs/PERFORMANCE.md), not CHOLMOD's try-several default
  cm.method[0].ordering = ordering == Ordering::kAmd || ordering == Ordering::kAuto ? CHOLMOD_AMD
                          : ordering == Ordering::kMetis ? CHOLMOD_METIS
                                                         : CHOLMOD_NESDIS;
  cm.postorder = 1;
}

SparseCholesky::~SparseCholesky() = default;

void SparseCholesky::factorize(const Eigen::SparseMatrix<double>& A) {
  using clock = std::chrono::steady_clock;
  const int n = static_cast<int>(A.outerSize());
  const bool same = impl_->outer.size() == static_cast<size_t>(n + 1) &&
                    std::equal(impl_->outer.begin(), impl_->outer.end(), A.outerIndexPtr()) &&
                    impl_->inner.size() == static_cast<size_t>(A.nonZeros()) &&
                    std::equal(impl_->inner.begin(), impl_->inner.end(), A.innerIndexPtr());
  if (!same) {
    const auto t0 = clock::now();
    impl_->llt.analyzePattern(A);
    stats_.analyze_seconds = std::chrono::duration<double>(clock::now() - t0).count();
    stats_.analyses += 1;
    impl_->outer.assign(A.outerIndexPtr(), A.outerIndexPtr() + n + 1);
    impl_->inner.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
  } else {
    stats_.analyze_seconds = 0;
  }
  const auto t1 = clock::now();
  impl_->llt.factorize(A);
  impl_->lower = A;
  stats_.factorize_seconds = std::chrono::duration<double>(clock::now() - t1).count();
  const cholmod_common& cm = impl_->llt.cholmod();
  if (cm.status == CHOLMOD_OUT_OF_MEMORY || cm.status == CHOLMOD_TOO_LARGE)
    throw std::bad_alloc();
  if (impl_->llt.info() != Eigen::Success)
    throw std::runtime_error(
        "the stiffness matrix is not positive definite: CHOLMOD could not factor it "
        "(a problem without Dirichlet conditions has no unique solution, nor one on linearly dependent functions: "
        "--solver iterative solves a consistent singular system)");
  stats_.factor_nonzeros = cm.lnz;
  stats_.flops = cm.fl;
  stats_.peak_bytes = static_cast<double>(cm.memory_usage);
}

Eigen::VectorXd SparseCholesky::pivots() const {
  const cholmod_factor* L = impl_->llt.factor();
  if (!L || !L->is_super || !L->is_ll) throw std::logic_error("SparseCholesky::pivots: no supernodal LL^T factor");
  const auto* super = static_cast<const int*>(L->super);
  const auto* pi = static_cast<const int*>(L->pi);
  const auto* px = static_cast<const int*>(L->px);
  const auto* perm = static_cast<const int*>(L->Perm);
  const auto* x = static_cast<const double*>(L->x);
  Eigen::VectorXd d(static_cast<Eigen::Index>(L->n));
  // Supernode s holds columns super[s] .. super[s + 1] - 1 as one dense column-major block of
  // pi[s + 1] - pi[s] rows at x + px[s], its diagonal first.
  for (size_t s = 0; s < L->nsuper; ++s) {
    const int columns = super[s + 1] - super[s], rows = pi[s + 1] - pi[s];
    for (int j = 0; j < columns; ++j) {
      const double l = x[px[s] + static_cast<long>(j) * (rows + 1)];
      d[perm ? perm[super[s] + j] : super[s] + j] = l * l;
    }
  }
  return d;
}

Eigen::VectorXd SparseCholesky::solve(const Eigen::VectorXd& b) {
  const auto t0 = std::chrono::steady_clock::now();
  Eigen::VectorXd x = impl_->llt.solve(b);
  const Eigen::VectorXd r = b - impl_->lower.selfadjointView<Eigen::Lower>() * x;
  const Eigen::VectorXd dx = impl_->llt.solve(r);
  x += dx;
  const double size = x.lpNorm<Eigen::Infinity>();
  stats_.refinement_correction = size > 0 ? dx.lpNorm<Eigen::Infinity>() / size : 0;
  stats_.solve_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!(stats_.refinement_correction <= kNumericallySingularCorrection)) {
    char text[96];
    std::snprintf(text, sizeof text, "%.1e", stats_.refinement_correction);
    throw std::runtime_error(std::string("the matrix is numerically singular: one step of iterative "
                                         "refinement changed the solution by ") +
                             text + " (relative), so it cannot be trusted (nearly dependent basis functions?)");
  }
  return x;
}

}  // namespace knotwork
