#include "studies/adaptive.hpp"

#include <chrono>
#include <cmath>
#include <optional>

#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// Cells longer than this ratio are halved across their long side only. Halving a square cell
// both ways at once puts two new segments across each other, and Weller's Lemma 3.4 then
// needs one of them to reach d+2 vertices on both sides of the crossing: measured on the
// L-shape, that extended most horizontal segments to full knot lines, the thin strips that
// followed over-marked, and the H1 rate fell below 0.5 beyond ~2000 dofs.
constexpr double kAspect = 1.2;

}  // namespace

std::vector<AdaptiveStep> adapt_case(const CaseDescription& c, Ordering ordering, const ProgressFunction& progress,
                                     const std::function<void(const AdaptiveStepView&)>& on_step) {
  const SpaceFamily& family = space_family(c);
  check_adaptive_family(c);
  auto say = [&](const std::string& s) {
    if (progress) progress(s);
  };
  say("building the starting space ([space] family = \"" + c.family + "\")");
  using clock = std::chrono::steady_clock;
  auto since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  auto t_start = clock::now();
  std::unique_ptr<SplineSpace> space = family.build(c, 0, say);
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
    auto t1 = clock::now();
    const PoissonSolution sol = solve_case(c, *space, ordering, [&](const std::string& what) { say(prefix + what); });
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
