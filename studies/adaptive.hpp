#pragma once
#include <functional>
#include <string>
#include <vector>

#include "studies/pipeline.hpp"
#include "solver/residual_estimator.hpp"

namespace knotwork {

// One solve of the adaptive loop.
struct AdaptiveStep {
  int dofs = 0, cells = 0, marked = 0, extended = 0;  // extended: what the family added beyond the marked cells
  double estimator = 0;                               // sqrt(sum of eta_K^2)
  double l2 = 0, h1_semi = 0;                         // NaN without an exact solution
  double h1_rate = 0;                                 // against dofs, from the previous step (NaN first)
  double seconds = 0;  // the whole step, output included
  // Phases of the step: building the space (the first step only), the solve (assembly,
  // CHOLMOD, error norms), the estimator, and the refinement that makes the next step's
  // space (the family's refinement and the construction of the refined space).
  double seconds_space = 0, seconds_solve = 0, seconds_estimate = 0, seconds_refine = 0;
  PoissonTimings solve_phases;  // the solve's own phases (assembly, the linear solve, errors)
  int iterations = 0;           // CG's iterations (0: a direct solve)
  // How its linear system was solved ("direct", "iterative, multigrid": SolverReport's method
  // and preconditioner) and why, when "auto" decided.
  std::string solver, solver_note;
  std::vector<std::string> notes;  // the family's notes on this step's space
};

// What a step hands to its observer (for output) before the space is refined.
struct AdaptiveStepView {
  int step;
  const SplineSpace& space;
  const PoissonSolution& solution;
  const ErrorIndicators& indicators;
  const std::vector<int>& marked;
  bool last;  // no refinement follows
};

// Solve - estimate - mark - refine, c.adapt.steps times or until c.adapt.max_dofs: the
// residual estimator, Doerfler marking with c.adapt.theta, and the family's refinement of
// the marked cells (each cell halved across its longer physical side, or alternately in x
// and y when it is about square). Throws InputError for families that cannot refine locally.
std::vector<AdaptiveStep> adapt_case(const CaseDescription& c, Ordering ordering, const ProgressFunction& progress,
                                     const std::function<void(const AdaptiveStepView&)>& on_step = {});

// Least-squares slope of -log(H1 error) against log(dofs) over steps [first, end): the
// observed rate N^(-rate).
double fitted_h1_rate(const std::vector<AdaptiveStep>& steps, size_t first);

}  // namespace knotwork
