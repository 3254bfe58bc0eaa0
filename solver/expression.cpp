#include "solver/expression.hpp"

#include <ginac/ginac.h>
#include <muParser.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <optional>
#include <numbers>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "basis/core/input_error.hpp"

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

// GiNaC evaluates powers of numbers exactly while it parses: 4777^775777777 (found by fuzzing)
// is an integer of 2.8 billion digits, and the parser never returns; (7^9999)^9999 has only
// small exponents but 84 million digits. A text is not given to GiNaC if one of its powers has
// a constant exponent beyond kMaxExactExponent, nested powers whose constant exponents multiply
// beyond it, or a constant power whose value lies beyond double precision (the solver could not
// use it anyway). All are judged in double by muParser, on the text's operands either side of
// '^': a number, a name, a call or a parenthesised group.
constexpr double kMaxExactExponent = 10000;

bool is_name_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_'; }

// [begin, end) of the operand right of the '^' at i, as far as muParser reads it: a number, a
// name, a call or a group (spaces after '^' and one sign included).
std::pair<size_t, size_t> exponent_operand(const std::string& t, size_t i) {
  size_t j = i + 1;
  while (j < t.size() && (t[j] == ' ' || t[j] == '\t')) ++j;
  size_t end = j;
  if (end < t.size() && t[end] == '(') {
    for (int depth = 0; end < t.size(); ++end)
      if (t[end] == '(') ++depth;
      else if (t[end] == ')' && --depth == 0) {
        ++end;
        break;
      }
  } else {
    if (end < t.size() && (t[end] == '-' || t[end] == '+')) ++end;
    while (end < t.size() && (t[end] == ' ' || t[end] == '\t')) ++end;  // "x^ - 3444...": found by fuzzing
    while (end < t.size() && (is_name_char(t[end]) ||
                              ((t[end] == '+' || t[end] == '-') && (t[end - 1] == 'e' || t[end - 1] == 'E'))))
      ++end;
  }
  return {j, end};
}

// GiNaC reads a sign after '^' as the sign of everything up to the end of the enclosing group:
// 2^-1*3+1 is 2^(-2). [begin, end) of that exponent, or an empty range without a sign.
std::pair<size_t, size_t> signed_exponent(const std::string& t, size_t i) {
  size_t j = i + 1;
  while (j < t.size() && (t[j] == ' ' || t[j] == '\t')) ++j;
  if (j == t.size() || (t[j] != '-' && t[j] != '+')) return {j, j};
  size_t end = j;
  for (int depth = 0; end < t.size(); ++end) {
    if (t[end] == '(') ++depth;
    else if (t[end] == ')' && --depth < 0) break;
    else if (t[end] == ',' && depth == 0) break;
  }
  return {j, end};
}

std::string number_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Whether some '^' in t is followed by a sign (spaces between allowed).
bool signed_exponent_position(const std::string& t) {
  for (size_t i = 0; i < t.size(); ++i)
    if (t[i] == '^') {
      const auto [g0, g1] = signed_exponent(t, i);
      if (g1 > g0) return true;
    }
  return false;
}

// [begin, end) of the operand left of the '^' at i: a group with the name of the function
// called on it, or a name or number (1.5e+3 included).
std::pair<size_t, size_t> base_operand(const std::string& t, size_t i) {
  size_t end = i;
  while (end > 0 && (t[end - 1] == ' ' || t[end - 1] == '\t')) --end;
  size_t begin = end;
  if (begin > 0 && t[begin - 1] == ')') {
    for (int depth = 0; begin > 0; --begin)
      if (t[begin - 1] == ')') ++depth;
      else if (t[begin - 1] == '(' && --depth == 0) {
        --begin;
        break;
      }
  }
  while (begin > 0 && (is_name_char(t[begin - 1]) ||
                       ((t[begin - 1] == '+' || t[begin - 1] == '-') && begin >= 2 &&
                        (t[begin - 2] == 'e' || t[begin - 2] == 'E') && begin >= 3 && std::isdigit(static_cast<unsigned char>(t[begin - 3])))))
    --begin;
  return {begin, end};
}

// The value of text if it is a constant (the same at two points), else nothing.
std::optional<double> constant_value(const std::string& text) {
  try {
    ExpressionEvaluator value(Expression::parse(text, "operand"));
    const double a = value(0.3, 0.7, 0.2), b = value(-0.4, 0.25, -0.6);
    if (a == b) return a;
  } catch (const std::exception&) {  // not an expression by itself: GiNaC will say what it makes of it
  }
  return std::nullopt;
}

