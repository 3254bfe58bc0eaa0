#pragma once
// The one grammar of user expressions, the tree it reads a text into, and the one program that
// evaluates trees at arrays of points. Internal to solver/expression*.cpp.
//
// Written by hand because no Debian library gives both things the solver needs from one
// reading: muParser evaluates but gives no tree to differentiate; GiNaC differentiates but
// its parser reads a sign after '^' as the sign of the rest of the group (2^-1*3 is 2^(-3)
// to it, 1.5 to everyone else). The tree below is read once; GiNaC differentiates it
// (expression_symbolic.cpp) and the program evaluates it, so both mean the same function.
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "solver/expression.hpp"
#include "solver/vector_math.hpp"

namespace knotwork::expression_detail {

struct Node;
using NodePtr = std::shared_ptr<const Node>;

struct Node {
  enum Kind { kNumber, kConstant, kVariable, kAdd, kSubtract, kMultiply, kDivide, kNegate, kPower, kCall, kExternal };
  Kind kind = kNumber;
  double value = 0;       // kNumber, kConstant: the value in double
  std::string name;       // kNumber: the literal as written (GiNaC reads it exactly); kConstant
                          // ("pi", "e") and kCall: the name
  int variable = 0;       // kVariable: 0 = x, 1 = y, 2 = z
  std::vector<NodePtr> operands;
  std::shared_ptr<const ExternalFunction> external;  // kExternal: the caller's function of (x, y, z)
  long begin = -1, end = -1;  // the span of the text it was read from; -1 if derived
  bool has_variables = false;
};

// Reads text by the grammar documented in expression.hpp. Throws ParseError.
struct ParseError {
  std::string message;
  long position;  // 0-based
};
NodePtr parse_tree(const std::string& text);

// The longest text a user may give: the tree and its derivatives are built recursively.
constexpr std::size_t kMaxExpressionLength = 4096;

NodePtr number_node(double value);
NodePtr external_node(std::shared_ptr<const ExternalFunction> f);
NodePtr variable_node(int variable);
NodePtr binary_node(Node::Kind kind, NodePtr a, NodePtr b);
NodePtr call_node(const std::string& name, std::vector<NodePtr> arguments);
// The functions of one argument, and whether name is one.
bool is_unary_function(const std::string& name);
// The value of a tree without variables, in double.
double constant_value(const Node& node);

// A straight-line program over arrays of points: register i holds, at every point, the value of
// instruction i. Equal instructions (same kind, operands and constant) share a register.
struct Instruction {
  enum Kind { kConstant, kX, kY, kZ, kSum, kDifference, kProduct, kQuotient, kNegate, kIntegerPower,
              kPower, kFunction1, kFunction2, kExternal };
  Kind kind = kConstant;
  int a = -1, b = -1;  // operand registers
  double constant = 0;
  int exponent = 0;
  double (*function1)(double) = nullptr;
  double (*function2)(double, double) = nullptr;
  // The array forms, where solver/vector_math has them (then used at one point too, so that
  // both runs give the same bits).
  ArrayFunction1 array1 = nullptr;
  ArrayFunction2 array2 = nullptr;
  const ExternalFunction* external = nullptr;  // kExternal (kept alive by its program)
};

class Program {
 public:
  // Appends the instructions of node (constants folded in double); returns its register.
  int compile(const Node& node);
  // Appends another program's instructions, sharing the equal ones; element r of the result is
  // the register here of `other`'s register r.
  std::vector<int> append(const Program& other);
  int size() const { return static_cast<int>(code_.size()); }
  // registers is resized to size() * n; register i at point k is registers[i * n + k].
  void run(std::vector<double>& registers, const double* x, const double* y, const double* z, long n) const;
  // The same at one point, without the per-array work; returns register `output`. registers
  // must hold size() values, with the constants written once by set_constants.
  void set_constants(double* registers) const;
  double run_at(double* registers, double x, double y, double z, int output) const;
  // After run_at: whether every operand of a power or a function is finite and within limit.
  bool operands_within(const double* registers, double limit) const;

 private:
  int add(const Instruction& in);
  std::vector<Instruction> code_;
  std::vector<std::shared_ptr<const ExternalFunction>> externals_;  // what kExternal points to
  std::unordered_map<std::string, int> registers_;  // an instruction's key -> its register
};

// The register of an expression's value inside its own program.
struct CompiledExpression {
  Program program;
  int output = 0;
};

}  // namespace knotwork::expression_detail
