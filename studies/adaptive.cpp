#include "studies/adaptive.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "solver/nested_multigrid.hpp"

#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// Cells longer than this ratio are halved across their long side only. Halving a square cell
// both ways at once puts two new segments across each other, and Weller's Lemma 3.4 then
// needs one of them to reach d+2 vertices on both sides of the crossing: measured on the
// L-shape, that extended most horizontal segments to full knot lines, the thin strips that
// followed over-marked, and the H1 rate fell below 0.5 beyond ~2000 dofs.
constexpr double kAspect = 1.2;

// Multigrid over the steps stops CG once its estimate of the algebraic error's energy norm is
// below this fraction of the previous step's error estimate (docs/ADAPTIVITY.md: measured).
constexpr double kAlgebraicFraction = 0.02;

}  // namespace

std::vector<AdaptiveStep> adapt_case(const CaseDescription& c, Ordering ordering, const ProgressFunction& progress,
                                     const std::function<void(const AdaptiveStepView&)>& on_step) {
  const SpaceFamily& family = space_family(c);
  check_adaptive_family(c);
  auto say = [&](const std::string& s) {
    if (progress) progress(s);
  };
  const std::string& method = c.solver.method;
  if (c.solver.preconditioner == "multigrid" && method != "auto" && method != "iterative")
    throw InputError(c.path + ": [solver] preconditioner: \"multigrid\" in adapt is multigrid over the steps, in "
                     "knotwork's CG: method = \"" + method + "\" does not run it (use \"auto\" or \"iterative\")");
  say("building the starting space ([space] family = \"" + c.family + "\")");
  using clock = std::chrono::steady_clock;
  auto since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  auto t_start = clock::now();
  std::unique_ptr<SplineSpace> space = family.build(c, 0, say);
  // Multigrid over the steps (docs/ADAPTIVITY.md): the family keeps each refinement's
  // prolongation, every step's matrix becomes a level, and CG starts from the last solution.
  // Asked for by name, or "auto" (measured faster than CHOLMOD and BoomerAMG on the loops of
  // docs/ADAPTIVITY.md, where the family says so) where the family keeps prolongations and CG
  // is allowed.
  std::optional<AdaptiveSolve> over_steps;
  const std::vector<std::string> own = space->structured_preconditioners();
  if (std::find(own.begin(), own.end(), "multigrid") == own.end()) {
    const bool asked = c.solver.preconditioner == "multigrid";
    const bool automatic = c.solver.preconditioner == "auto" && (method == "auto" || method == "iterative") &&
                           space->multigrid_over_steps_is_automatic();
    if ((asked || automatic) && space->keep_prolongations()) {
      over_steps.emplace();
      over_steps->multigrid = std::make_shared<NestedMultigrid>();
    } else if (asked) {
      throw InputError(c.path + ": [solver] preconditioner: \"multigrid\" in adapt is multigrid over the steps, which needs "
                       "a family whose refinement gives its prolongation (docs/ADAPTIVITY.md names them); family \"" + c.family +
                       "\" does not: use \"boomeramg\" or \"auto\"");
    }
  }
  double t_space = since(t_start);
  const Marking marking{c.adapt.maximum_strategy ? Marking::Strategy::kMaximum : Marking::Strategy::kDorfler,
                        c.adapt.theta, c.adapt.min_fraction};
  std::vector<AdaptiveStep> steps;
  for (int s = 0; s < c.adapt.steps; ++s) {
    const auto t0 = clock::now();
    const std::string prefix = "step " + std::to_string(s + 1) + "/" + std::to_string(c.adapt.steps) + ": ";
    AdaptiveStep st;
    st.notes = space->presentation().notes();
    for (const auto& n : st.notes) say(prefix + "note: " + n);
    if (over_steps) {
      // Below a fraction of the last step's estimate, the algebraic error is lost in the
      // discretization's; the last step is solved to the backward error [solver] tolerance.
      const bool last_step = s + 1 == c.adapt.steps || space->mesh().num_functions() >= c.adapt.max_dofs;
      over_steps->energy_tolerance = steps.empty() || last_step ? 0 : kAlgebraicFraction * steps.back().estimator;
    }
    auto t1 = clock::now();
    SolverReport solver;
    const PoissonSolution sol = solve_case(c, *space, ordering, [&](const std::string& what) { say(prefix + what); }, &solver,
                                           over_steps ? &*over_steps : nullptr);
    st.solver = solver.method == "direct" ? solver.method : solver.method + ", " + solver.preconditioner;
    st.solver_note = solver.note;
    const double t_solve = since(t1);
    say(prefix + "error estimator");
    t1 = clock::now();
    ErrorIndicators ind;
    try {
      ind = residual_indicators(space->mesh(), space->geometry(), sol.coefficients, c.problem);
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": " + e.what());
    }
    st.seconds_space = t_space;
    st.seconds_solve = t_solve;
    st.solve_phases = sol.timings;
    st.seconds_estimate = since(t1);
    st.iterations = sol.iterative.iterations;
    st.dofs = sol.num_functions;
    st.cells = space->mesh().num_cells();
    st.estimator = std::sqrt(ind.total());
    st.l2 = st.h1_semi = st.h1_rate = NAN;
    if (sol.errors) {
      st.l2 = sol.errors->l2;
      st.h1_semi = sol.errors->h1_semi;
      if (!steps.empty() && st.dofs > steps.back().dofs)
        st.h1_rate = std::log(steps.back().h1_semi / st.h1_semi) / std::log(double(st.dofs) / steps.back().dofs);
    }
    const bool last = s + 1 == c.adapt.steps || st.dofs >= c.adapt.max_dofs;
    std::vector<int> marked;
    if (!last) marked = c.adapt.mark_functions ? cells_of_marked_functions(space->mesh(), ind.eta_squared, marking)
                                               : mark(ind.eta_squared, marking);
    st.marked = static_cast<int>(marked.size());
    if (on_step) on_step({s, *space, sol, ind, marked, last});
    if (!last) {
      say(prefix + "refining " + std::to_string(marked.size()) + " marked cells");
      std::vector<CellSplit> split;
      Eigen::VectorXd mu(4), mv(4);
      mu << 0, 1, 0.5, 0.5;
      mv << 0.5, 0.5, 0, 1;
      GeometryAtPoints g;
      // A volume's refinement halves hexahedra in every direction: no direction to choose.
      if (space->geometry().parametric_dimension() == 2) {
        for (int m : marked) {
          space->geometry().evaluate(m, mu, mv, g);
          const double eu = (g.x.row(1) - g.x.row(0)).norm(), ev = (g.x.row(3) - g.x.row(2)).norm();
          split.push_back(eu > kAspect * ev   ? CellSplit::kAcrossU
                          : ev > kAspect * eu ? CellSplit::kAcrossV
                          : s % 2 == 0        ? CellSplit::kAcrossU
                                              : CellSplit::kAcrossV);
        }
      }
      t1 = clock::now();
      std::unique_ptr<SplineSpace> next =
          std::move(*space).refine(marked, split, &st.extended, [&](const std::string& what) { say(prefix + what); });
      if (!next)
        throw InputError(c.path + ": [space] family: \"" + c.family + "\" cannot refine marked cells");
      // The family's refinement builds the next space too: both are this step's refinement time.
      st.seconds_refine = since(t1);
      t_space = 0;
      space = std::move(next);
      if (over_steps) {
        const Eigen::SparseMatrix<double>* P = space->prolongation_from_predecessor();
        if (!P || P->cols() != sol.coefficients.size())
          throw std::logic_error("multigrid over adaptive steps: the refined space kept no prolongation");
        over_steps->initial = *P * sol.coefficients;
      }
    }
    st.seconds = std::chrono::duration<double>(clock::now() - t0).count();
    steps.push_back(st);
    if (last) break;
  }
  return steps;
}

double fitted_h1_rate(const std::vector<AdaptiveStep>& steps, size_t first) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0;
  for (size_t k = first; k < steps.size(); ++k) {
    const double x = std::log(double(steps[k].dofs)), y = std::log(steps[k].h1_semi);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    n += 1;
  }
  return -(n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace knotwork
