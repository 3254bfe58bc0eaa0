#pragma once
#include <array>
#include <memory>
#include <string>
#include <vector>

namespace knotwork {

// A scalar function of x, y and z (z = 0 in the plane) written by the user, e.g. "sin(pi*x)*exp(-y^2)".
// Operators + - * / ^, functions sin cos tan asin acos atan atan2 sinh cosh tanh
// exp log (natural) sqrt abs pow, constants pi and e.
class Expression {
 public:
  Expression() = default;
  // Checks the syntax; throws InputError("<where>: ... at position N") if it does not parse.
  // `where` names the file and field, e.g. "square.toml: [problem] exact".
  static Expression parse(const std::string& text, const std::string& where);
  static Expression constant(double value);
  const std::string& text() const { return text_; }
  const std::string& where() const { return where_; }
  bool empty() const { return text_.empty(); }

 private:
  std::string text_, where_;
};

// Evaluates one expression fast (compiled bytecode). Not thread-safe: make one per thread.
class ExpressionEvaluator {
 public:
  explicit ExpressionEvaluator(const Expression& e);
  ~ExpressionEvaluator();
  ExpressionEvaluator(ExpressionEvaluator&&) noexcept;
  double operator()(double x, double y);  // z = 0
  double operator()(double x, double y, double z);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Several expressions at many points at once (the exact solution and its gradient at a
// cell's quadrature points): compiled once into one program over arrays of points in which a
// subexpression common to several of them (sin(pi*x) in u, u_x and u_y) is computed once,
// with no interpretation per point. Built from GiNaC's reading of each text, checked against
// muParser's at a few points; an expression GiNaC does not read (or reads with another
// meaning) is evaluated by muParser, point by point. Not thread-safe: construct it once
// (GiNaC is not thread-safe either) and give every thread its own copy.
class ExpressionBatch {
 public:
  explicit ExpressionBatch(const std::vector<Expression>& expressions);
  ExpressionBatch(const ExpressionBatch& other);
  ~ExpressionBatch();
  ExpressionBatch(ExpressionBatch&&) noexcept;
  // Evaluates every expression at (x[k], y[k], z[k]), k < n; z may be null (z = 0).
  void evaluate(const double* x, const double* y, const double* z, long n);
  // Expression e at the points of the last evaluate().
  const double* result(int e) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// u and what the solver needs from it, derived symbolically (GiNaC) so that nobody
// differentiates by hand. In the plane: -(u_xx + u_yy) for the source, u_x and u_y for norms
// and fluxes. On a surface in R^3: the ambient gradient (u_x, u_y, u_z) and Hessian, from
// which the surface operators follow on the discrete surface (solver/assemble_poisson).
struct ExactSolution {
  Expression u, u_x, u_y, minus_laplacian;
  Expression u_z;                                    // surfaces only
  std::array<std::array<Expression, 3>, 3> hessian;  // surfaces only
  bool on_surface() const { return !u_z.empty(); }
};
// Throws InputError if u cannot be differentiated (unknown function, non-smooth parts GiNaC
// rejects). The derived expressions are checked against GiNaC's own evaluation.
ExactSolution differentiate_exact_solution(const Expression& u);
// f = -div(A grad u) + c u in the plane, symbolically: A is the identity (no entries), a I (one)
// or [[a11, a12], [a12, a22]] (three: a11, a12, a22); c is `reaction` when given, else the
// constant. Throws InputError naming the field that cannot be read or differentiated.
Expression derive_general_source(const Expression& u, const std::vector<Expression>& diffusion,
                                  const Expression& reaction, double constant_reaction);
// The same for a function of (x, y, z) restricted to a surface (u_z and the Hessian; no
// minus_laplacian, which depends on the surface).
ExactSolution differentiate_surface_solution(const Expression& u);

}  // namespace knotwork
