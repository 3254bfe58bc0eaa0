#pragma once
#include <array>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/g1/g1_space.hpp"

namespace knotwork {

// One basis function of S_k^{1,r}(M), as its nonzero B-spline coefficients over the faces:
// (g1_unknown(face, i, j, k, r), value), scaled so that the largest in magnitude is +1, except
// where the constant function's coefficient is made 1 instead: on the face functions (both), on
// each interior vertex's functions and each interior edge's where the constant has a part
// (g1_basis.cpp, constant_carrying_functions: classical AMG needs the constant to be all ones).
struct G1BasisFunction {
  enum class Kind { vertex, edge, face, vertex_pair, coupled };
  Kind kind = Kind::face;
  int owner = 0;  // the vertex, edge or face it is attached to (vertex_pair: the edge)
  std::vector<std::pair<long, double>> coefficients;
};

// The local basis of Blidia-Mourrain-Villamizar sections 4-6, built from the B-spline
// coefficients of each face split into
//   corner blocks  (the 2x2 coefficients at a corner: they fix the Taylor data there),
//   edge strips    (the two rows along a side, corner blocks excluded),
//   the interior   (indices 2..n-3 in both directions),
// so that the conditions of an interior edge involve only its strips and the corner blocks
// at its ends. Then
//   vertex functions: solutions on the corner blocks at the vertex and the strips of its
//     interior edges (the other ends' corner blocks zero), one per independent Taylor
//     datum: they span the image of the Taylor map at the vertex;
//   edge functions: solutions on the strips of one edge (Taylor data zero at both ends);
//     on a boundary edge every strip coefficient;
//   face functions: the interior B-splines.
// Supports: faces around the vertex, the faces of the edge, one face.
// When the degree is below the separability of an edge (Prop. 5.2 does not apply), the
// Taylor data at its two ends are coupled and the vertex functions miss part of the image
// of the Taylor map; then vertex_pair functions, solutions on the faces around both ends
// of one edge, complete it (the paper has no such functions: it assumes k >= s*). Where
// even those fall short (r = k - 1 around extraordinary vertices), `coupled` functions from
// the global null space (exact for rational data; not local) complete the basis.
struct G1Basis {
  int k = 0, r = 0;
  std::vector<G1BasisFunction> functions;
  G1SpaceDimension space;           // the null-space dimension the basis was checked against
  std::array<long, 5> counts{};     // vertex, edge, face, vertex_pair, coupled functions
  bool exact = false;               // local null spaces computed over Q
  long unknowns() const { return space.unknowns; }
};

// Throws std::invalid_argument for bad k, r or missing gluing data.
// `floating` forces the floating-point path (SVD, singular values below 1e-10 * largest
// are zero) also for rational data.
// `progress` (optional) hears each stage ("G1 basis: vertex functions, 1200 vertices").
G1Basis g1_basis(const QuadMesh& mesh, const GluingData& gluing, int k, int r, bool floating = false,
                 const std::function<void(const std::string&)>& progress = {});

// The largest constructions done, in unknowns = faces x (2k - r + 1)^2 (docs/RELIABILITY.md):
// 1 769 472 unknowns (k = 4, r = 1, 27 648 faces, 992 607 functions) built in 25 s with exact
// data, and the whole run took 6.8 GB here, both about linear in the unknowns. Sums of cosines
// and floating-point data (local SVDs, g1_space_dimension_local) are no slower: 512 000
// unknowns of floating-point data (k = 5) in 11 s.
constexpr long kMaxG1Unknowns = 2000000;
// std::length_error with the size, the limit and the estimate when the construction of a
// G1 space on `faces` faces would exceed it.
void check_g1_construction_size(long faces, int k, int r);

// Floating-point data (not rational, not sums of cosines): the dimension from local SVDs
// (g1_space_dimension_local) is refused as ambiguous when the smallest singular value counted
// as nonzero is less than this factor above the largest counted as zero. Measured on
// `geometric` data of a 27-face mesh with 17-digit coordinates (k = 4, r = 1): a margin of
// 1500, 150, 23 and 1.2 at 0 to 3 subdivisions; at 3 the count of the local basis and the
// dimension differ by one.
constexpr double kMinG1RankMargin = 10;

// Largest relative residual of conditions (2)-(3) over the basis functions:
// max over functions and rows of |C_row x| / (sum_j |C_row,j| * max|x|).
double g1_residual_max(const QuadMesh& mesh, const GluingData& gluing, const G1Basis& basis);

// Numerical rank of the functions' coefficient matrix: SVD (tolerance 1e-10 * largest) up
// to 2.5e7 matrix entries, sparse rank-revealing QR beyond; `method` says which.
long g1_basis_rank(const G1Basis& basis, std::string* method = nullptr);

// The interior edges whose separability (Definition 4.11) exceeds k: on the two faces of
// the edge alone, the Taylor data at its ends are coupled (the rank of the joint Taylor map
// is less than the sum of the two ends' ranks). Theorem 7.1 assumes there are none.
std::vector<int> g1_inseparable_edges(const QuadMesh& mesh, const GluingData& gluing, int k, int r);

// The plain C0 multipatch space on the same faces (each face R_k^r, values matched across
// interior edges, no condition on derivatives): the baseline G1 spaces are compared with.
// Functions of kind `face`; a coefficient shared by several faces is one function.
G1Basis c0_multipatch_basis(const QuadMesh& mesh, int k, int r);

// The faces a function lives on (sorted).
std::vector<int> support_faces(const G1BasisFunction& f, int k, int r);

// The basis as a BezierMesh: four polynomial cells of degree k per face (the quarters of
// the 4-split, patch = face, index_u/index_v = which half in s/t), boundary id 0
// ("boundary") on the mesh's boundary edges.
BezierMesh g1_bezier_mesh(const QuadMesh& mesh, const G1Basis& basis);

}  // namespace knotwork

namespace knotwork {

// The least-squares projection onto S_k^{1,r} (in the B-spline coefficients) of the G0
// spline made of the mesh's bilinear faces, as the paper does for its Fig. 6: returns the
// coefficient of every basis function (one column per coordinate x, y, z) and, in
// `deviation`, the largest distance between a projected and a bilinear coefficient.
Eigen::MatrixX3d g1_fit_bilinear(const QuadMesh& mesh, const G1Basis& basis, double* deviation = nullptr);

// The same for any target surface given per face: target(face, s, t) is the point the face's
// coefficient with Greville abscissae (s, t) should take (e.g. the bilinear point projected
// onto a sphere).
Eigen::MatrixX3d g1_fit(const QuadMesh& mesh, const G1Basis& basis,
                        const std::function<Eigen::Vector3d(int face, double s, double t)>& target,
                        double* deviation = nullptr);

// Bernstein coefficients of the same on each BezierMesh cell of g1_bezier_mesh (rows: the
// cell's (k+1)^2 Bernstein polynomials, a + (k+1) b with a along s).
std::vector<Eigen::MatrixXd> g1_cell_bernstein(const BezierMesh& mesh, const Eigen::MatrixXd& c);

}  // namespace knotwork
