#pragma once
#include <gmpxx.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "basis/tmesh/rectangular_partition.hpp"

namespace knotwork {

// PT-splines over an arbitrary T-mesh T (Sec. 3 of the PT-spline paper), highest smoothness
// S(m, n, m-1, n-1, T), by edge extension and Extended Edge Elimination (EEE):
//
// 1. Extension T^e. Minimal (the default): the l-edges of T are inserted as LR meshlines into
//    the tensor mesh of T's cross-cuts, each lengthened only until it splits a B-spline; the
//    local B-splines are the LR B-splines of T^e (basis/pt_minimal_extension.cpp). The result
//    is certified (functions dependent on the others dropped, the rest exactly independent and
//    as many as the brute-force dimension of S(T)) and, should that fail, replaced by the
//    full extension:
//    every horizontal T l-edge and ray is extended to a cross-cut (or every
//    vertical one: the direction with fewer extended edges). This is the extension of the
//    proof of Lemma 2. Over T^e every horizontal line is global, so each f in S(T^e) is
//    f = sum_j g_j(x) N_j(y) with N_j the B-splines on all y-coordinates, and g_j a spline
//    on the x-coordinates of the vertical lines of T that cross all of supp N_j. The basis
//    of S(T^e) is therefore the local tensor-product B-splines M_{j,i}(x) N_j(y).
// 2. EEE: f lies in S(T) iff across every extended edge (a line of T^e inside a cell of T,
//    y = Y_k for the full extension) the jump of d^n f / dy^n (d^m f / dx^m) vanishes. These
//    equations couple only the B-splines whose supports meet the edge; they are split into independent blocks (connected
//    components) and each block's null space is computed exactly over Q.
// 3. The basis of S(T): the B-splines that meet no extended edge, untouched, and one
//    combination per null vector of each block (Theorem 3).
// kAuto: minimal, certified, else the full extension in the direction with fewer extended
// edges. kMinimal: minimal or std::runtime_error (saying why). kHorizontal, kVertical: full.
// kDiagonalizable: the paper's premise, a diagonalizable T^e (by the ordering test of
// tmesh_conformality): the LR extension with every l-edge lengthened by k vertices, the
// smallest k for which T^e passes that test and the result is certified, else
// std::runtime_error. Less local than kMinimal where they differ (docs/PT_SPLINES.md).
enum class PtExtension { kAuto, kMinimal, kHorizontal, kVertical, kDiagonalizable };
// "auto", "minimal", "horizontal", "vertical", "diagonalizable"; nullopt for anything else.
std::optional<PtExtension> parse_pt_extension(const std::string& name);
const char* pt_extension_name(PtExtension extension);

// The B-splines' exact Bernstein factors on the cells of one T-mesh, shared per (knots, cell
// interval) in each direction (pt_cell_polynomials.cpp).
struct PtBernsteinCache;

struct PtLocalBSpline {
  std::vector<mpq_class> x, y;  // m + 2 and n + 2 local knots
};

struct PtSplineBasis {
  int m = 0, n = 0;
  C0Lines c0;  // knots of multiplicity m (in x) or n (in y): the space is only C^0 across them
  PtExtension extension = PtExtension::kHorizontal;  // the one used (never kAuto)
  std::string minimal_refused;  // kAuto fell back to a full extension: why (else empty)
  // The local B-splines the functions combine: the basis of S(T^e), followed by the
  // cross-cut B-splines once make_non_negative has run.
  std::vector<PtLocalBSpline> splines;
  // The basis of S(T): each function a combination (spline index, coefficient).
  std::vector<std::vector<std::pair<int, mpq_class>>> functions;
  long extended_edges = 0;  // pairs (cell of T, line of T^e through its interior)
  long equations = 0, rank = 0;
  int blocks = 0, largest_block = 0;  // EEE blocks; the largest one's number of B-splines
  int untouched = 0;                  // B-splines of T^e kept as they are
  int dropped_dependent = 0;          // minimal extension: functions dropped as dependent on the others
  // Minimal extension: how many functions the EEE null spaces fall short of the dimension of
  // S(T); when > 0 the null vectors were not computed and `functions` is incomplete.
  long short_of_dimension = 0;
  // Minimal extension: the LR B-splines proved linearly independent by peeling, so the
  // functions (independent combinations of them) are independent without cell polynomials:
  // the certificate then used that, else the rank of the cell polynomials.
  bool splines_independent = false;
  std::vector<RationalBox> extension_cells;  // the cells of T^e
  // Filled when the exact cell polynomials are first computed on a T-mesh, reused by later
  // calls on the same T-mesh (a different one replaces it);
  // copies share it. Valid as long as B-splines are only appended, never changed. Calls that
  // use it hold bernstein_lock for their whole computation: safe, and serialized, across threads.
  mutable std::shared_ptr<PtBernsteinCache> bernstein;
  mutable std::shared_ptr<std::mutex> bernstein_lock = std::make_shared<std::mutex>();
};

// The space S(m, n, m-1, n-1) of T, except only C^0 across the lines of `c0` (cross-cuts of T,
// which therefore never get extended: the B-splines carry them as knots of full multiplicity).
// Throws std::invalid_argument for m or n < 1, or a C^0 line that is not a cross-cut of T.
PtSplineBasis pt_spline_basis(const RectangularPartition& mesh, int m, int n,
                              PtExtension extension = PtExtension::kAuto, const C0Lines& c0 = {});

// Each function on each cell of T where it is not zero: (cell, Bernstein coefficients on the
// cell, index a + (m+1) b with a along x). Exact, and in double precision (computed from
// values on the largest piece of the cell where the B-splines are polynomials).
using PtCellPolynomialsExact = std::vector<std::vector<std::pair<int, std::vector<mpq_class>>>>;
using PtCellPolynomials = std::vector<std::vector<std::pair<int, std::vector<double>>>>;
PtCellPolynomialsExact pt_cell_polynomials_exact(const PtSplineBasis& basis, const RectangularPartition& mesh);
PtCellPolynomials pt_cell_polynomials(const PtSplineBasis& basis, const RectangularPartition& mesh);
// The exact coefficients rounded once (no rounding error from the sampling).
PtCellPolynomials to_double(const PtCellPolynomialsExact& exact);

// Value of function f at (x, y), exactly (the combination of its local B-splines).
mpq_class pt_evaluate(const PtSplineBasis& basis, int f, const mpq_class& x, const mpq_class& y);

// Largest jump, over every shared edge of T and every function, of the derivatives that
// S(T) keeps continuous (d^k/dx^k, k < m, across vertical edges; d^k/dy^k, k < n, across
// horizontal ones), sampled at m + n + 2 points per edge from the per-cell polynomials and
// relative to the function's largest Bernstein coefficient (times h^-k of the edge's cells).
// Across edges on the lines of `c0` only the values must agree.
double pt_smoothness_residual(const PtCellPolynomials& polynomials, const RectangularPartition& mesh, int m, int n,
                              const C0Lines& c0 = {});

// Changes the basis (by adding to some functions combinations of others) so that the functions
// that do not vanish on the boundary of the rectangle have linearly independent traces there
// (the BezierMesh contract for Dirichlet data); the others vanish on the whole boundary.
void make_boundary_traces_independent(PtSplineBasis& basis, const RectangularPartition& mesh);

// Exactly independent functions can still be nearly dependent in double precision: on a
// uniformly halved T-mesh the local EEE functions had (degree 3) a combination of norm 1e-6
// of theirs, and (degree 2) CHOLMOD factored the numerically singular stiffness matrix into
// a wrong solution (docs/PT_SPLINES.md). This
// replaces, group by group (functions sharing B-splines; those vanishing on the boundary
// apart from the others, so traces stay as they are), the functions of nearly dependent
// combinations by those combinations, normalized. The span is unchanged and every function
// stays exactly in S(T). See condition_block in pt_spline.cpp.
void make_numerically_independent(PtSplineBasis& basis, const RectangularPartition& mesh);

// Prop. 1: the tensor-product B-splines of the cross-cuts of T (non-negative, a partition of
// unity) replace as many basis functions as they are, and every other function gets
// c times the sum of the cross-cut B-splines over its support, with c = minus its smallest
// Bernstein coefficient, when that is negative: a basis of non-negative functions (their
// Bernstein coefficients are all >= 0). Returns the number of cross-cut B-splines.
int make_non_negative(PtSplineBasis& basis, const RectangularPartition& mesh);

}  // namespace knotwork
