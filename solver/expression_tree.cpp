// The grammar (recursive descent) and the program; why by hand: see expression_tree.hpp.
#include "solver/expression_tree.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <numbers>
#include <sstream>

namespace knotwork::expression_detail {

namespace {

struct FunctionEntry {
  const char* name;
  double (*function)(double);
};
const FunctionEntry kUnaryFunctions[] = {
    {"sin", [](double a) { return std::sin(a); }},   {"cos", [](double a) { return std::cos(a); }},
    {"tan", [](double a) { return std::tan(a); }},   {"asin", [](double a) { return std::asin(a); }},
    {"acos", [](double a) { return std::acos(a); }}, {"atan", [](double a) { return std::atan(a); }},
    {"sinh", [](double a) { return std::sinh(a); }}, {"cosh", [](double a) { return std::cosh(a); }},
    {"tanh", [](double a) { return std::tanh(a); }}, {"exp", [](double a) { return std::exp(a); }},
    {"log", [](double a) { return std::log(a); }},   {"sqrt", [](double a) { return std::sqrt(a); }},
    {"abs", [](double a) { return std::abs(a); }}};

double (*unary_function(const std::string& name))(double) {
  for (const auto& [n, f] : kUnaryFunctions)
    if (name == n) return f;
  return nullptr;
}

double atan2_of(double a, double b) { return std::atan2(a, b); }

const char* const kFunctionList = "sin, cos, tan, asin, acos, atan, atan2(y, x), sinh, cosh, tanh, exp, log, sqrt, abs, pow(a, b)";

// expr  := term (('+' | '-') term)*
// term  := unary (('*' | '/') unary)*
// unary := ('+' | '-') unary | power
// power := primary ('^' unary)?       so 2^3^2 = 2^9, -2^2 = -4, 2^-1*3 = (2^-1)*3
// primary := number | name | name '(' expr (',' expr)* ')' | '(' expr ')'
class Reader {
 public:
  explicit Reader(const std::string& text) : t_(text) {}

  NodePtr read() {
    if (t_.size() > kMaxExpressionLength)
      throw ParseError{"longer than " + std::to_string(kMaxExpressionLength) + " characters", 0};
    NodePtr e = expr();
    skip();
    if (i_ < t_.size()) throw ParseError{std::string("unexpected '") + t_[i_] + "'" + after_operand_hint(), long(i_)};
    return e;
  }

 private:
  void skip() {
    while (i_ < t_.size() && std::isspace(static_cast<unsigned char>(t_[i_]))) ++i_;
  }
  bool at(char c) {
    skip();
    return i_ < t_.size() && t_[i_] == c;
  }
  std::string after_operand_hint() const {
    return std::isalnum(static_cast<unsigned char>(t_[i_])) || t_[i_] == '(' || t_[i_] == '.'
               ? " (an operator is missing: write 2*x, not 2x)"
               : "";
  }

  static NodePtr spanned(Node n, std::size_t begin, std::size_t end) {
    n.begin = long(begin);
    n.end = long(end);
    return std::make_shared<const Node>(std::move(n));
  }

  NodePtr binary(Node::Kind kind, NodePtr a, NodePtr b) {
    Node n;
    n.kind = kind;
    n.has_variables = a->has_variables || b->has_variables;
    const long begin = a->begin, end = b->end;
    n.operands = {std::move(a), std::move(b)};
    return spanned(std::move(n), begin, end);
  }

