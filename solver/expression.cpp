#include "solver/expression.hpp"

#include <ginac/ginac.h>
#include <muParser.h>

#include <cmath>
#include <numbers>
#include <sstream>

#include "solver/input_error.hpp"

namespace knotwork {

namespace {

double pow_function(double a, double b) { return std::pow(a, b); }
double atan2_function(double a, double b) { return std::atan2(a, b); }
double natural_log(double a) { return std::log(a); }

void configure(mu::Parser& p, double* x, double* y) {
  p.DefineVar("x", x);
  p.DefineVar("y", y);
  p.DefineConst("pi", std::numbers::pi);
  p.DefineConst("Pi", std::numbers::pi);  // GiNaC prints pi this way
  p.DefineConst("e", std::numbers::e);
  p.DefineFun("pow", pow_function);
  p.DefineFun("atan2", atan2_function);
  p.DefineFun("log", natural_log);  // muParser's own log is base 10; users mean ln
}

}  // namespace

struct ExpressionEvaluator::Impl {
  double x = 0, y = 0;
  mu::Parser parser;
};

ExpressionEvaluator::ExpressionEvaluator(const Expression& e) : impl_(std::make_unique<Impl>()) {
  configure(impl_->parser, &impl_->x, &impl_->y);
  impl_->parser.SetExpr(e.text());
}
ExpressionEvaluator::~ExpressionEvaluator() = default;
ExpressionEvaluator::ExpressionEvaluator(ExpressionEvaluator&&) noexcept = default;

double ExpressionEvaluator::operator()(double x, double y) {
  impl_->x = x;
  impl_->y = y;
  return impl_->parser.Eval();
}

Expression Expression::parse(const std::string& text, const std::string& where) {
  if (text.find_first_not_of(" \t") == std::string::npos)
    throw InputError(where + ": expression is empty");
  double x = 0.31, y = 0.47;
  mu::Parser p;
  configure(p, &x, &y);
  try {
    p.SetExpr(text);
    p.Eval();  // muParser reports most syntax errors only on first evaluation
  } catch (mu::Parser::exception_type& e) {
    std::string msg = e.GetMsg();
    while (!msg.empty() && (msg.back() == '.' || msg.back() == ' ')) msg.pop_back();
    if (msg.find("position") == std::string::npos && e.GetPos() >= 0)
      msg += " at position " + std::to_string(e.GetPos());
    throw InputError(where + ": cannot parse \"" + text + "\": " + msg +
                     " (variables are x and y; constants pi and e)");
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

ExactSolution differentiate_exact_solution(const Expression& u) {
  using namespace GiNaC;
  symbol x("x"), y("y");
  symtab table;
  table["x"] = x;
  table["y"] = y;
  table["pi"] = Pi;
  table["e"] = exp(ex(1));
  parser reader(table);
  reader.strict = true;
  ex f;
  try {
    f = reader(u.text());
  } catch (std::exception& e) {
    std::string msg = e.what();
    msg = msg.substr(0, msg.find('\n'));
    throw InputError(u.where() + ": cannot differentiate \"" + u.text() + "\" symbolically (" + msg +
                     "); give `source` explicitly or use the functions listed in the README");
  }
  auto to_expression = [&](const ex& e, const std::string& what) {
    std::ostringstream s;
    s << csrc_double << e;
    Expression r = Expression::parse(s.str(), u.where() + " (derived " + what + ")");
    // Guard the round trip through text: muParser must agree with GiNaC.
    ExpressionEvaluator eval(r);
    const double pts[3][2] = {{0.3, 0.7}, {-0.4, 0.25}, {0.61, -0.83}};
    for (const auto& pt : pts) {
      const ex ge = evalf(e.subs(lst{x == pt[0], y == pt[1]}));
      if (!is_a<numeric>(ge) || !ex_to<numeric>(ge).is_real()) continue;
      const double gv = ex_to<numeric>(ge).to_double(), mv = eval(pt[0], pt[1]);
      if (!std::isfinite(gv) || !std::isfinite(mv)) continue;
      if (std::abs(gv - mv) > 1e-9 * (1.0 + std::abs(gv)))
        throw std::logic_error("derived " + what + " of \"" + u.text() +
                               "\" evaluates differently after conversion: " + s.str());
    }
    return r;
  };
  ExactSolution result;
  result.u = u;
  result.u_x = to_expression(f.diff(x), "u_x");
  result.u_y = to_expression(f.diff(y), "u_y");
  result.minus_laplacian = to_expression(-(f.diff(x, 2) + f.diff(y, 2)), "-laplacian");
  return result;
}

}  // namespace knotwork
