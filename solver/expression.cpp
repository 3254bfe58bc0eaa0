#include "solver/expression.hpp"

#include <ginac/ginac.h>
#include <muParser.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

#include "solver/input_error.hpp"

namespace knotwork {

namespace {

double pow_function(double a, double b) { return std::pow(a, b); }
double atan2_function(double a, double b) { return std::atan2(a, b); }
double natural_log(double a) { return std::log(a); }

void configure(mu::Parser& p, double* x, double* y, double* z) {
  p.DefineVar("x", x);
  p.DefineVar("y", y);
  p.DefineVar("z", z);
  p.DefineConst("pi", std::numbers::pi);
  p.DefineConst("Pi", std::numbers::pi);  // GiNaC prints pi this way
  p.DefineConst("e", std::numbers::e);
  p.DefineFun("pow", pow_function);
  p.DefineFun("atan2", atan2_function);
  p.DefineFun("log", natural_log);  // muParser's own log is base 10; users mean ln
}

}  // namespace

struct ExpressionEvaluator::Impl {
  double x = 0, y = 0, z = 0;
  mu::Parser parser;
};

ExpressionEvaluator::ExpressionEvaluator(const Expression& e) : impl_(std::make_unique<Impl>()) {
  configure(impl_->parser, &impl_->x, &impl_->y, &impl_->z);
  impl_->parser.SetExpr(e.text());
}
ExpressionEvaluator::~ExpressionEvaluator() = default;
ExpressionEvaluator::ExpressionEvaluator(ExpressionEvaluator&&) noexcept = default;

double ExpressionEvaluator::operator()(double x, double y) { return (*this)(x, y, 0.0); }

double ExpressionEvaluator::operator()(double x, double y, double z) {
  impl_->x = x;
  impl_->y = y;
  impl_->z = z;
  return impl_->parser.Eval();
}

Expression Expression::parse(const std::string& text, const std::string& where) {
  if (text.find_first_not_of(" \t") == std::string::npos)
    throw InputError(where + ": expression is empty");
  double x = 0.31, y = 0.47, z = 0.23;
  mu::Parser p;
  configure(p, &x, &y, &z);
  try {
    p.SetExpr(text);
    p.Eval();  // muParser reports most syntax errors only on first evaluation
  } catch (mu::Parser::exception_type& e) {
    std::string msg = e.GetMsg();
    while (!msg.empty() && (msg.back() == '.' || msg.back() == ' ')) msg.pop_back();
    if (msg.find("position") == std::string::npos && e.GetPos() >= 0)
      msg += " at position " + std::to_string(e.GetPos());
    throw InputError(where + ": cannot parse \"" + text + "\": " + msg +
                     " (variables are x, y and z; constants pi and e)");
  }
  Expression result;
  result.text_ = text;
  result.where_ = where;
  return result;
}

Expression Expression::constant(double value) {
  std::ostringstream s;
  s.precision(17);
  s << value;
  Expression e;
  e.text_ = s.str();
  e.where_ = "constant";
  return e;
}

namespace {

// The text of a derived expression, the same in every process. GiNaC orders the terms of
// sums and products by hash values seeded with the addresses of type names, which move with
// address-space randomization: printed as GiNaC stores them, a derivative came out with its
// terms in another order from one run to the next, and so did the last bits of every source
// value, error norm and solution computed from it. Here the operands of every sum and
// product are sorted by their own text. Leaves (numbers, symbols, constants) print as GiNaC's
// C printer prints them; functions by GiNaC's name, which muParser shares (sin, exp, log, ...).
std::string canonical_text(const GiNaC::ex& e) {
  using namespace GiNaC;
  if (is_a<add>(e) || is_a<mul>(e)) {
    std::vector<std::string> parts;
    for (size_t i = 0; i < e.nops(); ++i) parts.push_back("(" + canonical_text(e.op(i)) + ")");
    std::sort(parts.begin(), parts.end());
    std::string r;
    for (const auto& p : parts) r += (r.empty() ? "" : is_a<add>(e) ? "+" : "*") + p;
    return r;
  }
  if (is_a<power>(e)) return "(" + canonical_text(e.op(0)) + ")^(" + canonical_text(e.op(1)) + ")";
  if (is_a<function>(e)) {
    std::string r = ex_to<function>(e).get_name() + "(";
    for (size_t i = 0; i < e.nops(); ++i) r += (i ? "," : "") + canonical_text(e.op(i));
    return r + ")";
  }
  std::ostringstream s;
  s << csrc_double << e;
  return s.str();
}

// Parses u with GiNaC (symbols x, y, z) and turns derived GiNaC expressions back into
// Expressions, checking the round trip through text against GiNaC's own evaluation.
class Differentiator {
 public:
  explicit Differentiator(const Expression& u) : u_(u), x_("x"), y_("y"), z_("z") {
    using namespace GiNaC;
    symtab table;
    table["x"] = x_;
    table["y"] = y_;
    table["z"] = z_;
    table["pi"] = Pi;
    table["e"] = exp(ex(1));
    parser reader(table);
    reader.strict = true;
    try {
      f_ = reader(u.text());
    } catch (std::exception& e) {
      std::string msg = e.what();
      msg = msg.substr(0, msg.find('\n'));
      throw InputError(u.where() + ": cannot differentiate \"" + u.text() + "\" symbolically (" + msg +
                       "); give `source` explicitly or use the functions listed in the README");
    }
  }
  const GiNaC::ex& f() const { return f_; }
  const GiNaC::symbol& x() const { return x_; }
  const GiNaC::symbol& y() const { return y_; }
  const GiNaC::symbol& z() const { return z_; }

