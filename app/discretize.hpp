#pragma once
#include <memory>

#include "basis/tensor_patch.hpp"
#include "cases/case_file.hpp"
#include "solver/geometry_map.hpp"
#include "solver/poisson_solver.hpp"

#include <functional>

namespace knotwork {

// A case turned into what the solver needs: the BezierMesh and the geometry on its cells.
struct Discretization {
  TensorDiscretization tensor;                      // family "tensor"
  std::unique_ptr<SemiRegularCollection> segments;  // family "knot_segments"
  std::unique_ptr<RectangularPartition> tmesh;      // family "pt": the T-mesh (parameter domain)
  std::unique_ptr<PtSplineBasis> pt;                //   and its PT-spline basis
  std::unique_ptr<BezierMesh> local_mesh;           // knot_segments, pt; on the heap: geometry maps refer to it
  std::vector<InsertionReport> insertions;          // what each segment became
  bool simple_knots = true;                         // every interior knot of multiplicity 1
  std::vector<std::string> violations;              // of an explicit collection (solve_case refuses)
  std::unique_ptr<GeometryMap> geometry;
  const BezierMesh& mesh() const { return local_mesh ? *local_mesh : tensor.mesh; }
};

// Throws InputError naming the case file and [space] when the space cannot be built.
Discretization discretize(const CaseDescription& c);

// The case's geometry on a given knot-segment collection (a step of adaptive refinement).
Discretization discretize_collection(const CaseDescription& c, const SemiRegularCollection& collection);

// Family "pt": the case's starting T-mesh in parameter coordinates (cells or the tensor grid
// of the geometry's knot spans, each cut into [space] elements parts, then the segments).
std::vector<RationalBox> pt_start_cells(const CaseDescription& c);
// PT-splines on the given T-mesh of the case's parameter domain, ready to solve: the
// geometry's C0 knot lines are C0 lines of the space. Throws InputError naming the case.
Discretization discretize_pt(const CaseDescription& c, const std::vector<RationalBox>& cells);

// Solves the case's Poisson problem on its discretization; a GeometryError gets the case
// file and "[geometry]" in front of its message.
PoissonSolution solve_case(const CaseDescription& c, const Discretization& d, Ordering ordering,
                           const std::function<void(const std::string&)>& progress);

// The benchmark problem: unit square, u = sin(pi x) sin(pi y), degree p, n x n elements.
CaseDescription unit_square_benchmark_case(int p, int n);

// Largest physical cell diameter (longest cell diagonal), the h of convergence tables.
double mesh_size(const Discretization& d);

// "tensor NURBS, degree 2x2, C^1" style description of the space.
std::string describe_space(const CaseDescription& c);

}  // namespace knotwork
