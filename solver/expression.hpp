#pragma once
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace knotwork {

namespace expression_detail {
struct Node;
struct CompiledExpression;
}  // namespace expression_detail

// A scalar function of x, y and z (z = 0 in the plane) written by the user, e.g.
// "sin(pi*x)*exp(-y^2)". The grammar, read once into a tree (solver/expression_tree.hpp):
//   numbers    2, 0.5, .5, 1e-3, 2.5E+4
//   variables  x y z;  constants pi e
//   operators  + - * / ^, with ^ binding tightest and to the right: 2^3^2 = 2^9, -x^2 = -(x^2),
//              2^-1*3 = (2^-1)*3; no implicit products (2*x, not 2x)
//   functions  sin cos tan asin acos atan atan2(y, x) sinh cosh tanh exp log (natural) sqrt
//              abs pow(a, b)
// The same tree is differentiated (GiNaC) and evaluated (a compiled program), so the source
// derived from an exact solution and the solution itself are the same function.
// A function the caller gives instead of a formula (a Python callable): values at n points,
// z null in the plane. It is evaluated in batches, never differentiated: what would be derived
// from it must be given too.
using ExternalFunction = std::function<void(const double* x, const double* y, const double* z, long n, double* out)>;

// While one is alive on this thread, a bare name it holds stands for its function in the texts
// Expression::parse reads (the Python module puts a placeholder name where a dict case has a
// callable, then reads the case as usual).
class ExternalFunctionNames {
 public:
  ExternalFunctionNames();
  ~ExternalFunctionNames();
  ExternalFunctionNames(const ExternalFunctionNames&) = delete;
  ExternalFunctionNames& operator=(const ExternalFunctionNames&) = delete;
  // A fresh name for f (python_function_<k>).
  std::string add(std::shared_ptr<const ExternalFunction> f);
  // The function of a name, or null.
  static std::shared_ptr<const ExternalFunction> find(const std::string& name);
};

class Expression {
 public:
  Expression() = default;
  // Reads text; throws InputError("<where>: cannot parse \"...\": ... at character N").
  // `where` names the file and field, e.g. "square.toml: [problem] exact".
  static Expression parse(const std::string& text, const std::string& where);
  static Expression constant(double value);
  // A function given by the caller; `text` describes it in messages.
  static Expression external(std::shared_ptr<const ExternalFunction> f, const std::string& text,
                             const std::string& where);
  const std::string& text() const { return text_; }
  const std::string& where() const { return where_; }
  bool empty() const { return text_.empty(); }

  // Internal (solver/expression*.cpp): the tree and its program.
  const expression_detail::Node& tree() const { return *tree_; }
  const std::shared_ptr<const expression_detail::CompiledExpression>& compiled() const { return compiled_; }
  static Expression from_tree(std::string text, std::string where, std::shared_ptr<const expression_detail::Node> tree);

 private:
  std::string text_, where_;
  std::shared_ptr<const expression_detail::Node> tree_;
  std::shared_ptr<const expression_detail::CompiledExpression> compiled_;
};

// Evaluates one expression at one point (its compiled program). Not thread-safe: make one per
// thread; making one is cheap (no parsing, no GiNaC).
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
// cell's quadrature points): their programs merged into one over arrays of points in which a
// subexpression common to several of them (sin(pi*x) in u, u_x and u_y) is computed once,
// with no interpretation per point. Not thread-safe: give every thread its own copy.
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
// which the surface operators follow on the discrete surface (solver/assemble_poisson). In a
// volume: the gradient (u_x, u_y, u_z) and -(u_xx + u_yy + u_zz).
struct ExactSolution {
  Expression u, u_x, u_y, minus_laplacian;
  Expression u_z;                                    // surfaces and volumes
  std::array<std::array<Expression, 3>, 3> hessian;  // surfaces only
  bool on_surface() const { return !u_z.empty(); }
};
// Throws InputError if u cannot be differentiated (constant powers exact arithmetic cannot
// afford, functions whose derivatives leave the grammar) or if a derived expression in double
// precision differs from GiNaC's exact value at a check point (constants beyond 2^53).
ExactSolution differentiate_exact_solution(const Expression& u);
// f = -div(A grad u) + c u in the plane (dimension 2) or in space (3), symbolically: A is the
// identity (no entries), a I (one) or the symmetric matrix of the upper triangle's entries row by
// row (three: a11, a12, a22; six: a11, a12, a13, a22, a23, a33); c is `reaction` when given, else
// the constant. Throws InputError naming the field that cannot be read or differentiated.
Expression derive_general_source(const Expression& u, const std::vector<Expression>& diffusion,
                                  const Expression& reaction, double constant_reaction, int dimension = 2);
// The same for a function of (x, y, z) restricted to a surface (u_z and the Hessian; no
// minus_laplacian, which depends on the surface).
ExactSolution differentiate_surface_solution(const Expression& u);
// In a volume: u_x, u_y, u_z and -(u_xx + u_yy + u_zz) of u(x, y, z).
ExactSolution differentiate_volume_solution(const Expression& u);

}  // namespace knotwork
