#pragma once
#include <vector>

#include "basis/g1/g1_space.hpp"
#include "basis/g1/quad_mesh.hpp"

namespace knotwork {

// Where a face of a subdivided mesh lies in the coarse mesh it came from: the square
// [s0, s0 + size] x [t0, t0 + size] of coarse face `face`, in the same orientation.
struct CoarseFaceSquare {
  int face = 0;
  double s0 = 0, t0 = 0, size = 1;
};

// One level of quad-mesh subdivision of a G1 macro-patch domain: every face split into four
// along s = 1/2 and t = 1/2 (new vertices at edge midpoints and face centres), with the
// gluing data of each half of an old edge restricted to that half (a(u) -> a(u0 + u/2), the
// same for b and c: the G1 conditions are homogeneous in the derivatives, so halving both
// sides' parameters changes nothing), and the parametric data a = 0, b = -1, c = 1 on the
// new edges inside an old face (where both sides share one parametrization).
// Why this refinement: every function of S_k^{1,r} on the coarse mesh restricted to a
// quarter face is a polynomial per cell of the quarter's 4-split (the coarse split lines are
// quarter sides), is C^r (r >= 1) across the new inner edges and satisfies the restricted
// conditions on the halves of old edges. So the spaces are nested, and the coarse G1
// geometry is exactly a G1 spline of every finer level.
struct G1Refinement {
  QuadMesh mesh;
  GluingData gluing;
  std::vector<CoarseFaceSquare> origin;  // per face of `mesh`, relative to the coarsest mesh
};

// `levels` subdivisions (0 returns the input with identity origins). Vertex positions of the
// finer meshes are the bilinear interpolation of the coarse faces (topology and reporting
// only: the geometry of analysis is the coarse G1 fit, restricted).
G1Refinement refine_g1(const QuadMesh& mesh, const GluingData& gluing, int levels);

// p(u0 + u / 2) for both pieces of a restricted edge (u0 = 0: the first half, piece 0;
// u0 = 1/2: the second half, piece 1). Exact data stay exact.
PiecewisePolynomial restrict_to_half(const PiecewisePolynomial& p, int half);

}  // namespace knotwork
