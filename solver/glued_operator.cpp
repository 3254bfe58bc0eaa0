#include "solver/glued_operator.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "solver/sparsity.hpp"

namespace knotwork {

GluedPoissonOperator::GluedPoissonOperator(int num_functions, std::vector<std::unique_ptr<MatrixFreePoisson>> pieces,
                                           std::vector<std::vector<int>> global)
    : num_functions_(num_functions), pieces_(std::move(pieces)), global_(std::move(global)) {
  if (pieces_.size() != global_.size()) throw std::invalid_argument("GluedPoissonOperator: one numbering per piece expected");
  place_start_.assign(num_functions_ + 1, 0);
  int most = 0;
  for (size_t k = 0; k < pieces_.size(); ++k) {
    if (!pieces_[k] || pieces_[k]->num_functions() != int(global_[k].size()))
      throw std::invalid_argument("GluedPoissonOperator: a piece's numbering does not match its functions");
    for (int g : global_[k]) {
      if (g < -1 || g >= num_functions_) throw std::invalid_argument("GluedPoissonOperator: a function number out of range");
      if (g >= 0) ++place_start_[g + 1];
    }
    most = std::max(most, pieces_[k]->max_row_nonzeros());
  }
  int shared = 1;
  for (int f = 0; f < num_functions_; ++f) shared = std::max(shared, place_start_[f + 1]);
  max_row_nonzeros_ = most * shared;
  for (int f = 0; f < num_functions_; ++f) place_start_[f + 1] += place_start_[f];
  places_.resize(place_start_.back());
  std::vector<int> next(place_start_.begin(), place_start_.end() - 1);
  for (size_t k = 0; k < global_.size(); ++k)
    for (size_t f = 0; f < global_[k].size(); ++f)
      if (global_[k][f] >= 0) places_[next[global_[k][f]]++] = {int(k), int(f)};
}

void GluedPoissonOperator::apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  if (x.size() != num_functions_) throw std::invalid_argument("GluedPoissonOperator::apply: wrong vector size");
  y.setZero(num_functions_);
  Eigen::VectorXd xk, yk;
  for (size_t k = 0; k < pieces_.size(); ++k) {
    const std::vector<int>& g = global_[k];
    xk.resize(long(g.size()));
    for (size_t f = 0; f < g.size(); ++f) xk[long(f)] = g[f] >= 0 ? x[g[f]] : 0.0;
    pieces_[k]->apply(xk, yk);
    for (size_t f = 0; f < g.size(); ++f)
      if (g[f] >= 0) y[g[f]] += yk[long(f)];
  }
}

Eigen::VectorXd GluedPoissonOperator::diagonal() const {
  Eigen::VectorXd d = Eigen::VectorXd::Zero(num_functions_);
  for (size_t k = 0; k < pieces_.size(); ++k) {
    const Eigen::VectorXd dk = pieces_[k]->diagonal();
    for (size_t f = 0; f < global_[k].size(); ++f)
      if (global_[k][f] >= 0) d[global_[k][f]] += dk[long(f)];
  }
  return d;
}

Eigen::VectorXd GluedPoissonOperator::load(const Expression& source) const {
  Eigen::VectorXd F = Eigen::VectorXd::Zero(num_functions_);
  for (size_t k = 0; k < pieces_.size(); ++k) {
    const Eigen::VectorXd Fk = pieces_[k]->load(source);
    for (size_t f = 0; f < global_[k].size(); ++f)
      if (global_[k][f] >= 0) F[global_[k][f]] += Fk[long(f)];
  }
  return F;
}

bool GluedPoissonOperator::all_elements_affine() const {
  return std::all_of(pieces_.begin(), pieces_.end(), [](const auto& p) { return p->all_elements_affine(); });
}

bool GluedPoissonOperator::assembles_lower() const {
  return std::all_of(pieces_.begin(), pieces_.end(), [](const auto& p) { return p->assembles_lower(); }) && gives_pattern();
}

bool GluedPoissonOperator::gives_pattern() const {
  return std::all_of(pieces_.begin(), pieces_.end(), [](const auto& p) { return p->gives_pattern(); });
}

void GluedPoissonOperator::coupled_functions(int function, std::vector<int>& out) const {
  const size_t first = out.size();
  std::vector<int> coupled;
  for (int m = place_start_[function]; m < place_start_[function + 1]; ++m) {
    const auto [k, f] = places_[m];
    coupled.clear();
    pieces_[k]->coupled_functions(f, coupled);
    for (int h : coupled)
      if (global_[k][h] >= 0) out.push_back(global_[k][h]);
  }
  std::sort(out.begin() + long(first), out.end());
  out.erase(std::unique(out.begin() + long(first), out.end()), out.end());
}

