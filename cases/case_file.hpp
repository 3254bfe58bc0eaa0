#pragma once
#include <string>
#include <vector>

#include <Eigen/Core>
#include <optional>

#include "basis/pt/pt_spline.hpp"
#include "basis/knot_segments/semi_regular_collection.hpp"
#include "basis/tensor/tensor_patch.hpp"
#include "solver/poisson_problem.hpp"

namespace knotwork {

// Everything a case file says, validated. See cases/README.md for the keys.
struct CaseDescription {
  std::string path;  // as given
  std::string name;  // file name without extension
  std::string title;
  std::string geometry_type;
  NurbsPatch geometry;
  TensorSpaceOptions space;
  std::string family = "tensor";         // or "knot_segments", "g1", "pt"
  std::vector<KnotInsertion> segments;  // knot_segments: inserted in order, parameter coordinates
  std::string collection_file;             // knot_segments given explicitly ([space] collection)
  std::vector<LocalBSpline> collection;    // its functions, not yet checked for semi-regularity
  bool allow_non_semi_regular = false;     // --allow-non-semi-regular: solve on it anyway
  // family "g1": the G1 macro-patch space on a quad mesh; the geometry is the G1 spline
  // fitted to the mesh ([geometry] shape) and the problem is planar Poisson or
  // Laplace-Beltrami on a closed surface ([problem] operator).
  struct G1 {
    std::string mesh_file;              // resolved against the case file's folder
    int faces = 0;                      // of the coarse mesh (read and checked with the case)
    int degree = 4, split_smoothness = 1;
    std::string gluing = "symmetric";   // "symmetric", "geometric" or a JSON file (resolved)
    int refine = 0;                     // subdivisions before solving (converge adds one per level)
    bool c0 = false;                    // [space] smoothness = "c0": the plain C0 multipatch baseline
    std::string shape = "bilinear";     // "bilinear" | "sphere" | "torus"
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
    double radius = 1, major_radius = 2, minor_radius = 1;  // sphere; torus around the z axis
    bool surface = false;               // operator = "laplace_beltrami" (problem: -Laplace_Beltrami(u) + reaction u = f)
  } g1;
  // family "pt": PT-splines over a T-mesh in the geometry's parameter domain. The start is
  // `cells` (inline or from [space] tmesh) or else the tensor grid of the geometry's knot
  // spans; every start cell is cut into space.elements_per_span parts, then `segments` are
  // inserted (exact rationals).
  struct Pt {
    std::vector<RationalBox> cells;
    std::vector<AxisSegment> segments;
    std::string tmesh_file;  // resolved; empty for inline cells or the tensor start
    PtExtension extension = PtExtension::kAuto;
  } pt;
  QuadratureOptions quadrature;
  PoissonProblem problem;
  std::string output_directory;  // default results/<name>
  bool write_bezier = true, write_sampled = true;
  int samples = 4;  // linear sub-cells per cell and direction in the sampled output
  // [adapt]: the estimate-mark-refine loop of `knotwork adapt` (command-line flags override).
  struct Adapt {
    int steps = 10;          // solves, the first on the case's own mesh
    double theta = 0.5;      // Doerfler fraction of the estimated error squared to mark
    long max_dofs = 200000;  // stop refining beyond this many functions
  } adapt;
};

// Reads and validates a case file. Throws InputError with a one-line message naming the
// file and the field (TOML syntax errors with line and column; unknown keys with the
// closest valid one).
CaseDescription load_case(const std::string& path);

// Applies --degree / --elements style overrides with the same validation as the file.
void override_degree(CaseDescription& c, int degree);
void override_elements(CaseDescription& c, int elements);

// For families refined by doubling [space] elements per level: throws InputError when the
// finest of `levels` levels would have more than 2^26 cells.
void check_uniform_levels(const CaseDescription& c, int levels);

}  // namespace knotwork

#include "basis/tmesh/rectangular_partition.hpp"

namespace knotwork {

// A rectangular partition (T-mesh) file:
//   cells = [[x0, y0, x1, y1], ...]   numbers or exact rational strings such as "14/9"
//     or grid = {x = [...], y = [...]} with segments = [{direction, position, from, to}, ...]
//   degree = [m, n]                   (or one int)
//   smoothness = [alpha, beta]        optional, default [m-1, n-1]
struct PartitionDescription {
  std::vector<RationalBox> cells;
  int m = 2, n = 2, alpha = 1, beta = 1;
};
// Throws InputError naming the file and field (or the offending cells). Without need_degree
// the file may omit `degree` (a case's [space] tmesh gives its own).
PartitionDescription load_partition(const std::string& path, bool need_degree = true);

// For constructions of the highest smoothness only: throws InputError naming the file and
// `smoothness` unless alpha = m - 1 and beta = n - 1; `space` says which construction.
void require_highest_smoothness(const PartitionDescription& p, const std::string& path, const std::string& space);

// A collection of tensor-product B-splines given by their local knot vectors (the format
// `knotwork basis --export` writes; JSON or TOML):
//   degree = [dx, dy]
//   functions = [{x = [dx+2 knots], y = [dy+2 knots]}, ...]
struct CollectionDescription {
  int dx = 2, dy = 2;
  std::vector<LocalBSpline> splines;
};
CollectionDescription load_collection(const std::string& path);

// What an input file describes, from its top-level keys: `functions` (a collection),
// `cells` (a T-mesh) or else a case. Throws InputError if the file cannot be parsed.
enum class InputKind { kCase, kPartition, kCollection };
InputKind input_kind(const std::string& path);

}  // namespace knotwork
