// Index arithmetic of dyadic knot vectors (hierarchical and LR families). Written here: no
// Debian library has hierarchical or LR B-splines, and storing every level's knot vector in
// full, as hierarchical codes usually do, cannot reach the 40 levels of a corner refinement.
#include "basis/core/dyadic_knots.hpp"

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>

#include "basis/core/bspline_basis.hpp"

namespace knotwork {

DyadicKnots::DyadicKnots(int degree, std::vector<double> breaks, std::vector<int> interior_multiplicity)
    : p_(degree), breaks_(std::move(breaks)) {
  if (p_ < 1) throw std::invalid_argument("degree must be at least 1");
  if (breaks_.size() < 2) throw std::invalid_argument("at least two breakpoints are needed");
  if (interior_multiplicity.size() + 2 != breaks_.size())
    throw std::invalid_argument("one multiplicity per interior breakpoint is needed");
  for (size_t i = 0; i + 1 < breaks_.size(); ++i)
    if (!(breaks_[i] < breaks_[i + 1])) throw std::invalid_argument("breakpoints must increase");
  multiplicity_.push_back(p_ + 1);
  extra_before_.push_back(0);
  for (int m : interior_multiplicity) {
    if (m < 1 || m > p_) throw std::invalid_argument("interior multiplicities must be in 1..degree");
    multiplicity_.push_back(m);
    extra_before_.push_back(extra_before_.back() + m - 1);
  }
  multiplicity_.push_back(p_ + 1);
  // Element indices stay below 2^46 (cell keys), and an element keeps ~4 significant digits
  // of its own width in double precision.
  while (max_level_ < 60 && elements(max_level_ + 1) < (int64_t(1) << 46) &&
         std::ldexp(breaks_[1] - breaks_[0], -(max_level_ + 1)) > 1e-12 * std::max(std::abs(breaks_.front()), std::abs(breaks_.back())))
    ++max_level_;
}

double DyadicKnots::breakpoint(int level, int64_t e) const {
  const int64_t j = e >> level;
  if (j >= base_elements()) return breaks_.back();
  const int64_t r = e - (j << level);
  return breaks_[j] + (breaks_[j + 1] - breaks_[j]) * std::ldexp(double(r), -level);
}

int DyadicKnots::multiplicity(int level, int64_t e) const {
  if ((e & ((int64_t(1) << level) - 1)) != 0) return 1;
  return multiplicity_[e >> level];
}

int64_t DyadicKnots::first_knot(int level, int64_t e) const {
  if (e == 0) return 0;
  const int64_t j = std::min<int64_t>(base_elements() - 1, (e - 1) >> level);
  return p_ + 1 + (e - 1) + extra_before_[j];
}

int64_t DyadicKnots::breakpoint_of_knot(int level, int64_t k) const {
  int64_t lo = 0, hi = elements(level);  // largest e with first_knot(e) <= k
  while (lo < hi) {
    const int64_t mid = lo + (hi - lo + 1) / 2;
    if (first_knot(level, mid) <= k) lo = mid;
    else hi = mid - 1;
  }
  return lo;
}

std::pair<int64_t, int64_t> DyadicKnots::support(int level, int64_t k) const {
  return {breakpoint_of_knot(level, k), breakpoint_of_knot(level, k + p_ + 1)};
}

std::vector<double> DyadicKnots::local_knots(int level, int64_t k) const {
  std::vector<double> t(p_ + 2);
  for (int i = 0; i <= p_ + 1; ++i) t[i] = breakpoint(level, breakpoint_of_knot(level, k + i));
  return t;
}

Eigen::MatrixXd DyadicKnots::extraction(int level, int64_t e) const {
  const int64_t f = first_function(level, e);
  const double a = breakpoint(level, e), b = breakpoint(level, e + 1);
  Eigen::MatrixXd C(p_ + 1, p_ + 1);
  for (int i = 0; i <= p_; ++i) C.row(i) = single_bspline_bernstein(local_knots(level, f + i), a, b).transpose();
  return C;
}

Eigen::MatrixXd DyadicKnots::refinement(int level, int64_t child) const {
  const int64_t parent = child >> 1;
  const int64_t f = first_function(level, parent);
  const double a = breakpoint(level + 1, child), b = breakpoint(level + 1, child + 1);
  Eigen::MatrixXd coarse(p_ + 1, p_ + 1);
  for (int i = 0; i <= p_; ++i) coarse.row(i) = single_bspline_bernstein(local_knots(level, f + i), a, b).transpose();
  // coarse = R * fine on the child element, fine invertible (a B-spline basis of the element).
  const Eigen::MatrixXd fine = extraction(level + 1, child);
  Eigen::MatrixXd R = fine.transpose().fullPivLu().solve(coarse.transpose()).transpose();
  // The exact entries are rationals of modest size; round-off zeros must stay zeros, since a
  // truncated function is dropped from a cell where all its coefficients vanish.
  for (int i = 0; i < R.size(); ++i)
    if (std::abs(R.data()[i]) < 1e-12) R.data()[i] = 0;
  return R;
}

}  // namespace knotwork