// Why t must not be given to GiNaC, or nothing.
std::optional<std::string> unbounded_constant_power(const std::string& t) {
  const std::string exponent_beyond = "a constant exponent beyond " + std::to_string(int(kMaxExactExponent));
  // Nested powers multiply their exponents: ((9999/9998)^9999)^9999 is near 2.7 but has 10^8
  // digits. Per '^', the product of the constant exponents of it and of the powers in its base.
  std::map<size_t, double> nested_exponent;
  for (size_t i = 0; i < t.size(); ++i) {
    if (t[i] != '^') continue;
    const auto [e0, e1] = exponent_operand(t, i);
    const std::optional<double> exponent = e1 > e0 ? constant_value(t.substr(e0, e1 - e0)) : std::nullopt;
    if (exponent && !(std::abs(*exponent) <= kMaxExactExponent)) return exponent_beyond;  // or not finite
    // The exponent GiNaC computes with: the signed rest of the group, or the operand.
    auto [g0, g1] = signed_exponent(t, i);
    std::optional<double> ginac_exponent = exponent;
    if (g1 > g0) {
      ginac_exponent = constant_value(t.substr(g0, g1 - g0));
      if (ginac_exponent && !(std::abs(*ginac_exponent) <= kMaxExactExponent)) return exponent_beyond;
    } else {
      std::tie(g0, g1) = std::pair(e0, e1);
    }
    if (!ginac_exponent) continue;
    const auto [b0, b1] = base_operand(t, i);
    double inner = 1;
    for (auto k = nested_exponent.lower_bound(b0); k != nested_exponent.end() && k->first < b1; ++k)
      inner = std::max(inner, k->second);
    const double nested = inner * std::abs(*ginac_exponent);
    if (!(nested <= kMaxExactExponent))
      return "nested constant exponents with a product beyond " + std::to_string(int(kMaxExactExponent)) + " (" +
             t.substr(b0, b1 - b0) + "^" + t.substr(g0, g1 - g0) + ")";
    nested_exponent[i] = nested;
    if (b1 == b0) continue;
    const std::string base_text = t.substr(b0, b1 - b0);
    const std::optional<double> base = constant_value(base_text);
    if (!base || !std::isfinite(*base) || *base == 0) continue;
    const double power = std::pow(std::abs(*base), *ginac_exponent);
    if (!(power <= 1e300 && power >= 1e-300))
      return "a constant power beyond double precision (" + base_text + "^" + t.substr(g0, g1 - g0) + ")";
  }
  return std::nullopt;
}

// CLN's floats have no exponent limit, and it computes what a double would give up on: at a
// check point, nested powers of x^(-3 y^2 ...) (found by fuzzing) made a float exponent of
// 10^(10^13), and exp() of it asked for 4.8 TB. A point where an operand of a power or a
// function lies beyond double precision is not a check point (the text could not be compared
// there anyway). Post-order: an operand's own powers are judged before it is evaluated.
bool operands_within_double_range(const GiNaC::ex& e, const GiNaC::lst& at) {
  using namespace GiNaC;
  const numeric limit(1e300);
  for (auto node = e.postorder_begin(); node != e.postorder_end(); ++node) {
    if (!is_a<power>(*node) && !is_a<function>(*node)) continue;
    for (size_t k = 0; k < node->nops(); ++k) {
      const ex v = evalf(node->op(k).subs(at));
      if (!is_a<numeric>(v) || !ex_to<numeric>(v).is_real() || abs(ex_to<numeric>(v)) > limit) return false;
    }
  }
  return true;
}

// Parses u with GiNaC (symbols x, y, z) and turns derived GiNaC expressions back into
// Expressions, checking the round trip through text against GiNaC's own evaluation.
class Differentiator {
 public:
  explicit Differentiator(const Expression& u) : u_(u), x_("x"), y_("y"), z_("z") {
    f_ = read_text(u);  // a parse error becomes the field's InputError in derive_or_refuse
    check_same_reading(f_, u_);
  }
  // Another expression of the same problem (a coefficient), read with the same symbols and
  // checked the same way.
  GiNaC::ex read(const Expression& e) const {
    GiNaC::ex r;
    try {
      r = read_text(e);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& error) {
      std::string msg = error.what();
      throw InputError(e.where() + ": cannot differentiate \"" + e.text() + "\" symbolically (" +
                       msg.substr(0, msg.find('\n')) + ")");
    }
    check_same_reading(r, e);
    return r;
  }
  const GiNaC::ex& f() const { return f_; }
  const GiNaC::symbol& x() const { return x_; }
  const GiNaC::symbol& y() const { return y_; }
  const GiNaC::symbol& z() const { return z_; }

