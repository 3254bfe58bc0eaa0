#pragma once
// One parameter direction of a dyadic hierarchy: level 0 is an open knot vector given by its
// breakpoints and interior multiplicities; level l halves every element l times with simple
// knots. Everything is computed from indices on demand, so a level of 2^30 elements costs
// nothing until one of its elements is asked for (adaptive meshes reach 30+ levels at a
// corner and touch a handful of elements there).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace knotwork {

class DyadicKnots {
 public:
  // `breaks`: the level-0 breakpoints (increasing, at least two); `interior_multiplicity`:
  // one per interior breakpoint, in 1..degree. Ends are repeated degree+1 times.
  DyadicKnots(int degree, std::vector<double> breaks, std::vector<int> interior_multiplicity);

  int degree() const { return p_; }
  // The finest level whose element indices still fit the cell keys (31 bits).
  int max_level() const { return max_level_; }
  int64_t elements(int level) const { return int64_t(base_elements()) << level; }
  int base_elements() const { return static_cast<int>(breaks_.size()) - 1; }
  // Breakpoint e in 0..elements(level), and how often it is repeated in the knot vector.
  double breakpoint(int level, int64_t e) const;
  int multiplicity(int level, int64_t e) const;
  int64_t num_functions(int level) const { return first_knot(level, elements(level)); }
  // The first of the degree+1 functions that do not vanish on element e.
  int64_t first_function(int level, int64_t e) const { return first_knot(level, e) + multiplicity(level, e) - 1 - p_; }
  // The elements [first, last) the function k lives on.
  std::pair<int64_t, int64_t> support(int level, int64_t k) const;
  // Its degree+2 local knots.
  std::vector<double> local_knots(int level, int64_t k) const;
  // Rows: the degree+1 functions first_function(level, e).. ; columns: the Bernstein
  // polynomials of element e.
  Eigen::MatrixXd extraction(int level, int64_t e) const;
  // The degree+1 functions of element e at `level` as combinations of the degree+1
  // functions of its child element `child` (2e or 2e+1) at level+1: row a, column a'.
  Eigen::MatrixXd refinement(int level, int64_t child) const;

 private:
  int64_t first_knot(int level, int64_t e) const;  // index of the first copy of breakpoint e
  int64_t breakpoint_of_knot(int level, int64_t k) const;

  int p_;
  std::vector<double> breaks_;
  std::vector<int> multiplicity_;     // per level-0 breakpoint, ends included (degree+1)
  std::vector<int64_t> extra_before_;  // sum of (multiplicity - 1) of interior base breakpoints 1..j
  int max_level_ = 0;
};

}  // namespace knotwork
