// Expressions: read once into the tree of expression_tree.hpp, compiled once into its program;
// the evaluators run that program. The symbolic side is expression_symbolic.cpp.
#include "solver/expression.hpp"

#include <map>
#include <sstream>
#include <stdexcept>

#include "basis/core/input_error.hpp"
#include "solver/expression_tree.hpp"

namespace knotwork {

using expression_detail::CompiledExpression;
using expression_detail::Node;

Expression Expression::from_tree(std::string text, std::string where, std::shared_ptr<const Node> tree) {
  Expression e;
  e.text_ = std::move(text);
  e.where_ = std::move(where);
  auto compiled = std::make_shared<CompiledExpression>();
  compiled->output = compiled->program.compile(*tree);
  e.tree_ = std::move(tree);
  e.compiled_ = std::move(compiled);
  return e;
}

Expression Expression::parse(const std::string& text, const std::string& where) {
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) throw InputError(where + ": expression is empty");
  try {
    return from_tree(text, where, expression_detail::parse_tree(text));
  } catch (const expression_detail::ParseError& e) {
    const std::string shown = text.size() > 80 ? text.substr(0, 77) + "..." : text;
    throw InputError(where + ": cannot parse \"" + shown + "\": " + e.message + " at character " +
                     std::to_string(e.position + 1));
  }
}

Expression Expression::constant(double value) {
  std::ostringstream s;
  s.precision(17);
  s << value;
  return from_tree(s.str(), "constant", expression_detail::number_node(value));
}

namespace {
// The names an ExternalFunctionNames on this thread holds (null: none alive).
thread_local std::map<std::string, std::shared_ptr<const ExternalFunction>>* external_names = nullptr;
}  // namespace

ExternalFunctionNames::ExternalFunctionNames() {
  if (external_names) throw std::logic_error("ExternalFunctionNames: one per thread at a time");
  external_names = new std::map<std::string, std::shared_ptr<const ExternalFunction>>();
}

ExternalFunctionNames::~ExternalFunctionNames() {
  delete external_names;
  external_names = nullptr;
}

std::string ExternalFunctionNames::add(std::shared_ptr<const ExternalFunction> f) {
  const std::string name = "python_function_" + std::to_string(external_names->size());
  (*external_names)[name] = std::move(f);
  return name;
}

std::shared_ptr<const ExternalFunction> ExternalFunctionNames::find(const std::string& name) {
  if (!external_names) return nullptr;
  const auto it = external_names->find(name);
  return it == external_names->end() ? nullptr : it->second;
}

Expression Expression::external(std::shared_ptr<const ExternalFunction> f, const std::string& text,
                                const std::string& where) {
  return from_tree(text, where, expression_detail::external_node(std::move(f)));
}

struct ExpressionEvaluator::Impl {
  std::shared_ptr<const CompiledExpression> compiled;
  std::vector<double> registers;
};

ExpressionEvaluator::ExpressionEvaluator(const Expression& e) : impl_(std::make_unique<Impl>()) {
  if (e.empty()) throw std::logic_error("ExpressionEvaluator of an empty expression");
  impl_->compiled = e.compiled();  // immutable: shared
  impl_->registers.resize(impl_->compiled->program.size());
  impl_->compiled->program.set_constants(impl_->registers.data());
}
ExpressionEvaluator::~ExpressionEvaluator() = default;
ExpressionEvaluator::ExpressionEvaluator(ExpressionEvaluator&&) noexcept = default;

double ExpressionEvaluator::operator()(double x, double y) { return (*this)(x, y, 0.0); }

double ExpressionEvaluator::operator()(double x, double y, double z) {
  const CompiledExpression& c = *impl_->compiled;
  return c.program.run_at(impl_->registers.data(), x, y, z, c.output);
}

struct ExpressionBatch::Impl {
  std::shared_ptr<const expression_detail::Program> program;
  std::vector<int> output;  // per expression, its register
  std::vector<double> registers;
  long n = 0;
};

ExpressionBatch::ExpressionBatch(const std::vector<Expression>& expressions) : impl_(std::make_unique<Impl>()) {
  auto program = std::make_shared<expression_detail::Program>();
  for (const Expression& e : expressions) {
    if (e.empty()) throw std::logic_error("ExpressionBatch of an empty expression");
    impl_->output.push_back(program->append(e.compiled()->program)[e.compiled()->output]);
  }
  impl_->program = std::move(program);
}

ExpressionBatch::ExpressionBatch(const ExpressionBatch& other) : impl_(std::make_unique<Impl>()) {
  impl_->program = other.impl_->program;  // immutable: shared
  impl_->output = other.impl_->output;
}

ExpressionBatch::~ExpressionBatch() = default;
ExpressionBatch::ExpressionBatch(ExpressionBatch&&) noexcept = default;

void ExpressionBatch::evaluate(const double* x, const double* y, const double* z, long n) {
  impl_->program->run(impl_->registers, x, y, z, n);
  impl_->n = n;
}

const double* ExpressionBatch::result(int e) const {
  return impl_->registers.data() + static_cast<std::size_t>(impl_->output[e]) * impl_->n;
}

}  // namespace knotwork