  Expression to_expression(const GiNaC::ex& e, const std::string& what) const {
    const std::string text = canonical_text(e);
    Expression r = Expression::parse(text, u_.where() + " (derived " + what + ")");
    // The text in double precision must give GiNaC's value; constants too large for doubles
    // (sin(1e21 x)) or cancellations it cannot carry make it differ: refused, not solved on.
    if (const auto d = first_disagreement(e, r))
      throw InputError(u_.where() + ": \"" + u_.text() + "\": its derived " + what + " cannot be evaluated in double precision " +
                       d->at() + "; are its constants too large?");
    return r;
  }

 private:
  struct Disagreement {
    std::string point;      // "(x, y, z)"
    double text_value = 0;  // muParser's
    double exact_value = 0;  // GiNaC's
    std::string at() const {
      std::ostringstream s;
      s << "(at " << point << ": " << text_value << " against the exact " << exact_value << ")";
      return s.str();
    }
  };

  // The first check point where muParser's value of text and GiNaC's of e differ, if any.
  std::optional<Disagreement> first_disagreement(const GiNaC::ex& e, const Expression& text) const {
    using namespace GiNaC;
    ExpressionEvaluator eval(text);
    const double pts[3][3] = {{0.3, 0.7, 0.2}, {-0.4, 0.25, -0.6}, {0.61, -0.83, 0.45}};
    for (const auto& pt : pts) {
      ex ge;
      try {
        const lst at{x_ == pt[0], y_ == pt[1], z_ == pt[2]};
        if (!operands_within_double_range(e, at)) continue;
        ge = evalf(e.subs(at));
      } catch (const std::exception&) {  // CLN's floating-point underflow or overflow: no exact value here
        continue;
      }
      if (!is_a<numeric>(ge) || !ex_to<numeric>(ge).is_real()) continue;
      const double gv = ex_to<numeric>(ge).to_double(), mv = eval(pt[0], pt[1], pt[2]);
      if (!std::isfinite(gv) || !std::isfinite(mv)) continue;
      if (std::abs(gv - mv) > 1e-9 * (1.0 + std::abs(gv))) {
        std::ostringstream s;
        s << "(" << pt[0] << ", " << pt[1] << ", " << pt[2] << ")";
        return Disagreement{s.str(), mv, gv};
      }
    }
    return std::nullopt;
  }

  // The differentiator must read u as the evaluator does. They part on a sign after '^': GiNaC
  // reads (x+2)^-1*2 as (x+2)^(-2), muParser as 2/(x+2) (u and its derivatives then belonged
  // to two different functions, and the error did not converge).
  void check_same_reading(const GiNaC::ex& f, const Expression& u) const {
    const auto d = first_disagreement(f, u);
    if (!d) return;
    if (signed_exponent_position(u.text()))
      throw InputError(u.where() + ": \"" + u.text() + "\" has a sign after '^', which the evaluator and the symbolic "
                       "differentiator read differently (at " + d->point + ": " + number_text(d->text_value) + " and " +
                       number_text(d->exact_value) + "); put the signed exponent in parentheses, as in x^(-1)");
    throw InputError(u.where() + ": \"" + u.text() + "\" cannot be evaluated in double precision " + d->at() +
                     "; are its constants too large?");
  }

  GiNaC::ex read_text(const Expression& e) const {
    using namespace GiNaC;
    symtab table;
    table["x"] = x_;
    table["y"] = y_;
    table["z"] = z_;
    table["pi"] = Pi;
    table["e"] = exp(ex(1));
    parser reader(table);
    reader.strict = true;
    if (const auto why = unbounded_constant_power(e.text()))
      throw InputError(e.where() + ": cannot differentiate \"" + e.text() + "\" symbolically: " + *why +
                       " makes exact arithmetic compute numbers of millions of digits; give `source` explicitly");
    return reader(e.text());
  }

  Expression u_;
  // Real symbols: the coordinates are real, and GiNaC then simplifies conjugate(x) to x (the
  // derivative of abs(f) is written with conjugates, which the evaluator rightly cannot read).
  GiNaC::realsymbol x_, y_, z_;
  GiNaC::ex f_;
};

}  // namespace

