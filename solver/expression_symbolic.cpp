// The symbolic side of expressions: GiNaC differentiates the tree a user's text was read into
// (expression_tree.hpp), and each derivative is turned back into a tree for the same program.
// There is one reading of the text, so nothing here compares two parsers; what is checked is
// that double precision can carry what exact arithmetic derived.
#include <ginac/ginac.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "basis/core/input_error.hpp"
#include "solver/expression.hpp"
#include "solver/expression_tree.hpp"

namespace knotwork {

using expression_detail::Node;
using expression_detail::NodePtr;

namespace {

// The text of a derived expression, the same in every process. GiNaC orders the terms of
// sums and products by hash values seeded with the addresses of type names, which move with
// address-space randomization: taken in GiNaC's order, a derivative's terms were summed in
// another order from one run to the next, and so the last bits of every source value, error
// norm and solution computed from it moved. Here the operands of every sum and product are
// ordered by their own text, in the printed text and in the program alike.
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

// GiNaC computes powers of numbers exactly: 4777^775777777 (found by fuzzing) is an integer of
// 2.8 billion digits, (7^9999)^9999 one of 84 million. Before a power goes to GiNaC, its
// constant exponent (times those of the powers nested in its base, which GiNaC multiplies)
// must stay within kMaxExactExponent, and a power of constants within double precision (the
// solver could not use more).
constexpr double kMaxExactExponent = 10000;

struct Symbols {
  // Real symbols: the coordinates are real, and GiNaC then simplifies conjugate(x) to x (the
  // derivative of abs(f) is written with conjugates otherwise).
  GiNaC::realsymbol x{"x"}, y{"y"}, z{"z"};
  const GiNaC::realsymbol& operator[](int i) const { return i == 0 ? x : i == 1 ? y : z; }
};

struct Refusal {
  std::string why;
  bool whole = false;  // the message is `why` alone (not a cost of exact arithmetic)
};

std::string span_text(const Node& node, const std::string& text) {
  if (node.begin < 0 || node.end > long(text.size())) return "";
  const std::string part = text.substr(node.begin, node.end - node.begin);
  return part.front() == '(' && part.back() == ')' ? " " + part : " (" + part + ")";
}

// GiNaC allocates a power (and a quotient's power) before evaluating it, and loses it when the
// evaluation throws (0^0, 0^-1, 1/0; found by fuzzing: `9^0^0`). Such a power is refused here,
// before GiNaC sees it.
void refuse_undefined_power(const GiNaC::ex& base, const GiNaC::ex& exponent) {
  using namespace GiNaC;
  if (!base.is_zero() || !is_a<numeric>(exponent)) return;
  const numeric& p = ex_to<numeric>(exponent);
  if (p.is_zero()) throw std::domain_error("0^0 is undefined");
  if (!p.is_real() || p < 0) throw std::domain_error("division by zero");
}

// The tree as a GiNaC expression; `nested` receives the largest product of constant exponents
// along a chain of nested powers inside it.
GiNaC::ex to_ginac(const Node& node, const Symbols& s, const std::string& text, double& nested) {
  using namespace GiNaC;
  nested = 1;
  std::vector<ex> a;
  for (const NodePtr& o : node.operands) {
    double inner = 1;
    a.push_back(to_ginac(*o, s, text, inner));
    nested = std::max(nested, inner);
  }
  switch (node.kind) {
    case Node::kNumber: return node.name.empty() ? ex(numeric(node.value)) : ex(numeric(node.name.c_str()));
    case Node::kConstant: return node.name == "pi" ? ex(Pi) : exp(ex(1));
    case Node::kVariable: return s[node.variable];
    case Node::kAdd: return a[0] + a[1];
    case Node::kSubtract: return a[0] - a[1];
    case Node::kMultiply: return a[0] * a[1];
    case Node::kDivide: refuse_undefined_power(a[1], -1); return a[0] / a[1];
    case Node::kNegate: return -a[0];
    case Node::kPower: {
      const Node& base = *node.operands[0];
      const Node& exponent = *node.operands[1];
      if (!exponent.has_variables) {
        const double p = expression_detail::constant_value(exponent);
        const std::string limit = std::to_string(int(kMaxExactExponent));
        if (!(std::abs(p) <= kMaxExactExponent)) throw Refusal{"a constant exponent beyond " + limit + span_text(node, text)};
        nested *= std::max(1.0, std::abs(p));
        if (!(nested <= kMaxExactExponent))
          throw Refusal{"nested constant exponents with a product beyond " + limit + span_text(node, text)};
        if (!base.has_variables) {
          const double b = expression_detail::constant_value(base), power = std::pow(std::abs(b), p);
          if (std::isfinite(b) && b != 0 && !(power <= 1e300 && power >= 1e-300))
            throw Refusal{"a constant power beyond double precision" + span_text(node, text)};
        }
      }
      refuse_undefined_power(a[0], a[1]);
      return pow(a[0], a[1]);
    }
    case Node::kExternal:
      throw Refusal{"a Python function cannot be differentiated: give what is derived from it as well (the "
                    "source; with a Python exact solution, its gradient as exact_gradient)",
                    true};
    case Node::kCall: {
      const std::string& f = node.name;
      if (f == "atan2") return atan2(a[0], a[1]);
      if (f == "sin") return sin(a[0]);
      if (f == "cos") return cos(a[0]);
      if (f == "tan") return tan(a[0]);
      if (f == "asin") return asin(a[0]);
      if (f == "acos") return acos(a[0]);
      if (f == "atan") return atan(a[0]);
      if (f == "sinh") return sinh(a[0]);
      if (f == "cosh") return cosh(a[0]);
      if (f == "tanh") return tanh(a[0]);
      if (f == "exp") return exp(a[0]);
      if (f == "log") return log(a[0]);
      if (f == "sqrt") return sqrt(a[0]);
      if (f == "abs") return abs(a[0]);
      break;
    }
  }
  throw std::logic_error("expression tree: unknown node");
}

// A derived GiNaC expression as a tree: constants evaluated (exactly, then rounded), the
// operands of sums and products in canonical order. Throws std::invalid_argument for what
// the grammar does not have (a function GiNaC wrote into a derivative).
NodePtr from_ginac(const GiNaC::ex& e, const Symbols& s) {
  using namespace GiNaC;
  if (!e.has(s.x) && !e.has(s.y) && !e.has(s.z)) {
    const ex v = evalf(e);
    if (!is_a<numeric>(v) || !ex_to<numeric>(v).is_real()) throw std::invalid_argument("not a real constant");
    return expression_detail::number_node(ex_to<numeric>(v).to_double());
  }
  if (is_a<symbol>(e)) return expression_detail::variable_node(e.is_equal(s.x) ? 0 : e.is_equal(s.y) ? 1 : 2);
  if (is_a<add>(e) || is_a<mul>(e)) {
    std::vector<std::pair<std::string, ex>> parts;
    for (size_t i = 0; i < e.nops(); ++i) parts.emplace_back(canonical_text(e.op(i)), e.op(i));
    std::sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const Node::Kind kind = is_a<add>(e) ? Node::kAdd : Node::kMultiply;
    NodePtr r = from_ginac(parts[0].second, s);
    for (size_t i = 1; i < parts.size(); ++i) r = expression_detail::binary_node(kind, r, from_ginac(parts[i].second, s));
    return r;
  }
  if (is_a<power>(e)) return expression_detail::binary_node(Node::kPower, from_ginac(e.op(0), s), from_ginac(e.op(1), s));
  if (is_a<function>(e)) {
    const std::string name = ex_to<function>(e).get_name();
    std::vector<NodePtr> arguments;
    for (size_t i = 0; i < e.nops(); ++i) arguments.push_back(from_ginac(e.op(i), s));
    if ((name == "atan2" && arguments.size() == 2) || (arguments.size() == 1 && expression_detail::is_unary_function(name)))
      return expression_detail::call_node(name, std::move(arguments));
    throw std::invalid_argument("its derivative needs the function " + name);
  }
  throw std::invalid_argument("its derivative has a term outside the grammar");
}

// Reads an exact solution's tree into GiNaC and turns what is derived from it back into
// Expressions, each checked against GiNaC's exact value at three points.
class Differentiator {
 public:
  explicit Differentiator(const Expression& u) : u_(u) {
    f_ = read(u);
  }
  // u, or another expression of the same problem (a coefficient), with the same symbols.
  GiNaC::ex read(const Expression& e) const {
    GiNaC::ex r;
    try {
      double nested = 1;
      r = to_ginac(e.tree(), s_, e.text(), nested);
    } catch (const Refusal& refusal) {
      if (refusal.whole) throw InputError(e.where() + ": " + refusal.why);
      throw InputError(e.where() + ": cannot differentiate \"" + e.text() + "\" symbolically: " + refusal.why +
                       " makes exact arithmetic compute numbers of millions of digits; give `source` explicitly");
    } catch (const std::exception& error) {  // GiNaC's own: a division by zero, log(0)
      std::string msg = error.what();
      throw InputError(e.where() + ": cannot differentiate \"" + e.text() + "\" symbolically (" +
                       msg.substr(0, msg.find('\n')) + ")");
    }
    if (const auto d = first_disagreement(r, e))
      throw InputError(e.where() + ": \"" + e.text() + "\" cannot be evaluated in double precision " + *d +
                       "; are its constants too large?");
    return r;
  }
  const GiNaC::ex& f() const { return f_; }
  const GiNaC::realsymbol& x() const { return s_.x; }
  const GiNaC::realsymbol& y() const { return s_.y; }
  const GiNaC::realsymbol& z() const { return s_.z; }

