#pragma once
#include <gmpxx.h>

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "basis/exact/sparse_rank.hpp"
#include "basis/g1/quad_mesh.hpp"

namespace knotwork {

// An exact number c0 + sum_i c_i 2cos(pi r_i) with rational c and r: the values of the
// symmetric gluing data at vertices whose 2cos(2 pi / n) is irrational (valence 5, 7, 8, ...).
// They lie in the cyclotomic field Q(zeta_2M), M the least common denominator of the r_i, so
// the G1 conditions can be reduced modulo a prime p = 1 (mod 2M) (sparse_rank.hpp).
struct CosineSum {
  mpq_class rational;
  std::map<mpq_class, mpq_class> cosines;  // r in [0, 2) -> the coefficient of 2cos(pi r)
  CosineSum(long v = 0) : rational(v) {}
  CosineSum(const mpq_class& v) : rational(v) {}
  static CosineSum two_cos_pi(long p, long q);  // 2cos(pi p / q)
  double value() const;
  // The image in Z/prime with zeta = a primitive 2M-th root of unity there
  // (2cos(pi a / b) -> zeta^(aM/b) + zeta^(-aM/b)); M must be a multiple of every r's denominator.
  uint64_t residue(const ResidueMap& residue_of, uint64_t zeta, long M) const;
  long denominators_lcm() const;  // of the r_i (1 if none)
  CosineSum operator-() const;
  CosineSum& operator+=(const CosineSum& o);
  CosineSum& operator*=(const mpq_class& x);
  friend CosineSum operator+(CosineSum a, const CosineSum& b) { return a += b; }
  friend CosineSum operator-(CosineSum a, const CosineSum& b) { return a += -b; }
  friend CosineSum operator*(const mpq_class& x, CosineSum a) { return a *= x; }
  friend CosineSum operator*(long x, CosineSum a) { return a *= mpq_class(x); }
  friend CosineSum operator*(CosineSum a, const mpq_class& x) { return a *= x; }
  friend CosineSum operator/(CosineSum a, long x) { return a *= mpq_class(1, x); }
};

// A function on [0, 1] that is a polynomial on [0, 1/2] and on [1/2, 1], each piece given
// by its coefficients in powers of u (the global parameter, not shifted). Exact rational
// coefficients when the data are rational (`exact`), exact sums of cosines when they are
// those (`algebraic`), doubles always.
struct PiecewisePolynomial {
  std::array<std::vector<double>, 2> pieces;
  std::optional<std::array<std::vector<mpq_class>, 2>> exact;
  std::optional<std::array<std::vector<CosineSum>, 2>> algebraic;
  static PiecewisePolynomial constant(const mpq_class& v);
  static PiecewisePolynomial from_exact(std::array<std::vector<mpq_class>, 2> pieces);
  static PiecewisePolynomial from_algebraic(std::array<std::vector<CosineSum>, 2> pieces);
  static PiecewisePolynomial from_double(std::array<std::vector<double>, 2> pieces);
  double operator()(double u) const;
  mpq_class exact_value(const mpq_class& u) const;  // requires exact
  // The value at a rational u modulo a prime (requires exact or algebraic; see CosineSum).
  uint64_t residue(const mpq_class& u, const ResidueMap& residue_of, uint64_t zeta, long M) const;
  int degree() const;
};

// Gluing data [a, b, c] of every interior edge, in the edge's own orientation: u = 0 at
// QuadMesh::Edge::v[0]. Across the edge, with f1 on edge.face[0] and f0 on edge.face[1] in
// their corner frames at v[0] (docs/MATH.md §2):
//   f1(u, 0) = f0(0, u),   c(u) dv f1(u, 0) = b(u) du f0(0, u) + a(u) dv f0(0, u).
struct EdgeGluing {
  PiecewisePolynomial a, b, c;
};
struct GluingData {
  std::vector<std::optional<EdgeGluing>> edges;  // per mesh edge; empty on boundary edges
  bool exact() const;                            // every coefficient rational
  bool algebraic() const;                        // every coefficient rational or a CosineSum
  long cosine_denominators_lcm() const;          // M for CosineSum::residue over all the data
  // analysis_suitable_gluing on a surface: the crossing vertices (0-based) given a skewed fan
  // because the linear symmetric data fail Condition 3.2 there.
  std::vector<int> skewed_fans;
  std::string skewed_fans_list() const;  // "12, 13, ..." (1-based, the first 12) for messages
};

// The symmetric gluing (Blidia-Mourrain-Villamizar eq. 11) with Hermite functions of degree 2,
// C^0 at 1/2: a = 2cos(2pi/n0) d0(u) - 2cos(2pi/n1) d1(u), b = -1, c = 1, n the number of
// edges at each end; at a boundary vertex shared by F faces the angle pi/F replaces 2pi/n.
// kC1: the Hermite functions C^1 at 1/2 instead (d0 = 1 - 2u^2 | 2(1-u)^2): with a C^1 split
// (r >= 1) the paper's C^0 blend forces every G1 geometry to be singular at the midpoint of an
// edge whose a has a kink there (docs/G1_POISSON.md); these data do not. kLinear: d0 = 1 - u,
// d1 = u, one polynomial on the edge (analysis-suitable by degree: analysis_suitable_gluing
// on surfaces).
enum class SymmetricBlend { kC0, kC1, kLinear };
GluingData symmetric_gluing(const QuadMesh& mesh, SymmetricBlend blend = SymmetricBlend::kC0);

// The general construction (eqs. 8 and 10, c = 1) from a fan of vectors per vertex: the
// mesh's own edge directions, projected to the tangent plane at the vertex. At each end,
// a and b take the values of eq. (8) and are blended along the edge by the Hermite
// functions d0, d1 of degree 2, C^1 at 1/2 (d0 + d1 = 1), so Condition 3.1 holds by
// construction and constant data stay constant. On planar meshes whose coordinates are
// multiples of 2^-20 (e.g. 0.375, 1.25) the data are exact rationals; otherwise floating
// point.
// Throws std::invalid_argument naming the vertex where two consecutive edges are parallel.
// regular_fans_where_rational ("regular_fans" in files): at interior vertices where the
// symmetric angle 2pi/n has a rational cosine (valence 3, 4, 6) the regular fan's values
// a = 2cos(2pi/n), b = -1 replace the mesh's own directions, so that the data stay exact (on
// meshes with short binary coordinates) and as regular as the symmetric ones where they can;
// they follow the mesh at the other vertices (e.g. valence 5) and on the boundary (so that a
// corner of the domain stays a corner and a straight side stays straight).
GluingData geometric_gluing(const QuadMesh& mesh, bool regular_fans_where_rational = false);

// Analysis-suitable data (Collin-Sangalli-Takacs; docs/G1_POISSON.md) from the bilinear faces
// of a planar mesh: with G0, G1 the maps of the edge's two faces in their corner frames,
// c(u) = det J of G0 at (0, u), b(u) = -det J of G1 at (u, 0), a(u) = det(du G0(0, u), dv G1(u, 0)):
// b and c linear, a quadratic, one polynomial on the whole edge; the bilinear faces satisfy
// the G1 conditions with them (they are in the space) and Condition 3.1 holds at every vertex.
// Exact rationals always (a double coordinate is one). On a surface mesh (not planar): the
// linear symmetric data a(u) = 2cos(2pi/n0)(1 - u) - 2cos(2pi/n1) u, b = -1, c = 1, which are
// compatible at every vertex unless a crossing (valence-4) vertex has opposite neighbours of
// different valences: Condition 3.2 then fails there, and such a vertex gets a skewed fan
// instead of the square one (edge directions (1, 0), (0, 1), (-1, -1/8), (1/8, -1): no two
// opposite, so not a crossing), its edges a and b linear between the two ends' values (still
// analysis-suitable), until no crossing fails (`skewed_fans` lists them). Throws
// std::invalid_argument for a planar face that is not a convex counter-clockwise quad (naming
// it).
GluingData analysis_suitable_gluing(const QuadMesh& mesh);

// The data of an edge as seen from its other end: (a, b, c)(u) -> (a, c, b)(1 - u).
EdgeGluing reversed(const EdgeGluing& g);

// Condition 3.1 at every interior vertex: the product of [[0, 1], [b_i(0), a_i(0)]] over the
// edges around it (a = a/c, b = b/c at the vertex's end) is the identity. Returns one
// message per failing vertex ("vertex 5 (valence 3): product [[...]] is not the identity").
// At a crossing vertex (valence 4, a = 0 at it on every edge) also Condition 3.2, eqs. (6)
// and (7) ("vertex 5 (crossing, valence 4): Condition 3.2 fails ...").
// Also reports interior edges without data and c = 0 at an end.
std::vector<std::string> gluing_violations(const QuadMesh& mesh, const GluingData& gluing, double tolerance = 1e-10);

// The spline space S_k^{1,r}(M): per face R_k^r (degree k in s and t, knots 0, 1/2, 1, C^r
// at 1/2: (2k - r + 1)^2 B-spline coefficients), constrained by the G1 conditions across
// every interior edge, imposed as polynomial identities on both halves of the edge.
struct G1SpaceDimension {
  long unknowns = 0, constraints = 0, rank = 0, dimension = 0;
  bool exact = false;       // rank of the rational system (modulo two primes that agree)
  long cyclotomic = 0;      // or data in Q(zeta_N), N = this: rank modulo two primes = 1 (mod N)
  double tolerance = 0;     // otherwise: singular values below tolerance * largest are zero
  bool local = false;       // floating point from local SVDs (g1_space_dimension_local), not one dense SVD
  long coupled_edges = 0;   // local: the inseparable edges, whose rows join their two vertices
  // local: over every local SVD, the smallest singular value counted as nonzero and the largest
  // counted as zero, relative to the largest of the edge's (the group's) rows: the tolerance's
  // margin. It narrows as the mesh is subdivided (floating-point data restricted to shorter
  // edges lose numerical rank), which is when a floating-point count cannot be trusted.
  double smallest_kept = 0, largest_dropped = 0;
};
// Exact data: the exact rank. Otherwise, or with `floating` (an independent cross-check of the
// exact one): one dense SVD of all the conditions, cubic in the unknowns; the oracle the local
// SVDs of g1_space_dimension_local are tested against.
G1SpaceDimension g1_space_dimension(const QuadMesh& mesh, const GluingData& gluing, int k, int r, bool floating = false);
// Throws std::invalid_argument for k < 2, r outside [0, k-1], or an interior edge without data.
void check_g1_arguments(const QuadMesh& mesh, const GluingData& gluing, int k, int r);
// The exact conditions of every interior edge (empty for boundary edges), built on all cores;
// the same rows as g1_condition_rows_exact(mesh, gluing, k, r, e). Requires gluing.exact().
using G1ExactRows = std::vector<std::vector<std::pair<long, mpq_class>>>;
std::vector<G1ExactRows> g1_condition_rows_per_edge(const QuadMesh& mesh, const GluingData& gluing, int k, int r);
// Data that are sums of cosines (GluingData::algebraic(), not all rational): the rank of the
// conditions modulo two primes p = 1 (mod N), N = 2 * cosine_denominators_lcm(), with the
// cyclotomic field Q(zeta_N) mapped to Z/p. Each is at most the rank over the field, so the
// dimension is an upper bound the construction's count must reach; std::runtime_error if the
// two primes disagree. Sparse and linear in the mesh.
G1SpaceDimension g1_space_dimension_cyclotomic(const QuadMesh& mesh, const GluingData& gluing, int k, int r);
// Floating-point data (neither rational nor sums of cosines) on meshes of any size: the rank
// from local SVDs, linear in the mesh (g1_local_dimension.cpp). Each interior edge's rows,
// scaled to unit length, are reduced on its strips (which no other edge's rows meet): the SVD
// of the strip columns gives the strip rank, and its left singular vectors beyond that rank
// give rows on the corner blocks at the edge's two ends. Those rows are split between the two
// vertices when their row space allows it (a separable edge) and kept whole otherwise, which
// joins the two vertices into one group; each group's rank is one more SVD. Singular values
// below 1e-10 times the largest of the edge's rows (of the group's edges) count as zero.
// std::runtime_error when a group exceeds kMaxG1FloatingGroup corner-block unknowns (the
// dense SVD of one group is cubic in them) or when a singular value is not finite.
G1SpaceDimension g1_space_dimension_local(const QuadMesh& mesh, const GluingData& gluing, int k, int r);
constexpr long kMaxG1FloatingGroup = 2000;
// The exact dimension from those rows (so that a construction that needs them builds them once).
G1SpaceDimension g1_space_dimension_exact(const QuadMesh& mesh, int k, int r, const std::vector<G1ExactRows>& per_edge);

// dim Syz_k^{r-1,r,r} of one edge's data (Sec. 4.2): triples (A, B, C), A of degree k-1 and
// C^{r-1} at 1/2, B and C of degree k and C^r (A the derivative along the edge, B and C the
// cross-boundary derivatives), with A a + B b - C c = 0. Exact for rational data.
long gluing_syzygy_dimension(const EdgeGluing& g, int k, int r);

// Theorem 7.1: (2k-r-3)^2 F2 + sum over edges of dim Syz + 4 F2 - 9 F1 + 3 F0 + F+ (F+ the
// crossing vertices, where a = 0 on every edge). Stated for k at or above the separability
// of every edge; the count of the theorem is for closed meshes (boundary edges and
// vertices count differently, Remark 4.14): nullopt on meshes with a boundary.
std::optional<long> theorem_7_1_dimension(const QuadMesh& mesh, const GluingData& gluing, int k, int r);

// The rows of conditions (2) and (3) of one interior edge (all interior edges when edge < 0),
// as sparse rows over the unknowns g1_unknown(...): point evaluations at k + deg + 1 points
// of each half of the edge, enough to make them polynomial identities there. The exact
// version requires gluing.exact().
std::vector<std::vector<std::pair<long, double>>> g1_condition_rows(const QuadMesh& mesh, const GluingData& gluing,
                                                                    int k, int r, int edge = -1);
std::vector<std::vector<std::pair<long, mpq_class>>> g1_condition_rows_exact(const QuadMesh& mesh,
                                                                             const GluingData& gluing, int k, int r,
                                                                             int edge = -1);

// The same in extended precision (the floating-point local constructions).
std::vector<std::vector<std::pair<long, long double>>> g1_condition_rows_long(const QuadMesh& mesh,
                                                                            const GluingData& gluing, int k, int r,
                                                                            int edge);
// Sparse rows (column, value) as a dense matrix with `columns` columns.
Eigen::MatrixXd dense_rows(const std::vector<std::vector<std::pair<long, double>>>& rows, long columns);

// Index of coefficient (i, j) (i along s, j along t) of face f among the unknowns.
inline long g1_unknown(int f, int i, int j, int k, int r) {
  const int n = 2 * k - r + 1;
  return static_cast<long>(f) * n * n + static_cast<long>(i) * n + j;
}

// The same for the coefficient a steps along the u direction and b steps along the v
// direction of the face's frame at `corner` (docs/MATH.md §2: corner 0 at (s, t) = (0, 0),
// u along s; corners counter-clockwise).
long g1_corner_unknown(int face, int corner, int a, int b, int k, int r);

// The knot vector of each direction of a face: 0^(k+1), (1/2)^(k-r), 1^(k+1).
std::vector<double> g1_face_knots(int k, int r);

}  // namespace knotwork