namespace {

// One instruction of a batch program: register `target` = f(operands), point by point.
struct Instruction {
  enum Kind { kConstant, kX, kY, kZ, kSum, kProduct, kIntegerPower, kPower, kFunction1, kFunction2 } kind;
  std::vector<int> operands;
  double constant = 0;
  int exponent = 0;
  double (*function1)(double) = nullptr;
  double (*function2)(double, double) = nullptr;
};

// a^n by repeated squaring (|n| <= 64): exact for small n where pow() is slow.
double integer_power(double a, int n) {
  double r = 1, b = a;
  for (unsigned m = static_cast<unsigned>(n < 0 ? -n : n); m; m >>= 1, b *= b)
    if (m & 1) r *= b;
  return n < 0 ? 1 / r : r;
}

double (*function_of(const std::string& name, size_t arity))(double) {
  static const std::pair<const char*, double (*)(double)> table[] = {
      {"sin", [](double a) { return std::sin(a); }},   {"cos", [](double a) { return std::cos(a); }},
      {"tan", [](double a) { return std::tan(a); }},   {"asin", [](double a) { return std::asin(a); }},
      {"acos", [](double a) { return std::acos(a); }}, {"atan", [](double a) { return std::atan(a); }},
      {"sinh", [](double a) { return std::sinh(a); }}, {"cosh", [](double a) { return std::cosh(a); }},
      {"tanh", [](double a) { return std::tanh(a); }}, {"exp", [](double a) { return std::exp(a); }},
      {"log", [](double a) { return std::log(a); }},   {"abs", [](double a) { return std::abs(a); }}};
  if (arity != 1) return nullptr;
  for (const auto& [n, f] : table)
    if (name == n) return f;
  return nullptr;
}

// Compiles GiNaC expressions into one instruction list; a subexpression is keyed by its
// canonical text (so equal ones share a register, and operand order is the same in every
// process). Throws std::invalid_argument for what it does not know.
class BatchCompiler {
 public:
  BatchCompiler(std::vector<Instruction>& program, const GiNaC::symbol& x, const GiNaC::symbol& y,
                const GiNaC::symbol& z)
      : program_(program), x_(x), y_(y), z_(z) {}
  int compile(const GiNaC::ex& e) {
    using namespace GiNaC;
    const std::string key = canonical_text(e);
    if (auto it = registers_.find(key); it != registers_.end()) return it->second;
    Instruction in{};
    if (!e.has(x_) && !e.has(y_) && !e.has(z_)) {
      const ex v = evalf(e);
      if (!is_a<numeric>(v) || !ex_to<numeric>(v).is_real()) throw std::invalid_argument("not a real constant");
      in.kind = Instruction::kConstant;
      in.constant = ex_to<numeric>(v).to_double();
    } else if (is_a<symbol>(e)) {
      in.kind = e.is_equal(x_) ? Instruction::kX : e.is_equal(y_) ? Instruction::kY : Instruction::kZ;
    } else if (is_a<add>(e) || is_a<mul>(e)) {
      std::vector<std::pair<std::string, ex>> parts;
      for (size_t i = 0; i < e.nops(); ++i) parts.emplace_back(canonical_text(e.op(i)), e.op(i));
      std::sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      in.kind = is_a<add>(e) ? Instruction::kSum : Instruction::kProduct;
      for (const auto& part : parts) in.operands.push_back(compile(part.second));
    } else if (is_a<power>(e)) {
      const ex exponent = e.op(1);
      in.operands.push_back(compile(e.op(0)));
      if (is_a<numeric>(exponent) && ex_to<numeric>(exponent).is_integer() && abs(ex_to<numeric>(exponent)) <= 64) {
        in.kind = Instruction::kIntegerPower;
        in.exponent = ex_to<numeric>(exponent).to_int();
      } else {
        in.kind = Instruction::kPower;
        in.operands.push_back(compile(exponent));
      }
    } else if (is_a<function>(e)) {
      const std::string name = ex_to<function>(e).get_name();
      for (size_t i = 0; i < e.nops(); ++i) in.operands.push_back(compile(e.op(i)));
      if (name == "atan2" && e.nops() == 2) {
        in.kind = Instruction::kFunction2;
        in.function2 = [](double a, double b) { return std::atan2(a, b); };
      } else if (auto* f = function_of(name, e.nops())) {
        in.kind = Instruction::kFunction1;
        in.function1 = f;
      } else {
        throw std::invalid_argument("function " + name);
      }
    } else {
      throw std::invalid_argument("unsupported term");
    }
    program_.push_back(std::move(in));
    const int r = static_cast<int>(program_.size()) - 1;
    registers_.emplace(key, r);
    return r;
  }

