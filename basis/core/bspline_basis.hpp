#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <span>
#include <vector>

namespace knotwork {

// Univariate B-spline basis of degree p on a knot vector with multiplicities.
// The domain is [knots[p], knots[n]] with n = number of functions.
// The constructor validates the knot vector and throws std::invalid_argument with
// a message that says what is wrong (callers add the file and field).
class BSplineBasis1D {
 public:
  BSplineBasis1D() = default;
  BSplineBasis1D(int degree, std::vector<double> knots);

  // Open (clamped) knot vector on [a,b] with `elements` equal spans, each interior
  // knot repeated `multiplicity` times.
  static BSplineBasis1D open_uniform(int degree, double a, double b, int elements,
                                     int multiplicity = 1);

  int degree() const { return p_; }
  const std::vector<double>& knots() const { return knots_; }
  int num_functions() const { return static_cast<int>(knots_.size()) - p_ - 1; }
  double domain_begin() const { return knots_[p_]; }
  double domain_end() const { return knots_[num_functions()]; }
  bool is_open() const;  // end knots repeated p+1 times

  // Index s with knots[s] <= t < knots[s+1] and a non-empty span; t at the right end
  // of the domain belongs to the last span. Functions s-p..s are alive there.
  int find_span(double t) const;
  // Values of N_{s-p..s} at t (p+1 numbers).
  void evaluate(int span, double t, double* values) const;
  // Derivatives of order 0..order of N_{s-p..s}: out is (order+1) x (p+1), row-major.
  void evaluate_derivatives(int span, double t, int order, double* out) const;

  // Distinct knot values in the domain, and their multiplicities.
  std::vector<double> breakpoints() const;
  std::vector<int> multiplicities() const;
  // Span index of every element (non-empty knot span) in the domain, left to right.
  std::vector<int> element_spans() const;
  int num_elements() const { return static_cast<int>(element_spans().size()); }

 private:
  int p_ = 0;
  std::vector<double> knots_;
};

// The Greville abscissae xi_i = (t_{i+1} + ... + t_{i+p}) / p of the functions of degree p >= 1
// over `knots` (p + 1 + n knots for n functions): the affine function a + b t has the
// coefficients a + b xi_i (linear precision).
std::vector<double> greville_abscissae(const std::vector<double>& knots, int degree);
inline std::vector<double> greville_abscissae(const BSplineBasis1D& basis) {
  return greville_abscissae(basis.knots(), basis.degree());
}

// The functions first .. first + count - 1 of `basis` alone, on their own knots (unclamped
// where they stop short of the ends). Its domain is the elements on which only those
// functions live, where they are the same functions as in `basis`: a process's rows of a
// tensor patch (its matrix rows then come from its elements alone). Throws
// std::invalid_argument when the range is outside the basis or spans no element.
BSplineBasis1D consecutive_functions(const BSplineBasis1D& basis, int first, int count);

// Value at t of the spline with the given coefficients (de Boor's algorithm).
double de_boor(const BSplineBasis1D& basis, std::span<const double> coefficients, double t);

// Boehm's algorithm: insert t once. Coefficients are n x dim (one control point per row).
// Returns the refined basis; `coefficients` is replaced by the refined ones.
BSplineBasis1D insert_knot(const BSplineBasis1D& basis, Eigen::MatrixXd& coefficients, double t);

// The basis of degree p+r with every distinct knot's multiplicity raised by r
// (the same continuity everywhere), i.e. the degree-elevated space.
BSplineBasis1D elevated_basis(const BSplineBasis1D& basis, int r);
// Degree elevation of a spline: returns the elevated basis; coefficients replaced.
BSplineBasis1D elevate_degree(const BSplineBasis1D& basis, Eigen::MatrixXd& coefficients, int r);

// The matrix T (fine.num_functions() x coarse.num_functions()) with c_fine = T c_coarse
// for every spline in the coarse space. The fine space must contain the coarse one
// (same domain, degree >= coarse degree, every coarse knot present with enough
// multiplicity); otherwise throws std::invalid_argument.
// Works element by element through Bezier extraction, subdivision and degree elevation.
Eigen::SparseMatrix<double> refinement_matrix(const BSplineBasis1D& coarse,
                                              const BSplineBasis1D& fine);

// Bezier extraction operator of every element: rows are the p+1 functions alive on the
// element (span-p..span), columns the Bernstein polynomials of the element:
// N_active = C_e * B. Computed by local Boehm insertion, exact up to roundoff.
std::vector<Eigen::MatrixXd> bezier_extraction(const BSplineBasis1D& basis);

}  // namespace knotwork

namespace knotwork {
// Bernstein coefficients, on [a, b], of the single B-spline of degree knots.size()-2 with
// the given knots (zero vector when [a, b] is outside its support). [a, b] must lie inside
// one knot span. Exact up to roundoff: blossoms of the piece at a and b (de Boor).
Eigen::VectorXd single_bspline_bernstein(std::span<const double> knots, double a, double b);
}  // namespace knotwork
