#pragma once
// A case as read from its file: the sections every family shares ([problem], [output],
// [adapt], quadrature) and the family's own section, which only the family reads and
// interprets (families/<family>/<family>_case.*). load_case dispatches on [space] family.
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "basis/core/multipatch.hpp"
#include "basis/core/multivolume.hpp"
#include "basis/core/nurbs_patch.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "basis/tmesh/rectangular_partition.hpp"
#include "cases/document_node.hpp"
#include "solver/poisson_problem.hpp"

namespace knotwork {

// A family's part of a case (its [space], and for some families [geometry] and [problem]
// details). Copied with the case.
struct CaseSection {
  virtual ~CaseSection() = default;
  virtual std::unique_ptr<CaseSection> clone() const = 0;
};

// Owns the family's section; copying a case copies it.
class FamilySection {
 public:
  FamilySection() = default;
  FamilySection(const FamilySection& o) : p_(o.p_ ? o.p_->clone() : nullptr) {}
  FamilySection& operator=(const FamilySection& o) {
    if (this != &o) p_ = o.p_ ? o.p_->clone() : nullptr;
    return *this;
  }
  FamilySection(FamilySection&&) noexcept = default;
  FamilySection& operator=(FamilySection&&) noexcept = default;
  template <class T>
  T& emplace() {
    auto p = std::make_unique<T>();
    T& r = *p;
    p_ = std::move(p);
    return r;
  }
  template <class T>
  T* get() const { return dynamic_cast<T*>(p_.get()); }