 private:
  std::vector<Instruction>& program_;
  const GiNaC::symbol &x_, &y_, &z_;
  std::map<std::string, int> registers_;
};

}  // namespace

namespace {

// Runs the program on n points, one instruction over all of them at a time.
void run_program(const std::vector<Instruction>& program, std::vector<std::vector<double>>& registers,
                 const double* x, const double* y, const double* z, long n) {
  for (size_t i = 0; i < program.size(); ++i) {
    const Instruction& in = program[i];
    std::vector<double>& t = registers[i];
    t.resize(n);
    auto operand = [&](int j) { return registers[in.operands[j]].data(); };
    switch (in.kind) {
      case Instruction::kConstant: std::fill(t.begin(), t.end(), in.constant); break;
      case Instruction::kX: std::copy(x, x + n, t.begin()); break;
      case Instruction::kY: std::copy(y, y + n, t.begin()); break;
      case Instruction::kZ:
        if (z) std::copy(z, z + n, t.begin());
        else std::fill(t.begin(), t.end(), 0.0);
        break;
      case Instruction::kSum: {
        std::copy(operand(0), operand(0) + n, t.begin());
        for (size_t j = 1; j < in.operands.size(); ++j) {
          const double* a = operand(static_cast<int>(j));
          for (long k = 0; k < n; ++k) t[k] += a[k];
        }
        break;
      }
      case Instruction::kProduct: {
        std::copy(operand(0), operand(0) + n, t.begin());
        for (size_t j = 1; j < in.operands.size(); ++j) {
          const double* a = operand(static_cast<int>(j));
          for (long k = 0; k < n; ++k) t[k] *= a[k];
        }
        break;
      }
      case Instruction::kIntegerPower: {
        const double* a = operand(0);
        for (long k = 0; k < n; ++k) t[k] = integer_power(a[k], in.exponent);
        break;
      }
      case Instruction::kPower: {
        const double *a = operand(0), *b = operand(1);
        for (long k = 0; k < n; ++k) t[k] = std::pow(a[k], b[k]);
        break;
      }
      case Instruction::kFunction1: {
        const double* a = operand(0);
        for (long k = 0; k < n; ++k) t[k] = in.function1(a[k]);
        break;
      }
      case Instruction::kFunction2: {
        const double *a = operand(0), *b = operand(1);
        for (long k = 0; k < n; ++k) t[k] = in.function2(a[k], b[k]);
        break;
      }
    }
  }
}

}  // namespace

struct ExpressionBatch::Impl {
  std::vector<Expression> expressions;
  std::vector<Instruction> program;
  std::vector<std::vector<double>> registers;
  // Per expression: its register in the program, or -1 and its muParser evaluator.
  std::vector<int> output;
  std::vector<std::optional<ExpressionEvaluator>> fallback;
  std::vector<std::vector<double>> fallback_values;
};

ExpressionBatch::ExpressionBatch(const std::vector<Expression>& expressions) : impl_(std::make_unique<Impl>()) {
  using namespace GiNaC;
  symbol x("x"), y("y"), z("z");
  symtab table;
  table["x"] = x;
  table["y"] = y;
  table["z"] = z;
  table["pi"] = Pi;
  table["Pi"] = Pi;
  table["e"] = exp(ex(1));
  BatchCompiler compiler(impl_->program, x, y, z);
  for (const Expression& e : expressions) {
    int r = -1;
    try {
      parser reader(table);
      reader.strict = true;
      // muParser evaluates it (see unbounded_constant_power).
      r = unbounded_constant_power(e.text()) ? -1 : compiler.compile(reader(e.text()));
    } catch (std::exception&) {
      r = -1;
    }
    impl_->output.push_back(r);
  }
  // The same meaning as muParser's at a few points, or muParser it is.
  const double px[3] = {0.3, -0.4, 0.61}, py[3] = {0.7, 0.25, -0.83}, pz[3] = {0.2, -0.6, 0.45};
  impl_->registers.resize(impl_->program.size());
  run_program(impl_->program, impl_->registers, px, py, pz, 3);
  for (size_t i = 0; i < expressions.size(); ++i) {
    int& r = impl_->output[i];
    ExpressionEvaluator reference(expressions[i]);
    for (int k = 0; k < 3 && r >= 0; ++k) {
      const double mine = impl_->registers[r][k], theirs = reference(px[k], py[k], pz[k]);
      if (std::isfinite(mine) != std::isfinite(theirs) ||
          (std::isfinite(mine) && std::abs(mine - theirs) > 1e-12 * (1 + std::abs(theirs))))
        r = -1;
    }
    impl_->fallback.emplace_back();
    if (r < 0) impl_->fallback.back().emplace(expressions[i]);
  }
  impl_->expressions = expressions;
  impl_->fallback_values.resize(expressions.size());
}