  NodePtr expr() {
    NodePtr left = term();
    for (;;) {
      if (at('+')) ++i_, left = binary(Node::kAdd, left, term());
      else if (at('-')) ++i_, left = binary(Node::kSubtract, left, term());
      else return left;
    }
  }
  NodePtr term() {
    NodePtr left = unary();
    for (;;) {
      if (at('*')) ++i_, left = binary(Node::kMultiply, left, unary());
      else if (at('/')) ++i_, left = binary(Node::kDivide, left, unary());
      else return left;
    }
  }
  NodePtr unary() {
    skip();
    const std::size_t begin = i_;
    if (at('+')) {
      ++i_;
      return unary();
    }
    if (at('-')) {
      ++i_;
      NodePtr operand = unary();
      Node n;
      n.kind = Node::kNegate;
      n.has_variables = operand->has_variables;
      const long end = operand->end;
      n.operands = {std::move(operand)};
      return spanned(std::move(n), begin, std::size_t(end));
    }
    NodePtr base = primary();
    if (at('^')) {
      ++i_;
      return binary(Node::kPower, base, unary());
    }
    return base;
  }

  NodePtr primary() {
    skip();
    if (i_ == t_.size()) throw ParseError{"an operand is missing at the end", long(i_)};
    const std::size_t begin = i_;
    const char c = t_[i_];
    if (c == '(') {
      if (++depth_ > kMaxDepth) throw ParseError{"parentheses nested deeper than " + std::to_string(kMaxDepth), long(i_)};
      ++i_;
      NodePtr inner = expr();
      if (!at(')')) throw ParseError{i_ < t_.size() ? std::string("expected ')' before '") + t_[i_] + "'" : "a ')' is missing", long(i_)};
      ++i_;
      --depth_;
      Node n = *inner;  // the group's span, for messages
      return spanned(std::move(n), begin, i_);
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number(begin);
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') return name(begin);
    throw ParseError{std::string("unexpected '") + c + "' where an operand should be", long(i_)};
  }

  NodePtr number(std::size_t begin) {
    auto digits = [&] {
      const std::size_t from = i_;
      while (i_ < t_.size() && std::isdigit(static_cast<unsigned char>(t_[i_]))) ++i_;
      return i_ > from;
    };
    bool any = digits();
    if (i_ < t_.size() && t_[i_] == '.') ++i_, any = digits() || any;
    if (!any) throw ParseError{"'.' is not a number", long(begin)};
    if (i_ < t_.size() && (t_[i_] == 'e' || t_[i_] == 'E')) {
      // 2e3 is a number; 2e (or 2*e written without '*') is not
      std::size_t j = i_ + 1;
      if (j < t_.size() && (t_[j] == '+' || t_[j] == '-')) ++j;
      if (j < t_.size() && std::isdigit(static_cast<unsigned char>(t_[j]))) {
        i_ = j;
        digits();
      }
    }
    Node n;
    n.kind = Node::kNumber;
    n.name = t_.substr(begin, i_ - begin);
    n.value = std::strtod(n.name.c_str(), nullptr);
    if (!std::isfinite(n.value)) throw ParseError{"the number " + n.name + " is beyond double precision", long(begin)};
    return spanned(std::move(n), begin, i_);
  }

  NodePtr name(std::size_t begin) {
    while (i_ < t_.size() && (std::isalnum(static_cast<unsigned char>(t_[i_])) || t_[i_] == '_')) ++i_;
    const std::string word = t_.substr(begin, i_ - begin);
    Node n;
    if (at('(')) {
      const bool two = word == "atan2" || word == "pow";
      if (!two && !is_unary_function(word))
        throw ParseError{"unknown function '" + word + "' (the functions are " + kFunctionList + ")", long(begin)};
      if (++depth_ > kMaxDepth) throw ParseError{"calls nested deeper than " + std::to_string(kMaxDepth), long(i_)};
      ++i_;
      n.kind = Node::kCall;
      n.name = word;
      n.operands.push_back(expr());
      while (at(',')) ++i_, n.operands.push_back(expr());
      if (!at(')')) throw ParseError{i_ < t_.size() ? std::string("expected ')' or ',' before '") + t_[i_] + "'" : "a ')' is missing", long(i_)};
      ++i_;
      --depth_;
      const std::size_t wanted = two ? 2 : 1;
      if (n.operands.size() != wanted)
        throw ParseError{word + " takes " + std::to_string(wanted) + (wanted == 1 ? " argument" : " arguments") + ", not " +
                             std::to_string(n.operands.size()),
                         long(begin)};
      n.has_variables = std::any_of(n.operands.begin(), n.operands.end(), [](const NodePtr& a) { return a->has_variables; });
      if (word == "pow") n.kind = Node::kPower, n.name.clear();
      return spanned(std::move(n), begin, i_);
    }
    if (word == "x" || word == "y" || word == "z") {
      n.kind = Node::kVariable;
      n.variable = word[0] - 'x';
      n.has_variables = true;
    } else if (word == "pi" || word == "e") {
      n.kind = Node::kConstant;
      n.name = word;
      n.value = word == "pi" ? std::numbers::pi : std::numbers::e;
    } else if (is_unary_function(word) || word == "atan2" || word == "pow") {
      throw ParseError{"'" + word + "' is a function: write " + word + "(...)", long(begin)};
    } else if (auto f = ExternalFunctionNames::find(word)) {
      n.kind = Node::kExternal;
      n.name = word;
      n.external = std::move(f);
      n.has_variables = true;
    } else {
      throw ParseError{"unknown name '" + word + "' (the variables are x, y and z; the constants pi and e)", long(begin)};
    }
    return spanned(std::move(n), begin, i_);
  }

  // Parentheses and calls nest at most this deep: a derivative of sin nested n deep grows like
  // n^3 terms (n = 100: 2.5 MB of text, 8 s); no formula a user writes comes near.
  static constexpr int kMaxDepth = 64;
  const std::string& t_;
  std::size_t i_ = 0;
  int depth_ = 0;
};

}  // namespace

NodePtr parse_tree(const std::string& text) { return Reader(text).read(); }

bool is_unary_function(const std::string& name) { return unary_function(name) != nullptr; }

NodePtr external_node(std::shared_ptr<const ExternalFunction> f) {
  Node n;
  n.kind = Node::kExternal;
  n.name = "external";
  n.external = std::move(f);
  n.has_variables = true;
  return std::make_shared<const Node>(std::move(n));
}

NodePtr number_node(double value) {
  Node n;
  n.kind = Node::kNumber;
  n.value = value;
  return std::make_shared<const Node>(std::move(n));
}

NodePtr variable_node(int variable) {
  Node n;
  n.kind = Node::kVariable;
  n.variable = variable;
  n.has_variables = true;
  return std::make_shared<const Node>(std::move(n));
}

NodePtr binary_node(Node::Kind kind, NodePtr a, NodePtr b) {
  Node n;
  n.kind = kind;
  n.has_variables = a->has_variables || b->has_variables;
  n.operands = {std::move(a), std::move(b)};
  return std::make_shared<const Node>(std::move(n));
}

NodePtr call_node(const std::string& name, std::vector<NodePtr> arguments) {
  Node n;
  n.kind = Node::kCall;
  n.name = name;
  n.has_variables = std::any_of(arguments.begin(), arguments.end(), [](const NodePtr& a) { return a->has_variables; });
  n.operands = std::move(arguments);
  return std::make_shared<const Node>(std::move(n));
}

double constant_value(const Node& node) {
  const auto& o = node.operands;
  switch (node.kind) {
    case Node::kNumber:
    case Node::kConstant: return node.value;
    case Node::kVariable: return std::nan("");
    case Node::kAdd: return constant_value(*o[0]) + constant_value(*o[1]);
    case Node::kSubtract: return constant_value(*o[0]) - constant_value(*o[1]);
    case Node::kMultiply: return constant_value(*o[0]) * constant_value(*o[1]);
    case Node::kDivide: return constant_value(*o[0]) / constant_value(*o[1]);
    case Node::kNegate: return -constant_value(*o[0]);
    case Node::kPower: return std::pow(constant_value(*o[0]), constant_value(*o[1]));
    case Node::kCall:
      if (node.name == "atan2") return std::atan2(constant_value(*o[0]), constant_value(*o[1]));
      return unary_function(node.name)(constant_value(*o[0]));
    case Node::kExternal: break;  // has variables
  }
  return std::nan("");
}

namespace {

// a^n by repeated squaring (|n| <= 64): exact for small n, where pow() is slow.
double integer_power(double a, int n) {
  double r = 1, b = a;
  for (unsigned m = static_cast<unsigned>(n < 0 ? -n : n); m; m >>= 1, b *= b)
    if (m & 1) r *= b;
  return n < 0 ? 1 / r : r;
}

std::string key_of(const Instruction& in) {
  std::ostringstream s;
  s << int(in.kind) << ':' << in.a << ',' << in.b << ',' << in.exponent << ','
    << reinterpret_cast<const void*>(in.function1) << reinterpret_cast<const void*>(in.function2)
    << reinterpret_cast<const void*>(in.external) << ',';
  std::uint64_t bits;
  std::memcpy(&bits, &in.constant, sizeof bits);  // the bits: 0.0 and -0.0 differ
  s << bits;
  return s.str();
}

}  // namespace

int Program::add(const Instruction& in) {
  const auto [it, inserted] = registers_.try_emplace(key_of(in), size());
  if (inserted) code_.push_back(in);
  return it->second;
}

int Program::compile(const Node& node) {
  Instruction in;
  if (!node.has_variables) {
    in.kind = Instruction::kConstant;
    in.constant = constant_value(node);
    return add(in);
  }
  const auto& o = node.operands;
  switch (node.kind) {
    case Node::kNumber:
    case Node::kConstant: break;  // no variables: above
    case Node::kVariable: in.kind = Instruction::Kind(Instruction::kX + node.variable); break;
    case Node::kAdd: in.kind = Instruction::kSum; break;
    case Node::kSubtract: in.kind = Instruction::kDifference; break;
    case Node::kMultiply: in.kind = Instruction::kProduct; break;
    case Node::kDivide: in.kind = Instruction::kQuotient; break;
    case Node::kNegate: in.kind = Instruction::kNegate; break;
    case Node::kPower: {
      in.a = compile(*o[0]);
      if (!o[1]->has_variables) {
        const double p = constant_value(*o[1]);
        if (p == std::round(p) && std::abs(p) <= 64) {
          in.kind = Instruction::kIntegerPower;
          in.exponent = static_cast<int>(p);
          return add(in);
        }
      }
      in.kind = Instruction::kPower;
      in.array2 = array_pow();
      in.b = compile(*o[1]);
      return add(in);
    }
    case Node::kExternal:
      in.kind = Instruction::kExternal;
      in.external = node.external.get();
      externals_.push_back(node.external);
      return add(in);
    case Node::kCall:
      in.a = compile(*o[0]);
      if (node.name == "atan2") {
        in.kind = Instruction::kFunction2;
        in.function2 = atan2_of;
        in.array2 = array_atan2();
        in.b = compile(*o[1]);
      } else {
        in.kind = Instruction::kFunction1;
        in.function1 = unary_function(node.name);
        in.array1 = array_function(node.name);
      }
      return add(in);
  }
  if (node.kind != Node::kVariable) {
    in.a = compile(*o[0]);
    if (o.size() > 1) in.b = compile(*o[1]);
  }
  return add(in);
}

std::vector<int> Program::append(const Program& other) {
  externals_.insert(externals_.end(), other.externals_.begin(), other.externals_.end());
  std::vector<int> here(other.code_.size());
  for (std::size_t r = 0; r < other.code_.size(); ++r) {
    Instruction in = other.code_[r];
    if (in.a >= 0) in.a = here[in.a];
    if (in.b >= 0) in.b = here[in.b];
    here[r] = add(in);
  }
  return here;
}

void Program::set_constants(double* r) const {
  for (std::size_t i = 0; i < code_.size(); ++i)
    if (code_[i].kind == Instruction::kConstant) r[i] = code_[i].constant;
}

double Program::run_at(double* r, double x, double y, double z, int output) const {
  const Instruction* code = code_.data();
  const std::size_t size = code_.size();
  for (std::size_t i = 0; i < size; ++i) {
    const Instruction& in = code[i];
    const double a = in.a >= 0 ? r[in.a] : 0.0, b = in.b >= 0 ? r[in.b] : 0.0;
    double& t = r[i];
    switch (in.kind) {
      case Instruction::kConstant: break;  // set once (set_constants)
      case Instruction::kX: t = x; break;
      case Instruction::kY: t = y; break;
      case Instruction::kZ: t = z; break;
      case Instruction::kSum: t = a + b; break;
      case Instruction::kDifference: t = a - b; break;
      case Instruction::kProduct: t = a * b; break;
      case Instruction::kQuotient: t = a / b; break;
      case Instruction::kNegate: t = -a; break;
      case Instruction::kIntegerPower: t = integer_power(a, in.exponent); break;
      case Instruction::kPower: in.array2(&a, &b, &t, 1); break;
      case Instruction::kFunction1:
        if (in.array1) in.array1(&a, &t, 1);
        else t = in.function1(a);
        break;
      case Instruction::kFunction2:
        if (in.array2) in.array2(&a, &b, &t, 1);
        else t = in.function2(a, b);
        break;
      case Instruction::kExternal: (*in.external)(&x, &y, &z, 1, &t); break;
    }
  }
  return r[output];
}

bool Program::operands_within(const double* r, double limit) const {
  for (const Instruction& in : code_) {
    if (in.kind != Instruction::kIntegerPower && in.kind != Instruction::kPower && in.kind != Instruction::kFunction1 &&
        in.kind != Instruction::kFunction2)
      continue;
    for (int operand : {in.a, in.b})
      if (operand >= 0 && !(std::abs(r[operand]) <= limit)) return false;
  }
  return true;
}

void Program::run(std::vector<double>& registers, const double* x, const double* y, const double* z, long n) const {
  registers.resize(code_.size() * static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < code_.size(); ++i) {
    const Instruction& in = code_[i];
    double* t = registers.data() + i * n;
    const double* a = in.a >= 0 ? registers.data() + in.a * n : nullptr;
    const double* b = in.b >= 0 ? registers.data() + in.b * n : nullptr;
    switch (in.kind) {
      case Instruction::kConstant: std::fill(t, t + n, in.constant); break;
      case Instruction::kX: std::copy(x, x + n, t); break;
      case Instruction::kY: std::copy(y, y + n, t); break;
      case Instruction::kZ:
        if (z) std::copy(z, z + n, t);
        else std::fill(t, t + n, 0.0);
        break;
      case Instruction::kSum: for (long k = 0; k < n; ++k) t[k] = a[k] + b[k]; break;
      case Instruction::kDifference: for (long k = 0; k < n; ++k) t[k] = a[k] - b[k]; break;
      case Instruction::kProduct: for (long k = 0; k < n; ++k) t[k] = a[k] * b[k]; break;
      case Instruction::kQuotient: for (long k = 0; k < n; ++k) t[k] = a[k] / b[k]; break;
      case Instruction::kNegate: for (long k = 0; k < n; ++k) t[k] = -a[k]; break;
      case Instruction::kIntegerPower: for (long k = 0; k < n; ++k) t[k] = integer_power(a[k], in.exponent); break;
      case Instruction::kPower: in.array2(a, b, t, n); break;
      case Instruction::kFunction1:
        if (in.array1) in.array1(a, t, n);
        else for (long k = 0; k < n; ++k) t[k] = in.function1(a[k]);
        break;
      case Instruction::kFunction2:
        if (in.array2) in.array2(a, b, t, n);
        else for (long k = 0; k < n; ++k) t[k] = in.function2(a[k], b[k]);
        break;
      case Instruction::kExternal: (*in.external)(x, y, z, n, t); break;
    }
  }
}

}  // namespace knotwork::expression_detail