  Expression to_expression(const GiNaC::ex& e, const std::string& what) const {
    NodePtr tree;
    try {
      tree = from_ginac(e, s_);
    } catch (const std::invalid_argument& why) {
      throw InputError(u_.where() + ": cannot differentiate \"" + u_.text() + "\" symbolically: " + why.what() +
                       "; give `source` explicitly");
    }
    Expression r = Expression::from_tree(canonical_text(e), u_.where() + " (derived " + what + ")", std::move(tree));
    // Constants too large for doubles (sin(1e21 x)) or cancellations double precision cannot
    // carry make the program differ from GiNaC's value: refused, not solved on.
    if (const auto d = first_disagreement(e, r))
      throw InputError(u_.where() + ": \"" + u_.text() + "\": its derived " + what +
                       " cannot be evaluated in double precision " + *d + "; are its constants too large?");
    return r;
  }

 private:
  // "(at (x, y, z): value against the exact value)" at the first check point where the
  // program of `text` and GiNaC's value of e differ, if any.
  std::optional<std::string> first_disagreement(const GiNaC::ex& e, const Expression& text) const {
    using namespace GiNaC;
    const expression_detail::CompiledExpression& program = *text.compiled();
    std::vector<double> registers(program.program.size());
    program.program.set_constants(registers.data());
    const double pts[3][3] = {{0.3, 0.7, 0.2}, {-0.4, 0.25, -0.6}, {0.61, -0.83, 0.45}};
    for (const auto& pt : pts) {
      const double mv = program.program.run_at(registers.data(), pt[0], pt[1], pt[2], program.output);
      // CLN's floats have no exponent limit, and it computes what a double gives up on: at a
      // check point, nested powers of x^(-3 y^2 ...) (found by fuzzing) made a float exponent
      // of 10^(10^13), and exp() of it asked for 4.8 TB. A point where an operand of a power
      // or a function lies beyond double range, in the program's own evaluation, is not a check
      // point (the double could not be compared there anyway). One evaluation per point: it
      // was an exact evaluation of every such operand's subtree, quadratic in the depth (6.4 s
      // for sin nested 40 deep, now 0.56 s).
      if (!program.program.operands_within(registers.data(), 1e300)) continue;
      ex ge;
      try {
        const lst at{s_.x == pt[0], s_.y == pt[1], s_.z == pt[2]};
        ge = evalf(e.subs(at));
      } catch (const std::exception&) {  // CLN's floating-point underflow or overflow: no exact value here
        continue;
      }
      if (!is_a<numeric>(ge) || !ex_to<numeric>(ge).is_real()) continue;
      const double gv = ex_to<numeric>(ge).to_double();
      if (!std::isfinite(gv) || !std::isfinite(mv)) continue;
      if (std::abs(gv - mv) > 1e-9 * (1.0 + std::abs(gv))) {
        std::ostringstream m;
        m << "(at (" << pt[0] << ", " << pt[1] << ", " << pt[2] << "): " << mv << " against the exact " << gv << ")";
        return m.str();
      }
    }
    return std::nullopt;
  }

