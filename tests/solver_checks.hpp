#pragma once
// What every iterative solve must show against the direct one on the same system: CG stopped at
// its backward-error tolerance, and the algebraic error invisible in the discretization error
// (the L2 and H1 errors agree with CHOLMOD's to 1e-4 relative, far below the gap between levels).
#include <catch2/catch.hpp>
#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "solver/poisson_solver.hpp"

inline void require_direct_errors(const knotwork::PoissonSolution& cg, const knotwork::PoissonSolution& direct) {
  REQUIRE(cg.iterative.converged);
  REQUIRE(cg.errors->l2 == Approx(direct.errors->l2).epsilon(1e-4));
  REQUIRE(cg.errors->h1_semi == Approx(direct.errors->h1_semi).epsilon(1e-4));
}

// CG iterations per degree over three refinements: bounded in h (the finest mesh needs at most
// two more than the coarsest) and in p (no count above `limit`).
inline void require_bounded_in_h_and_p(const std::string& name, const std::map<int, std::vector<int>>& iterations,
                                       int limit) {
  for (const auto& [p, counts] : iterations) {
    INFO(name << ", p = " << p << ": " << counts[0] << ", " << counts[1] << ", " << counts[2]);
    REQUIRE(counts.back() <= counts.front() + 2);
    REQUIRE(*std::max_element(counts.begin(), counts.end()) <= limit);
  }
}
