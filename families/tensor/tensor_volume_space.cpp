// The tensor family on a volume: the trivariate space of basis/tensor (build_tensor_volume) on
// the case's NURBS volume, evaluated exactly by VolumeGeometryMap.
#include "families/tensor/tensor_volume_space.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cstdio>
#include <stdexcept>

#include "basis/core/input_error.hpp"
#include "basis/core/glue_patches.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "cases/resource_limits.hpp"
#include "solver/affine_volume_operator.hpp"
#include "solver/amg_preconditioner.hpp"
#include "solver/fast_diagonalization_3d.hpp"
#include "solver/patchwise_multigrid.hpp"
#include "solver/tensor_multigrid_3d.hpp"
#include "families/tensor/patch_separable_coefficients.hpp"

namespace knotwork {

namespace {


int continuity_of(const TensorVolumeOptions& o, int k) { return o.continuity[k] < 0 ? o.degree[k] - 1 : o.continuity[k]; }

std::string describe(const TensorVolumeOptions& o, bool rational) {
  std::string r = std::string(rational ? "NURBS" : "B-spline") + ", degree " + std::to_string(o.degree[0]) + "x" +
                  std::to_string(o.degree[1]) + "x" + std::to_string(o.degree[2]) + ", C^" + std::to_string(continuity_of(o, 0));
  if (continuity_of(o, 1) != continuity_of(o, 0) || continuity_of(o, 2) != continuity_of(o, 0))
    r += "/C^" + std::to_string(continuity_of(o, 1)) + "/C^" + std::to_string(continuity_of(o, 2));
  return r + " at new knots, on hexahedra";
}

class TensorVolumeSpace final : public SplineSpace, public SpaceReport {
 public:
  TensorVolumeSpace(const CaseDescription& c, const TensorVolumeOptions& options, RowShare share) : options_(options) {
    check_tensor_volume_memory(c, options);
    try {
      d_ = build_tensor_volume(c.volume, options, share);
      d_.mesh.set_interface_rule(&interfaces_from_parameter_boxes);  // for the estimator, built when it asks
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": [space]: " + e.what());
    }
    try {
      geometry_ = std::make_unique<VolumeGeometryMap>(d_.mesh, d_.volume);
    } catch (const GeometryError& e) {
      throw InputError(c.path + ": [geometry]: " + e.what());
    }
  }
  const SpaceReport& presentation() const override { return *this; }
  const MeshPart* part() const override { return d_.part ? &*d_.part : nullptr; }
  const BezierMesh& mesh() const override { return d_.mesh; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::vector<int> degree() const override { return as_list(options_.degree); }
  std::string description() const override { return describe(options_, d_.mesh.is_rational()); }
  std::vector<ReportField> report() const override {
    return {{.key = "elements", .value = long(options_.elements_per_span[0]), .column = true, .width = 9}};
  }
  // The fast diagonalization, also what "auto" takes (docs/SOLVERS.md: 14-25 iterations on
  // the curved volumes for p = 2..4, against CHOLMOD 4.4x faster in 1/11 of the memory at 48^3,
  // and bounded in p where BoomerAMG's iterations are not).
  // Multigrid by name (it reads the assembled matrix: its Galerkin levels).
  std::vector<std::string> structured_preconditioners() const override { return {kFastDiagonalization, kMultigrid}; }
  bool structured_preconditioner_needs_only_diagonal(const std::string& name) const override { return name != kMultigrid; }
  // Without a matrix: multigrid from the operator where it is the Kronecker one (one affine map).
  bool structured_preconditioner_without_matrix(const std::string&) const override { return true; }
  std::unique_ptr<Preconditioner> make_structured_preconditioner_without_matrix(
      const std::string& name, const DofLayout& layout, std::shared_ptr<const MatrixFreePoisson> op,
      const Eigen::VectorXd& free_diagonal) const override {
    auto affine = std::dynamic_pointer_cast<const AffineVolumeOperator>(op);
    if (name != kMultigrid || !affine) return nullptr;
    return tensor_multigrid_3d(std::move(affine), layout, free_diagonal, volume_separable_coefficients(d_));
  }
  std::unique_ptr<Preconditioner> make_structured_preconditioner(const std::string& name, const DofLayout& layout,
                                                                 const Eigen::SparseMatrix<double>& lower,
                                                                 const PoissonProblem& problem) const override {
    std::array<bool, 6> nitsche{};
    if (problem.dirichlet_method == DirichletMethod::kNitsche && problem.boundary.size() == 6)
      for (int s = 0; s < 6; ++s) nitsche[s] = problem.boundary[s].kind == BoundaryKind::kDirichlet;
    if (name == kMultigrid)
      return tensor_multigrid_3d(d_.space, layout, lower, volume_separable_coefficients(d_), nitsche, problem.nitsche_penalty);
    return fast_diagonalization_3d(d_.space, layout, lower.diagonal(), volume_separable_coefficients(d_, &problem), nitsche,
                                   problem.nitsche_penalty);
  }
  // Where the map is one affine map and the functions are B-splines, the operator that writes
  // the matrix from its Kronecker form (solver/affine_volume_operator.hpp); elsewhere, and on a
  // process's part (its slabs are assembled by the element loop), none: std::invalid_argument,
  // which the pipeline reads as "assemble element by element".
  std::unique_ptr<MatrixFreePoisson> matrix_free_operator(double stiffness, double reaction,
                                                          const QuadratureOptions& quadrature) const override {
    if (d_.part) throw std::invalid_argument("a process's part of a volume is assembled element by element");
    if (d_.mesh.is_rational()) throw std::invalid_argument("NURBS functions are not products of univariate ones");
    const std::optional<AffineVolumeMap> map = affine_map(d_.volume);
    if (!map) throw std::invalid_argument("the volume's map is not one affine map");
    return std::make_unique<AffineVolumeOperator>(d_.space, *map, stiffness, reaction,
                                                  std::array<int, 3>{quadrature.points_u, quadrature.points_v, quadrature.points_w},
                                                  quadrature.error_points_w);
  }

 private:
  TensorVolumeOptions options_;
  TensorVolumeDiscretization d_;
  std::unique_ptr<VolumeGeometryMap> geometry_;
};

}  // namespace

void check_multivolume_memory(const CaseDescription& c, const TensorVolumeOptions& o);

namespace {
// Whether the pipeline will run CG without a matrix on this case (studies/pipeline.cpp,
// matrix_free_obstacle: the volume's operator, AffineVolumeOperator, serves it).
bool without_matrix(const CaseDescription& c) {
  return c.solver.matrix != "assembled" && !c.solver.estimate_condition && c.problem.coefficients.constant() &&
         !c.problem.source.empty() && c.problem.dirichlet_method != DirichletMethod::kNitsche && affine_map(c.volume);
}
}  // namespace

void check_tensor_volume_memory(const CaseDescription& c, const TensorVolumeOptions& o) {
  if (c.multivolume()) return check_multivolume_memory(c, o);
  double cells = 1, functions = 1;
  std::array<double, 3> n;  // functions per direction
  for (int k = 0; k < 3; ++k) {
    // An extra knot adds an element (or nothing, where it is a knot already: counted anyway).
    const double elements = double(c.volume.bases[k].num_elements()) * o.elements_per_span[k] + double(o.extra_knots[k].size());
    cells *= elements;
    n[k] = elements * (o.degree[k] - continuity_of(o, k)) + continuity_of(o, k) + 1;
    functions *= n[k];
  }
  // The path the solve takes (resolve_solver): "auto" is CG with the fast diagonalization from
  // kAutoIterativeFunctions functions, the direct solve below; "iterative" is CG with the named
  // preconditioner ("auto": the fast diagonalization) on the assembled matrix.
  const bool iterative = c.solver.method == "iterative" ||
                         (c.solver.method == "auto" && functions >= CaseDescription::Solver::kAutoIterativeFunctions);
  const std::string preconditioner = c.solver.preconditioner == "auto" ? kFastDiagonalization : c.solver.preconditioner;
  char what[200];
  std::snprintf(what, sizeof what, "%.3g hexahedra of degree %dx%dx%d (%.3g unknowns, %s)", cells, o.degree[0], o.degree[1],
                o.degree[2], functions, iterative ? ("CG + " + preconditioner).c_str() : "direct solve; CG with --solver iterative needs less");
  // The ordering "auto" takes on volumes is METIS; "default" (CHOLMOD's own choice) counted as AMD's fill.
  const bool metis = c.solver.ordering == "auto" || c.solver.ordering == "metis" || c.solver.ordering == "nesdis";
  double bytes = iterative ? volume_iterative_bytes(cells, functions, o.degree, preconditioner, !c.solver.petsc_options.empty())
                           : volume_galerkin_bytes(cells, functions, o.degree, metis);
  if (iterative && (preconditioner == kFastDiagonalization || preconditioner == kMultigrid)) {
    const bool multigrid = preconditioner == kMultigrid;
    bytes = volume_structured_bytes(functions, o.degree,
                                    multigrid ? tensor_multigrid_3d_bytes(functions, o.degree, true) : fast_diagonalization_3d_bytes(n));
    if (without_matrix(c)) {
      std::array<double, 3> elements;
      for (int k = 0; k < 3; ++k)
        elements[k] = double(c.volume.bases[k].num_elements()) * o.elements_per_span[k] + double(o.extra_knots[k].size());
      const double faces = 2 * (elements[0] * elements[1] + elements[1] * elements[2] + elements[0] * elements[2]);
      bytes = volume_matrix_free_bytes(functions, faces, o.degree,
                                       multigrid ? tensor_multigrid_3d_bytes(functions, o.degree, false) : fast_diagonalization_3d_bytes(n));
      std::snprintf(what, sizeof what, "%.3g hexahedra of degree %dx%dx%d (%.3g unknowns, CG + %s without a matrix)", cells,
                    o.degree[0], o.degree[1], o.degree[2], functions, preconditioner.c_str());
    }
  }
  check_memory(c.path + ": [space] elements", bytes, what);
}

// The direct solve's (or CG with --solver iterative's) memory of all the volumes' cells, their
// functions counted per volume (the shared ones twice: an upper bound).
void check_multivolume_memory(const CaseDescription& c, const TensorVolumeOptions& o) {
  double cells = 0, functions = 0;
  for (const NurbsVolume& v : c.volume_domain.patches) {
    double patch_cells = 1, patch_functions = 1;
    for (int k = 0; k < 3; ++k) {
      const double elements = double(v.bases[k].num_elements()) * o.elements_per_span[k] + double(o.extra_knots[k].size());
      patch_cells *= elements;
      patch_functions *= elements * (o.degree[k] - continuity_of(o, k)) + continuity_of(o, k) + 1;
    }
    cells += patch_cells;
    functions += patch_functions;
  }
  // The path the solve takes (resolve_solver): "auto" is CG with multigrid from
  // kAutoIterativeFunctions functions (as on one volume), the direct solve below; "iterative"
  // with "auto" or "multigrid" is CG with multigrid; other preconditioners as volume_solve_bytes.
  std::string method;
  double bytes = volume_solve_bytes(c, cells, functions, o.degree, &method);
  const bool iterative = c.solver.method == "iterative" ||
                         (c.solver.method == "auto" && functions >= CaseDescription::Solver::kAutoIterativeFunctions);
  if (iterative && (c.solver.preconditioner == "auto" || c.solver.preconditioner == kMultigrid)) {
    // Peak RSS 1.00-1.13x the one-volume formula on the seven Fichera cubes (p = 2 at 265 000
    // and 853 000 functions, p = 3 at 45 000 and 289 000; measured 2026-12-07): 1.25x covers them.
    method = "CG + multigrid";
    bytes = 1.25 * volume_structured_bytes(functions, o.degree, tensor_multigrid_3d_bytes(functions, o.degree, true));
  }
  char what[200];
  std::snprintf(what, sizeof what, "%.3g hexahedra of degree %dx%dx%d on %d volumes (%.3g unknowns, %s)", cells, o.degree[0],
                o.degree[1], o.degree[2], c.volume_domain.num_patches(), functions, method.c_str());
  check_memory(c.path + ": [space] elements", bytes, what);
}

double volume_solve_bytes(const CaseDescription& c, double cells, double functions, const std::array<int, 3>& degree,
                          std::string* method) {
  const bool iterative = c.solver.method == "iterative";
  if (method) *method = iterative ? "CG" : "direct solve";
  const std::string preconditioner = c.solver.preconditioner == "auto" ? std::string(kBoomerAmgName) : c.solver.preconditioner;
  const bool metis = c.solver.ordering == "auto" || c.solver.ordering == "metis" || c.solver.ordering == "nesdis";
  return iterative ? volume_iterative_bytes(cells, functions, degree, preconditioner, !c.solver.petsc_options.empty())
                   : volume_galerkin_bytes(cells, functions, degree, metis);
}


namespace {

// The tensor family on several volumes glued face to face: each volume's trivariate space of
// the same options, glued C0 by their traces (basis/core/glue_patches: refused, naming the
// interface, where the faces' knots or degrees differ), on the volumes' one map.
class MultiVolumeTensorSpace final : public SplineSpace, public SpaceReport {
 public:
  MultiVolumeTensorSpace(const CaseDescription& c, const TensorVolumeOptions& options) : options_(options) {
    const MultiVolume& domain = c.volume_domain;
    check_multivolume_memory(c, options);
    std::vector<const BezierMesh*> meshes;
    try {
      for (const NurbsVolume& v : domain.patches) patches_.push_back(build_tensor_volume(v, options));
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": [space]: " + e.what());
    }
    for (const TensorVolumeDiscretization& d : patches_) meshes.push_back(&d.mesh);
    try {
      glued_ = glue_volumes(domain, meshes);
      exterior_ = exterior_faces(domain);
      geometry_ = std::make_unique<VolumeGeometryMap>(glued_.mesh, domain.patches);
    } catch (const GeometryError& e) {
      throw InputError(c.path + ": [geometry] file: " + e.what());
    }
  }
  const SpaceReport& presentation() const override { return *this; }
  const BezierMesh& mesh() const override { return glued_.mesh; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::vector<int> degree() const override { return as_list(options_.degree); }
  std::string description() const override {
    return describe(options_, glued_.mesh.is_rational()) + ", " + std::to_string(patches_.size()) + " volumes glued C0";
  }
  std::vector<ReportField> report() const override {
    return {{.key = "elements", .value = long(options_.elements_per_span[0]), .column = true, .width = 9}};
  }
  // Multigrid over the volumes' uniform refinements, glued across their faces
  // (solver/patchwise_multigrid.hpp): what "auto" takes from 10 000 functions (docs/VOLUMES.md,
  // "Multigrid on several volumes": bounded iterations where BoomerAMG's grow with p, and faster
  // than CHOLMOD).
  std::vector<std::string> structured_preconditioners() const override { return {kMultigrid}; }
  bool structured_preconditioner_needs_only_diagonal(const std::string&) const override { return false; }
  std::unique_ptr<Preconditioner> make_structured_preconditioner(const std::string& /*name: the one*/,
                                                                 const DofLayout& layout,
                                                                 const Eigen::SparseMatrix<double>& lower,
                                                                 const PoissonProblem& problem) const override {
    // Each volume's faces whose Dirichlet data Nitsche's method imposes (boundary id i is
    // exterior_[i], face 1..6 of its volume: u = 0, u = 1, v = 0, ...).
    std::vector<std::array<bool, 6>> nitsche(patches_.size(), std::array<bool, 6>{});
    if (problem.dirichlet_method == DirichletMethod::kNitsche)
      for (size_t i = 0; i < exterior_.size() && i < problem.boundary.size(); ++i)
        nitsche[exterior_[i].patch][exterior_[i].side - 1] = problem.boundary[i].kind == BoundaryKind::kDirichlet;
    PatchwiseLevel finest;
    for (size_t k = 0; k < patches_.size(); ++k)
      finest.patches.push_back(volume_multigrid_patch(patches_[k].space, volume_separable_coefficients(patches_[k]),
                                                      glued_.global_function[k], nitsche[k], problem.nitsche_penalty));
    finest.layout = layout;
    return patchwise_multigrid(std::move(finest), lower);
  }

 private:
  TensorVolumeOptions options_;
  std::vector<TensorVolumeDiscretization> patches_;
  GluedPatches glued_;
  std::vector<PatchSideRef> exterior_;  // boundary id -> volume face
  std::unique_ptr<VolumeGeometryMap> geometry_;
};

}  // namespace

std::unique_ptr<SplineSpace> make_tensor_volume_space(const CaseDescription& c, const TensorVolumeOptions& options,
                                                     RowShare share) {
  if (c.multivolume()) return std::make_unique<MultiVolumeTensorSpace>(c, options);  // whole on every process
  return std::make_unique<TensorVolumeSpace>(c, options, share);
}

}  // namespace knotwork