  Expression u_;
  Symbols s_;
  GiNaC::ex f_;
};

// u_x, u_y (and u_z in a volume) and -Laplace u in `dimension` Cartesian coordinates.
ExactSolution differentiate_cartesian(const Expression& u, int dimension) {
  const Differentiator d(u);
  ExactSolution r;
  r.u = u;
  const GiNaC::symbol* v[3] = {&d.x(), &d.y(), &d.z()};
  Expression* gradient[3] = {&r.u_x, &r.u_y, &r.u_z};
  GiNaC::ex laplacian = 0;
  for (int i = 0; i < dimension; ++i) {
    *gradient[i] = d.to_expression(d.f().diff(*v[i]), std::string("u_") + "xyz"[i]);
    laplacian += d.f().diff(*v[i], 2);
  }
  r.minus_laplacian = d.to_expression(-laplacian, "-laplacian");
  return r;
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
      r.hessian[i][j] = r.hessian[j][i] = d.to_expression(di.diff(*v[j]), std::string("u_") + names[i] + names[j]);
  }
  return r;
}

// GiNaC and CLN throw their own exceptions (a floating-point underflow in exp(-x^2111...), a
// pole): they become InputErrors naming the field, like a syntax error.
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
                     "); give `source` explicitly");
  }
}

}  // namespace

