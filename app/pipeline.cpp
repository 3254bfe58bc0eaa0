#include "app/pipeline.hpp"

#include "solver/input_error.hpp"

namespace knotwork {

std::unique_ptr<SplineSpace> build_space(const CaseDescription& c, int level, const ProgressFunction& progress) {
  return space_family(c).build(c, level, progress);
}

PoissonSolution solve_case(const CaseDescription& c, const SplineSpace& space, Ordering ordering,
                           const ProgressFunction& progress) {
  space.check_solvable();
  PoissonSolveOptions so;
  so.quadrature = c.quadrature;
  so.ordering = ordering;
  so.progress = progress;
  so.cell_errors = true;
  try {
    return solve_poisson(space.mesh(), space.geometry(), c.problem, so);
  } catch (const GeometryError& e) {
    throw InputError(c.path + ": [geometry]: " + e.what());
  } catch (const InputError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": " + e.what());
  }
}

// Written as a case file, so that it is read and validated like one.
CaseDescription unit_square_benchmark_case(int p, int n) {
  const std::string text = "[geometry]\ntype = \"rectangle\"\n[space]\ndegree = " + std::to_string(p) +
                           "\nelements = " + std::to_string(n) + "\n[problem]\nexact = \"sin(pi*x)*sin(pi*y)\"\n";
  return load_case_text(text, "bench");
}

}  // namespace knotwork