 private:
  std::unique_ptr<CaseSection> p_;
};

// Everything a case file says, validated. See cases/README.md for the keys.
struct CaseDescription {
  std::string path;  // as given
  std::string name;  // file name without extension
  std::string title;
  std::string family = "tensor";  // [space] family: a registered family (families/families.cpp)
  // [geometry] of the families whose domain is one NURBS patch (type rectangle,
  // quarter_annulus, lshape or nurbs); empty geometry_type for the others.
  std::string geometry_type;  // "file" for [geometry] file
  NurbsPatch geometry;        // the one patch (also of a one-patch file)
  // [geometry] file: the domain as read, with its interfaces and the file's boundary labels
  // (no patch otherwise). A domain of several patches leaves `geometry` empty.
  MultiPatch domain;
  bool multipatch() const { return domain.num_patches() > 1; }
  // [geometry] type = "box", "thick_quarter_annulus", a nurbs with knots_w, or a file of a
  // volume: the domain is this volume (the tensor family's trivariate spaces; docs/VOLUMES.md),
  // and `geometry` is empty; a file's named boundaries (sides 1..6) in `volume_boundaries`.
  NurbsVolume volume;
  std::vector<NamedBoundary> volume_boundaries;
  // Parts of the volume's parameter box that are not in the domain (type = "fichera": the
  // octant), each (u0, u1, v0, v1, w0, w1) on knots of the volume; their faces are the
  // boundary "hole". A family that cannot remove cells refuses such a geometry.
  std::vector<std::array<double, 6>> volume_removed_boxes;
  // A file of several volumes glued face to face (`volume` is then its first).
  MultiVolume volume_domain;
  bool multivolume() const { return volume_domain.num_patches() > 1; }
  bool is_volume() const { return volume.control_points.rows() > 0; }
  FamilySection section;                // the family's own settings
  bool allow_unverified_space = false;  // --allow-unverified-space: solve although the family's check failed
  QuadratureOptions quadrature;
  PoissonProblem problem;
  std::string output_directory;  // default results/<name>
  bool write_bezier = true, write_sampled = true;
  int samples = 4;  // linear sub-cells per cell and direction in the sampled output
  // [solver]: the linear solve (docs/SOLVERS.md; --solver and --tolerance override).
  struct Solver {
    // "auto" picks CG for spaces with a structured preconditioner from this many functions on
    // (docs/SOLVERS.md: where the measured times cross), and CHOLMOD otherwise.
    static constexpr int kAutoIterativeFunctions = 10000;
    // direct (CHOLMOD) | iterative (CG) | auto (docs/SOLVERS.md) | petsc (PETSc's KSP, on every
    // process mpirun started: docs/SCALING.md)
    std::string method = "auto";
    std::string preconditioner = "auto";  // auto | jacobi | boomeramg | a family's structured one (SpaceFamily)
    // PETSc options: for boomeramg, its own ("-pc_hypre_boomeramg_..."); for petsc, the KSP's
    // and PC's ("-ksp_type cg -pc_type hypre", "-pc_type cholesky -pc_factor_mat_solver_type mumps")
    std::string petsc_options;
    // CG's, serial or PETSc's: the backward error of the solution (IterativeStats; under PETSc
    // knotwork's convergence test, unless petsc_options give -ksp_rtol or -ksp_atol).
    double tolerance = 1e-15;
    bool tolerance_given = false;  // by the case or --tolerance
    int max_iterations = 1000;
    // How CG gets K: "assembled" (a sparse matrix), "matrix_free" (the family's operator applied
    // without a matrix: docs/SOLVERS.md, "Without a matrix"; about 20% less memory) or "auto":
    // matrix-free where it applies and every element is affine (measured faster there),
    // assembled otherwise (measured faster on curved elements).
    std::string matrix = "auto";
    // --condition: estimate the Jacobi-scaled condition numbers of the stiffness and mass
    // matrices (solver/condition_estimate.hpp); a command-line request, not a case key.
    bool estimate_condition = false;
    // --ordering, when a command names one ("amd", "metis", ...): the memory guard of a volume's
    // direct solve follows it (METIS fills in 0.6x as much as AMD there); "auto" otherwise.
    std::string ordering = "auto";
  } solver;
  // [adapt]: the estimate-mark-refine loop of `knotwork adapt` (command-line flags override).
  struct Adapt {
    int steps = 10;          // solves, the first on the case's own mesh
    double theta = 0.5;      // Doerfler fraction of the estimated error squared to mark
    long max_dofs = 200000;  // stop refining beyond this many functions
    // [adapt] marking = "functions": Doerfler marking of functions (indicator: the sum of
    // eta_K^2 over the cells a function lives on), refining the cells of their supports, as
    // hierarchical codes do; "cells" (default): Doerfler marking of cells.
    bool mark_functions = false;
    // [adapt] strategy = "maximum": mark every cell (function) whose indicator eta is at least
    // theta times the largest; "dorfler" (default): the fewest holding theta of eta^2's sum.
    bool maximum_strategy = false;
    // [adapt] min_fraction: mark at least this share of the cells (functions), largest first.
    double min_fraction = 0;
  } adapt;
};

// The family's section of a case; std::logic_error when the case is of another family
// (a programming error: families only see their own cases).
template <class T>
T& family_section(CaseDescription& c) {
  if (T* s = c.section.get<T>()) return *s;
  throw std::logic_error(c.path + ": the case is of family \"" + c.family + "\", not the one asked for");
}
template <class T>
const T& family_section(const CaseDescription& c) {
  if (const T* s = c.section.get<T>()) return *s;
  throw std::logic_error(c.path + ": the case is of family \"" + c.family + "\", not the one asked for");
}

// Reads and validates a case file through its family's reader (families/load_case.cpp).
// Throws InputError with a one-line message naming the file and the field (TOML syntax
// errors with line and column; unknown keys with the closest valid one).
CaseDescription load_case(const std::string& path);
// The same from TOML text (`name` stands for the file in messages; relative paths in it
// resolve against the current folder).
CaseDescription load_case_text(const std::string& toml_text, const std::string& name);
// The same from a document built in memory (the Python module's dict cases).
CaseDescription load_case_document(const DocumentNode& root, const std::string& name);

// --solver / --tolerance with the same validation as [solver] (0: not given).
void override_solver(CaseDescription& c, const std::string& method, double tolerance,
                     const std::string* petsc_options = nullptr);
// [solver] petsc_options is for preconditioner = "boomeramg" or method = "petsc": refused
// otherwise, naming `what` (the key or the flag).
void check_petsc_options(const CaseDescription& c, const std::string& what);
// The names [solver] method takes.
const std::vector<std::string>& solver_methods();

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
// The same from a parsed document (`name` stands for the file in messages).
PartitionDescription load_partition_document(const DocumentNode& root, const std::string& name, bool need_degree = true);

// For constructions of the highest smoothness only: throws InputError naming the file and
// `smoothness` unless alpha = m - 1 and beta = n - 1; `space` says which construction.
void require_highest_smoothness(const PartitionDescription& p, const std::string& path, const std::string& space);

// Whether the file's top level has one of `keys` (the basis tools tell file kinds apart by
// it). Throws InputError when the file cannot be parsed.
bool document_has_key(const std::string& path, const std::vector<std::string>& keys);

}  // namespace knotwork
