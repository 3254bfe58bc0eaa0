#include "app/adaptive.hpp"

#include <chrono>
#include <cmath>
#include <optional>

#include "solver/input_error.hpp"

namespace knotwork {

namespace {

// Cells longer than this ratio are halved across their long side only. Halving a square cell
// both ways at once puts two new segments across each other, and Weller's Lemma 3.4 then
// needs one of them to reach d+2 vertices on both sides of the crossing: measured on the
// L-shape, that extended most horizontal segments to full knot lines, the thin strips that
// followed over-marked, and the H1 rate fell below 0.5 beyond ~2000 dofs.
constexpr double kAspect = 1.2;

}  // namespace

std::vector<AdaptiveStep> adapt_case(const CaseDescription& c, Ordering ordering,
                                     const std::function<void(const std::string&)>& progress,
                                     const std::function<void(const AdaptiveStepView&)>& on_step) {
  const bool pt = c.family == "pt";
  if (c.family != "knot_segments" && !pt)
    throw InputError(c.path + ": [space] family: adaptive refinement works by knot segments or PT-splines; set family = "
                     "\"knot_segments\" or \"pt\" (got \"" + c.family + "\")");
  auto say = [&](const std::string& s) {
    if (progress) progress(s);
  };
  say("building the starting space: " + describe_space(c));
  std::vector<RationalBox> cells;  // family "pt": the T-mesh
  if (pt) cells = pt_start_cells(c);
  Discretization first = pt ? discretize_pt(c, cells) : discretize(c);
  // Collections built by insertion are semi-regular by construction; explicit ones were
  // checked by discretize.
  if (!first.violations.empty())
    throw InputError(c.path + ": [space]: adaptive refinement needs a semi-regular start, and the collection is not: " +
                     first.violations.front());
  std::optional<SemiRegularCollection> collection;  // family "knot_segments"
  if (!pt) collection = *first.segments;
  std::vector<AdaptiveStep> steps;
  for (int s = 0; s < c.adapt.steps; ++s) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::string prefix = "step " + std::to_string(s + 1) + "/" + std::to_string(c.adapt.steps) + ": ";
    using clock = std::chrono::steady_clock;
    auto since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
    const Discretization d = s == 0 ? std::move(first) : pt ? discretize_pt(c, cells) : discretize_collection(c, *collection);
    const double t_space = since(t0);
    auto t1 = clock::now();
    const PoissonSolution sol = solve_case(c, d, ordering, [&](const std::string& what) { say(prefix + what); });
    const double t_solve = since(t1);
    say(prefix + "error estimator");
    t1 = clock::now();
    ErrorIndicators ind;
    try {
      ind = residual_indicators(d.mesh(), *d.geometry, sol.coefficients, c.problem);
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": " + e.what());
    }
    AdaptiveStep st;
    st.seconds_space = t_space;
    st.seconds_solve = t_solve;
    st.seconds_estimate = since(t1);
    st.dofs = sol.num_functions;
    st.cells = d.mesh().num_cells();
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
    if (!last) marked = dorfler_marking(ind.eta_squared, c.adapt.theta);
    st.marked = static_cast<int>(marked.size());
    if (on_step) on_step({s, d, sol, ind, marked, pt ? nullptr : &*collection, pt ? d.tmesh.get() : nullptr});
    if (!last) {
      say(prefix + "refining " + std::to_string(marked.size()) + " marked cells " +
          (pt ? "of the T-mesh" : "by knot segments"));
      std::vector<SemiRegularCollection::Split> split;
      Eigen::VectorXd mu(4), mv(4);
      mu << 0, 1, 0.5, 0.5;
      mv << 0.5, 0.5, 0, 1;
      GeometryAtPoints g;
      for (int m : marked) {
        d.geometry->evaluate(m, mu, mv, g);
        const double eu = (g.x.row(1) - g.x.row(0)).norm(), ev = (g.x.row(3) - g.x.row(2)).norm();
        split.push_back(eu > kAspect * ev   ? SemiRegularCollection::kSplitX
                        : ev > kAspect * eu ? SemiRegularCollection::kSplitY
                        : s % 2 == 0        ? SemiRegularCollection::kSplitX
                                            : SemiRegularCollection::kSplitY);
      }
      t1 = clock::now();
      if (pt) {
        // The BezierMesh cells are the T-mesh cells, in order: halve the marked ones.
        for (size_t k = 0; k < marked.size(); ++k) {
          RationalBox& a = cells[marked[k]];
          RationalBox b = a;
          if (split[k] == SemiRegularCollection::kSplitX) a.x1 = b.x0 = (a.x0 + a.x1) / 2;
          else a.y1 = b.y0 = (a.y0 + a.y1) / 2;
          cells.push_back(b);
        }
      } else {
        for (const auto& r : collection->refine_cells(marked, split)) st.extended += r.extended;
      }
      st.seconds_refine = since(t1);
    }
    st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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
