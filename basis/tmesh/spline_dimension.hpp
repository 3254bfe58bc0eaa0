#pragma once
#include <cstdint>

#include <vector>

#include "basis/exact/sparse_rank.hpp"
#include "basis/tmesh/rectangular_partition.hpp"

namespace knotwork {

// Brute-force dimension of S(m, n, alpha, beta) over a rectangular partition: piecewise
// polynomials of bi-degree (m, n), C^alpha in x across vertical edges and C^beta in y
// across horizontal ones. Unknowns: the (m+1)(n+1) monomial coefficients of every cell.
// Constraints: d^k/dx^k (p_left - p_right)(x0, y) = 0 as a polynomial in y (k <= alpha) on
// every shared vertical segment, likewise in y. Dimension = unknowns - rank.
// This is the oracle the spline constructions are tested against.
struct DimensionResult {
  long unknowns = 0;
  long constraints = 0;
  long rank = 0;
  long dimension = 0;
  bool exact = false;  // rank over Q by rational elimination (asked for, or the primes disagreed)
};

enum class RankMethod {
  kModular,  // sparse elimination modulo two 61-bit primes (fast); over Q if they disagree
  kExact,    // elimination over Q with GMP rationals (exact; for small partitions)
};

// Largest brute force done: unknowns = cells x (m+1)(n+1). Measured on this project's 2-core
// machine (docs/RELIABILITY.md): 262 144 unknowns (16 384 bicubic cells) in 39 s and 0.8 GB
// modulo two primes; 65 536 in 60 s and 0.5 GB over Q. The limits keep a run near a minute,
// where the cost grows faster than the size.
constexpr long kMaxBruteForceUnknowns = 400000;
// The brute-force system: the piecewise polynomials of bi-degree (m, n) on the cells (unknowns
// cell * (m+1)(n+1) + i + (m+1) j, coefficients of x^i y^j), and one row per condition of C^alpha
// across each vertical and C^beta across each horizontal shared edge (C^0 on the lines of c0).
std::vector<SparseRationalRow> smoothness_constraints(const RectangularPartition& part, int m, int n, int alpha,
                                                      int beta, const C0Lines& c0 = {});
constexpr long kMaxExactBruteForceUnknowns = 80000;

// The commands that offer the brute force as a check (`dimension`, `basis`) call this first:
// std::length_error, saying the size and the limit, above the limit of the method.
void check_brute_force_size(long cells, int m, int n, RankMethod method);

// Throws std::invalid_argument for degrees < 0 or smoothness outside [-1, degree-1].
// Edges on the lines of `c0` are only C^0.
DimensionResult spline_space_dimension(const RectangularPartition& partition, int m, int n, int alpha,
                                       int beta, RankMethod method = RankMethod::kModular,
                                       const C0Lines& c0 = {});

}  // namespace knotwork