ExpressionBatch::ExpressionBatch(const ExpressionBatch& other) : impl_(std::make_unique<Impl>()) {
  const Impl& o = *other.impl_;
  impl_->expressions = o.expressions;
  impl_->program = o.program;
  impl_->output = o.output;
  impl_->registers.resize(o.program.size());
  impl_->fallback_values.resize(o.output.size());
  for (size_t e = 0; e < o.output.size(); ++e) {
    impl_->fallback.emplace_back();
    if (o.output[e] < 0) impl_->fallback.back().emplace(o.expressions[e]);
  }
}

ExpressionBatch::~ExpressionBatch() = default;
ExpressionBatch::ExpressionBatch(ExpressionBatch&&) noexcept = default;

void ExpressionBatch::evaluate(const double* x, const double* y, const double* z, long n) {
  Impl& m = *impl_;
  run_program(m.program, m.registers, x, y, z, n);
  for (size_t e = 0; e < m.output.size(); ++e) {
    if (m.output[e] >= 0) continue;
    std::vector<double>& v = m.fallback_values[e];
    v.resize(n);
    for (long k = 0; k < n; ++k) v[k] = (*m.fallback[e])(x[k], y[k], z ? z[k] : 0.0);
  }
}

const double* ExpressionBatch::result(int e) const {
  return impl_->output[e] >= 0 ? impl_->registers[impl_->output[e]].data() : impl_->fallback_values[e].data();
}

namespace {

ExactSolution differentiate_planar(const Expression& u) {
  const Differentiator d(u);
  ExactSolution result;
  result.u = u;
  result.u_x = d.to_expression(d.f().diff(d.x()), "u_x");
  result.u_y = d.to_expression(d.f().diff(d.y()), "u_y");
  result.minus_laplacian = d.to_expression(-(d.f().diff(d.x(), 2) + d.f().diff(d.y(), 2)), "-laplacian");
  return result;
}

ExactSolution differentiate_surface(const Expression& u) {
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

// GiNaC and CLN throw their own exceptions (a floating-point underflow in exp(-x^2111...), a
// power too large): they become InputErrors naming the field, like a syntax error.
template <class Derive>
auto derive_or_refuse(const Expression& u, Derive derive) -> decltype(derive()) {
  try {
    return derive();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    std::string msg = e.what();
    msg = msg.substr(0, msg.find('\n'));
    throw InputError(u.where() + ": cannot differentiate \"" + u.text() + "\" symbolically (" + msg +
                     "); give `source` explicitly or use the functions listed in the README");
  }
}

}  // namespace

ExactSolution differentiate_exact_solution(const Expression& u) {
  return derive_or_refuse(u, [&] { return differentiate_planar(u); });
}

ExactSolution differentiate_surface_solution(const Expression& u) {
  return derive_or_refuse(u, [&] { return differentiate_surface(u); });
}

Expression derive_general_source(const Expression& u, const std::vector<Expression>& diffusion,
                                  const Expression& reaction, double constant_reaction) {
  return derive_or_refuse(u, [&] {
    const Differentiator d(u);
    const GiNaC::ex ux = d.f().diff(d.x()), uy = d.f().diff(d.y());
    GiNaC::ex a11 = 1, a12 = 0, a22 = 1;
    if (diffusion.size() == 1) a11 = a22 = d.read(diffusion[0]);
    if (diffusion.size() == 3) a11 = d.read(diffusion[0]), a12 = d.read(diffusion[1]), a22 = d.read(diffusion[2]);
    const GiNaC::ex c = reaction.empty() ? GiNaC::ex(constant_reaction) : d.read(reaction);
    const GiNaC::ex f = -((a11 * ux + a12 * uy).diff(d.x()) + (a12 * ux + a22 * uy).diff(d.y())) + c * d.f();
    return d.to_expression(f, "source -div(A grad u) + c u");
  });
}

}  // namespace knotwork