const char* GluedPoissonOperator::assembly_method() const {
  for (const auto& p : pieces_)
    if (std::strcmp(p->assembly_method(), "kronecker_form") != 0) return p->assembly_method();
  return "kronecker_form";
}

Eigen::SparseMatrix<double> GluedPoissonOperator::lower_pattern(const DofLayout& layout) const {
  if (!gives_pattern()) throw std::logic_error("GluedPoissonOperator::lower_pattern: a piece does not give its couplings");
  if (static_cast<int>(layout.dof.size()) != num_functions_)
    throw std::logic_error("GluedPoissonOperator::lower_pattern: a layout of another space");
  // The pattern: column d's free rows at or after it, from each of its pieces' couplings (the
  // functions that share an element there), sorted and merged. Counted, then written.
  const int n = layout.num_free();
  Eigen::SparseMatrix<double> K(n, n);
  int* outer = K.outerIndexPtr();
  const auto rows_of = [&](int d, std::vector<int>& rows, std::vector<int>& coupled) {
    rows.clear();
    coupled.clear();
    coupled_functions(layout.function_of_dof[d], coupled);
    for (int h : coupled) {
      const int a = layout.dof[h];
      if (a >= d) rows.push_back(a);
    }
  };
  outer[0] = 0;
#pragma omp parallel
  {
    std::vector<int> rows, coupled;
#pragma omp for schedule(static)
    for (int d = 0; d < n; ++d) {
      rows_of(d, rows, coupled);
      outer[d + 1] = int(rows.size());
    }
  }
  for (int d = 0; d < n; ++d) outer[d + 1] += outer[d];
  K.resizeNonZeros(outer[n]);
  int* inner = K.innerIndexPtr();
  double* values = K.valuePtr();
#pragma omp parallel
  {
    std::vector<int> rows, coupled;
#pragma omp for schedule(static)
    for (int d = 0; d < n; ++d) {
      rows_of(d, rows, coupled);
      std::copy(rows.begin(), rows.end(), inner + outer[d]);
      std::fill(values + outer[d], values + outer[d + 1], 0.0);
    }
  }
  return K;
}

Eigen::SparseMatrix<double> GluedPoissonOperator::lower_matrix(const DofLayout& layout) const {
  if (!assembles_lower()) throw std::logic_error("GluedPoissonOperator::lower_matrix: a piece does not write its matrix");
  Eigen::SparseMatrix<double> K = lower_pattern(layout);
  const int* outer = K.outerIndexPtr();
  const int* inner = K.innerIndexPtr();
  double* values = K.valuePtr();
  // The values: each piece's written matrix over its free functions, added in. Pieces one after
  // another; a piece's columns in parallel, since its numbering is one-to-one (two of its lower
  // entries never land on one shared entry).
  for (size_t k = 0; k < pieces_.size(); ++k) {
    const std::vector<int>& g = global_[k];
    std::vector<bool> fixed(g.size());
    for (size_t f = 0; f < g.size(); ++f) fixed[f] = g[f] < 0 || layout.dof[g[f]] < 0;  // (not held: left out too)
    const DofLayout local = make_dof_layout(int(g.size()), fixed);
    const Eigen::SparseMatrix<double> Kk = pieces_[k]->lower_matrix(local);
    bool missing = false;
#pragma omp parallel for schedule(static) reduction(|| : missing)
    for (int c = 0; c < int(Kk.outerSize()); ++c) {
      const int b = layout.dof[g[local.function_of_dof[c]]];
      for (Eigen::SparseMatrix<double>::InnerIterator it(Kk, c); it; ++it) {
        const int a = layout.dof[g[local.function_of_dof[it.row()]]];
        const int column = std::min(a, b), row = std::max(a, b);
        const int* first = inner + outer[column];
        const int* last = inner + outer[column + 1];
        const int* at = std::lower_bound(first, last, row);
        if (at == last || *at != row) {
          missing = true;
          continue;
        }
        values[at - inner] += it.value();
      }
    }
    if (missing) throw std::logic_error("GluedPoissonOperator::lower_matrix: a piece's entry outside the couplings");
  }
  return K;
}

}  // namespace knotwork