ExactSolution differentiate_exact_solution(const Expression& u) {
  return derive_or_refuse(u, [&] { return differentiate_cartesian(u, 2); });
}

ExactSolution differentiate_surface_solution(const Expression& u) {
  return derive_or_refuse(u, [&] { return differentiate_surface(u); });
}

ExactSolution differentiate_volume_solution(const Expression& u) {
  return derive_or_refuse(u, [&] { return differentiate_cartesian(u, 3); });
}

Expression derive_general_source(const Expression& u, const std::vector<Expression>& diffusion,
                                  const Expression& reaction, double constant_reaction, int dimension) {
  return derive_or_refuse(u, [&] {
    const Differentiator d(u);
    const GiNaC::symbol* v[3] = {&d.x(), &d.y(), &d.z()};
    // A as a symmetric dimension x dimension matrix of its entries, row by row of the upper triangle.
    GiNaC::ex a[3][3];
    for (int i = 0; i < dimension; ++i)
      for (int j = 0; j < dimension; ++j) a[i][j] = i == j ? GiNaC::ex(1) : GiNaC::ex(0);
    if (diffusion.size() == 1) {
      const GiNaC::ex s = d.read(diffusion[0]);
      for (int i = 0; i < dimension; ++i) a[i][i] = s;
    } else if (!diffusion.empty()) {
      if (diffusion.size() != static_cast<size_t>(dimension * (dimension + 1) / 2))
        throw std::logic_error("derive_general_source: a coefficient matrix of the wrong size");
      int e = 0;
      for (int i = 0; i < dimension; ++i)
        for (int j = i; j < dimension; ++j) a[i][j] = a[j][i] = d.read(diffusion[e++]);
    }
    GiNaC::ex grad[3];
    for (int i = 0; i < dimension; ++i) grad[i] = d.f().diff(*v[i]);
    GiNaC::ex divergence = 0;
    for (int i = 0; i < dimension; ++i) {
      GiNaC::ex flux = 0;
      for (int j = 0; j < dimension; ++j) flux += a[i][j] * grad[j];
      divergence += flux.diff(*v[i]);
    }
    const GiNaC::ex c = reaction.empty() ? GiNaC::ex(constant_reaction) : d.read(reaction);
    return d.to_expression(-divergence + c * d.f(), "source -div(A grad u) + c u");
  });
}

}  // namespace knotwork
