// User expressions ([problem] exact, source, dirichlet, neumann): read by the grammar,
// evaluated, differentiated symbolically by GiNaC as an exact solution, and the derived
// expressions compiled into the batch program the solver evaluates at quadrature points.
#include <string>

#include "fuzz/fuzz_input.hpp"
#include "solver/expression.hpp"
#include "basis/core/input_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const knotwork::Expression e = knotwork::Expression::parse(text, "fuzz: [problem] exact");
    knotwork::ExpressionEvaluator evaluate(e);
    evaluate(0.25, 0.5);
    evaluate(-1.0, 0.0, 2.0);
    const knotwork::ExactSolution u = knotwork::differentiate_exact_solution(e);
    knotwork::ExpressionBatch batch({u.u, u.u_x, u.u_y, u.minus_laplacian});
    const double x[3] = {0.1, 0.5, 0.9}, y[3] = {0.3, 0.7, 0.2};
    batch.evaluate(x, y, nullptr, 3);
  } catch (const knotwork::InputError&) {
  }
  return 0;
}