  Expression to_expression(const GiNaC::ex& e, const std::string& what) const {
    using namespace GiNaC;
    const std::string text = canonical_text(e);
    Expression r = Expression::parse(text, u_.where() + " (derived " + what + ")");
    ExpressionEvaluator eval(r);
    const double pts[3][3] = {{0.3, 0.7, 0.2}, {-0.4, 0.25, -0.6}, {0.61, -0.83, 0.45}};
    for (const auto& pt : pts) {
      const ex ge = evalf(e.subs(lst{x_ == pt[0], y_ == pt[1], z_ == pt[2]}));
      if (!is_a<numeric>(ge) || !ex_to<numeric>(ge).is_real()) continue;
      const double gv = ex_to<numeric>(ge).to_double(), mv = eval(pt[0], pt[1], pt[2]);
      if (!std::isfinite(gv) || !std::isfinite(mv)) continue;
      if (std::abs(gv - mv) > 1e-9 * (1.0 + std::abs(gv)))
        throw std::logic_error("derived " + what + " of \"" + u_.text() +
                               "\" evaluates differently after conversion: " + text);
    }
    return r;
  }

 private:
  Expression u_;
  GiNaC::symbol x_, y_, z_;
  GiNaC::ex f_;
};

}  // namespace

ExactSolution differentiate_exact_solution(const Expression& u) {
  const Differentiator d(u);
  ExactSolution result;
  result.u = u;
  result.u_x = d.to_expression(d.f().diff(d.x()), "u_x");
  result.u_y = d.to_expression(d.f().diff(d.y()), "u_y");
  result.minus_laplacian = d.to_expression(-(d.f().diff(d.x(), 2) + d.f().diff(d.y(), 2)), "-laplacian");
  return result;
}

ExactSolution differentiate_surface_solution(const Expression& u) {
  const Differentiator d(u);
  ExactSolution r;
  r.u = u;
  const GiNaC::symbol* v[3] = {&d.x(), &d.y(), &d.z()};
  const char* names = "xyz";
  Expression* gradient[3] = {&r.u_x, &r.u_y, &r.u_z};
  for (int i = 0; i < 3; ++i) {
    const GiNaC::ex di = d.f().diff(*v[i]);
    *gradient[i] = d.to_expression(di, std::string("u_") + names[i]);
    for (int j = i; j < 3; ++j)
      r.hessian[i][j] = r.hessian[j][i] =
          d.to_expression(di.diff(*v[j]), std::string("u_") + names[i] + names[j]);
  }
  return r;
}

}  // namespace knotwork
