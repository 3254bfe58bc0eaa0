// Family "tensor": tensor-product B-splines and NURBS on one patch, k-refined from the case's
// geometry (uniform elements per knot span, optional extra knots), isoparametric when rational.
#include <algorithm>
#include <cstdio>

#include "solver/fast_diagonalization.hpp"
#include "solver/tensor_multigrid.hpp"
#include "solver/tensor_operator.hpp"
#include "families/tensor/patch_separable_coefficients.hpp"
#include "basis/core/geometry_map.hpp"
#include "families/tensor/multipatch_tensor_space.hpp"
#include "families/tensor/tensor_case.hpp"
#include "families/tensor/tensor_volume_space.hpp"
#include "cases/resource_limits.hpp"
#include "cases/spline_space.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// On several patches the multigrid keeps the whole matrix, its Galerkin levels and the band's
// factor: peak RSS 1.57x and 1.54x the one-patch formula at p = 2 (0.79M and 3.2M functions on
// the plus) and 1.23x at p = 4 (0.81M), measured 2026-12-07 (the matrix then from the element
// loop; now written patch by patch, one patch's matrix at a time besides it); 1.7x covers them.
constexpr double kSeveralPatchesMultigrid = 1.7;

// "auto" on one patch: multigrid instead of the fast diagonalization where the map (with the
// problem's A) does not separate (separability_spread above kSeparableEnough) and from
// kAutoMultigridOnMaps functions (docs/SOLVERS.md, "Which one auto takes": on the L-shape and
// the anisotropic annulus, spreads 5.8 and 6.3, the fast diagonalization took 33-35 CG
// iterations and multigrid 11-13, and multigrid was as fast at 130 000-150 000 functions and
// 8-23% faster from 260 000; separable maps and A = 1 give 1, the variable coefficient of
// square_variable_coefficient 1.17). Measured from the map and A alone, so the memory check
// below and the space decide alike.
constexpr double kAutoMultigridOnMaps = 200000;
constexpr double kSeparableEnough = 2.0;
bool auto_takes_multigrid(const NurbsPatch& patch, const std::vector<Expression>& diffusion, double functions,
                          double& spread) {
  spread = 1;
  if (functions < kAutoMultigridOnMaps) return false;
  spread = separability_spread(patch, diffusion);
  return spread > kSeparableEnough;
}

// Refuses discretizations that cannot fit in memory before allocating anything (a rank's part:
// its share of the cells).
void check_tensor_memory(const CaseDescription& c, const TensorSpaceOptions& s, int ranks = 1) {
  double cells = 1, functions = 1, per_direction[2] = {1, 1};
  const int processes = ranks;
  if (c.multipatch()) {
    multipatch_tensor_size(c, s, cells, functions);
    // In parts of whole patches when there are as many patches as processes (about 1/ranks of
    // the space each, plus a halo along interfaces); else every process builds all of it.
    if (c.domain.num_patches() < ranks) ranks = 1;
  } else {
    for (int d = 0; d < 2; ++d) {
      const BSplineBasis1D& g = d == 0 ? c.geometry.basis_u : c.geometry.basis_v;
      const double elements = double(g.num_elements()) * s.elements_per_span[d] + s.extra_knots[d].size();
      cells *= elements;
      functions *= elements + s.degree[d];
      per_direction[d] = elements + s.degree[d];
    }
  }
  // The path the solve will take (studies/pipeline.cpp resolves it the same way): serially, CG
  // with "auto" from kAutoIterativeFunctions functions on (the fast diagonalization on one
  // patch, multigrid on several); CG keeps no factor.
  const std::string& method = c.solver.method;
  const bool iterative =
      ranks == 1 && (method == "iterative" || (method == "auto" && functions >= CaseDescription::Solver::kAutoIterativeFunctions));
  char what[160];
  if (ranks > 1)
    std::snprintf(what, sizeof what, "%.3g cells of degree %dx%d on each of %d processes", cells / ranks, s.degree[0],
                  s.degree[1], ranks);
  else
    std::snprintf(what, sizeof what, "%.3g cells of degree %dx%d", cells, s.degree[0], s.degree[1]);
  const int p = s.degree[0], q = s.degree[1];
  if (iterative) {
    double spread = 1;
    const std::string& name = c.solver.preconditioner != "auto" ? c.solver.preconditioner
                              : c.multipatch() || auto_takes_multigrid(c.geometry, c.problem.coefficients.diffusion, functions, spread) ? kMultigrid
                                                                                                       : kFastDiagonalization;
    std::snprintf(what, sizeof what, "%.3g cells of degree %dx%d with CG + %s%s", cells, p, q, name.c_str(),
                  c.solver.matrix == "matrix_free" ? ", no matrix" : "");
    const double pc = name == kFastDiagonalization ? fast_diagonalization_bytes(per_direction[0], per_direction[1])
                      : name == kMultigrid         ? tensor_multigrid_bytes(functions, p, q, c.solver.matrix != "matrix_free")
                                                   : algebraic_preconditioner_bytes(name, functions, p, q);
    const double several = c.multipatch() && name == kMultigrid ? kSeveralPatchesMultigrid : 1.0;
    check_memory(c.path + ": [space] elements",
                 several * iterative_bytes(cells, functions, p, q, pc, c.solver.matrix != "matrix_free"), what);
    return;
  }
  // Under PETSc every process also holds the whole PCShell: multigrid's hierarchy (from the
  // whole matrix where the map is curved: counted so, the larger; on several patches always,
  // and there what "auto" takes, with the factor measured serially above) or the fast
  // diagonalization.
  double shell = 0;
  if (processes > 1 && method == "petsc") {
    const std::string& name = c.solver.preconditioner;
    if (c.multipatch()) {
      if (name == kMultigrid || name == "auto") shell = kSeveralPatchesMultigrid * tensor_multigrid_bytes(functions, p, q, true);
    } else if (double spread = 1;
               name == kMultigrid ||
               (name == "auto" && auto_takes_multigrid(c.geometry, c.problem.coefficients.diffusion, functions, spread))) {
      shell = tensor_multigrid_bytes(functions, p, q, true);
    } else if (name == kFastDiagonalization || name == "auto") {
      shell = fast_diagonalization_bytes(per_direction[0], per_direction[1]);
    }
  }
  check_memory(c.path + ": [space] elements", galerkin_bytes(cells / ranks, functions / ranks, p, q) + shell, what);
}

std::string describe(const TensorSpaceOptions& s) {
  const int ru = s.continuity[0] < 0 ? s.degree[0] - 1 : s.continuity[0];
  const int rv = s.continuity[1] < 0 ? s.degree[1] - 1 : s.continuity[1];
  std::string r = std::string(s.rational ? "NURBS" : "B-spline") + ", degree " + std::to_string(s.degree[0]) + "x" +
                  std::to_string(s.degree[1]) + ", C^" + std::to_string(ru);
  if (rv != ru) r += "/C^" + std::to_string(rv);
  return r + " at new knots";
}

// A volume case's space options refined `level` times (elements doubled in every direction).
TensorVolumeOptions refined_volume(const CaseDescription& c, int level) {
  TensorVolumeOptions s = family_section<VolumeSpaceSection>(c).space;
  for (int& e : s.elements_per_span) e <<= level;
  return s;
}

class TensorSpace final : public SplineSpace, public SpaceReport {
 public:
  const SpaceReport& presentation() const override { return *this; }
  TensorSpace(const CaseDescription& c, const TensorSpaceOptions& options, RowShare share = {}) : options_(options) {
    check_tensor_memory(c, options, share.ranks);
    diffusion_ = c.problem.coefficients.diffusion;
    try {
      d_ = build_tensor_discretization(c.geometry, options, share);
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": [space]: " + e.what());
    }
    // The residual estimator's neighbours, derived only if something asks (most runs never do).
    d_.mesh.set_interface_rule(&interfaces_from_parameter_boxes);
    geometry_ = std::make_unique<PatchGeometryMap>(
        d_.mesh, d_.patch, PatchGeometryMap::ElementGrid{d_.space_u.breakpoints(), d_.space_v.breakpoints(), d_.first_row});
  }
  const BezierMesh& mesh() const override { return d_.mesh; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::string automatic_structured_preconditioner(std::string& why) const override {
    const double functions = d_.part ? d_.part->global_functions : d_.mesh.num_functions();
    double spread = 1;
    if (!auto_takes_multigrid(d_.patch, diffusion_, functions, spread)) return kFastDiagonalization;
    char text[320];
    std::snprintf(text, sizeof text,
                  "since the map does not separate (the fast diagonalization's fit is off by a factor of %.3g over the "
                  "patch, more than %.3g) and from %.0f functions: measured faster there (docs/SOLVERS.md)",
                  spread, kSeparableEnough, kAutoMultigridOnMaps);
    why = text;
    return kMultigrid;
  }
  std::string description() const override { return describe(options_); }
  std::vector<int> degree() const override { return as_list(options_.degree); }
  std::vector<std::string> structured_preconditioners() const override { return {kFastDiagonalization, kMultigrid}; }
  bool structured_preconditioner_needs_only_diagonal(const std::string& name) const override { return name != kMultigrid; }
  std::unique_ptr<Preconditioner> make_structured_preconditioner(const std::string& name, const DofLayout& layout,
                                                                 const Eigen::SparseMatrix<double>& lower,
                                                                 const PoissonProblem& problem) const override {
    NitscheEnds ends;
    ends.factor = problem.nitsche_penalty;
    if (problem.dirichlet_method == DirichletMethod::kNitsche && problem.boundary.size() == 4)
      for (int s = 0; s < 4; ++s) ends.sides[s] = problem.boundary[s].kind == BoundaryKind::kDirichlet;
    if (name == kMultigrid)
      return tensor_multigrid(d_.space_u, d_.space_v, layout, lower, patch_separable_coefficients(d_, *geometry_), ends);
    return fast_diagonalization(d_.space_u, d_.space_v, layout, lower.diagonal(),
                                patch_separable_coefficients(d_, *geometry_, &problem), ends);
  }
  bool structured_preconditioner_without_matrix(const std::string&) const override { return true; }
  std::unique_ptr<Preconditioner> make_structured_preconditioner_without_matrix(
      const std::string& name, const DofLayout& layout, std::shared_ptr<const MatrixFreePoisson> op,
      const Eigen::VectorXd& free_diagonal) const override {
    // The operator is the one matrix_free_operator made.
    std::shared_ptr<const TensorPoissonOperator> tensor = std::dynamic_pointer_cast<const TensorPoissonOperator>(op);
    if (name != kMultigrid || !tensor) return nullptr;
    if (d_.part) tensor = whole_patch_operator(*tensor);
    return tensor_multigrid(std::move(tensor), layout, free_diagonal, patch_separable_coefficients(d_, *geometry_));
  }
  std::unique_ptr<MatrixFreePoisson> matrix_free_operator(double stiffness, double reaction,
                                                          const QuadratureOptions& quadrature) const override {
    const Eigen::VectorXd* weights = d_.mesh.is_rational() ? &d_.mesh.weights() : nullptr;
    // (The operator lives within a solve on this space: it may read the space's net in place.)
    if (!d_.part)
      return std::make_unique<TensorPoissonOperator>(
          TensorPatch{&d_.space_u, &d_.space_v, weights, &d_.geometry_u, &d_.geometry_v, &d_.geometry_homogeneous,
                      /*geometry_outlives_operator=*/true},
          stiffness, reaction, quadrature.points_u, quadrature.points_v);
    // A process's rows of the patch: the operator of its element rows alone, over the part's
    // functions (their rows along v on their own knots, as the part's net holds the geometry's).
    // Its rows of the functions the process owns are whole: they live on those elements only.
    const int su = d_.space_u.num_functions(), gu = d_.geometry_u.num_functions();
    const BSplineBasis1D rows_v = consecutive_functions(d_.space_v, d_.part->function_offset / su, d_.mesh.num_functions() / su);
    const BSplineBasis1D net_rows_v =
        consecutive_functions(d_.geometry_v, d_.net_first_row, static_cast<int>(d_.geometry_homogeneous.rows() / gu));
    return std::make_unique<TensorPoissonOperator>(
        TensorPatch{&d_.space_u, &rows_v, weights, &d_.geometry_u, &net_rows_v, &d_.geometry_homogeneous,
                    /*geometry_outlives_operator=*/true},
        stiffness, reaction, quadrature.points_u, quadrature.points_v);
  }
  // On a part, the operator of the whole patch with the part's stiffness, reaction and rules:
  // the PCShell applies the preconditioner to the whole residual on every process. Its net is
  // refined whole here, 24 bytes per function, and copied into the operator (the part's own
  // net holds a few rows only).
  std::shared_ptr<const TensorPoissonOperator> whole_patch_operator(const TensorPoissonOperator& part) const {
    const Eigen::MatrixX3d net = refined_homogeneous_net(d_.patch, d_.geometry_u, d_.geometry_v);
    // Geometry and space bases coincide for an isoparametric space: the weights are the net's.
    const Eigen::VectorXd weights = d_.mesh.is_rational() ? Eigen::VectorXd(net.col(2)) : Eigen::VectorXd();
    return std::make_shared<const TensorPoissonOperator>(
        TensorPatch{&d_.space_u, &d_.space_v, &weights, &d_.geometry_u, &d_.geometry_v, &net,
                    /*geometry_outlives_operator=*/false},
        part.stiffness(), part.reaction(), part.points_u(), part.points_v());
  }
  std::vector<ReportField> report() const override {
    return {{.key = "elements", .value = long(options_.elements_per_span[0]), .column = true, .width = 9}};
  }
  const MeshPart* part() const override { return d_.part ? &*d_.part : nullptr; }

 private:
  TensorSpaceOptions options_;
  std::vector<Expression> diffusion_;  // the problem's A (empty: 1): what "auto" measures against the fit
  TensorDiscretization d_;
  std::unique_ptr<PatchGeometryMap> geometry_;
};

}  // namespace

SpaceFamily tensor_family() {
  SpaceFamily f;
  f.name = "tensor";
  f.read_case = read_tensor_case;
  f.structured_preconditioners = {kFastDiagonalization, kMultigrid};
  f.space_keys = tensor_space_keys();
  f.build = [](const CaseDescription& c, int level, const ProgressFunction&) -> std::unique_ptr<SplineSpace> {
    if (c.is_volume()) return make_tensor_volume_space(c, refined_volume(c, level));
    TensorSpaceOptions s = patch_space(c);
    s.elements_per_span = {s.elements_per_span[0] << level, s.elements_per_span[1] << level};
    if (c.multipatch()) {
      check_tensor_memory(c, s);
      return make_multipatch_tensor_space(c, s);
    }
    return std::make_unique<TensorSpace>(c, s);
  };
  f.build_part = [](const CaseDescription& c, int level, int rank, int ranks,
                    const ProgressFunction&) -> std::unique_ptr<SplineSpace> {
    // A volume: each process its slabs of hexahedra along w, as rows along v on a patch.
    if (c.is_volume()) return make_tensor_volume_space(c, refined_volume(c, level), RowShare{rank, ranks});
    TensorSpaceOptions s = patch_space(c);
    s.elements_per_span = {s.elements_per_span[0] << level, s.elements_per_span[1] << level};
    if (c.multipatch()) {
      check_tensor_memory(c, s, ranks);
      // Whole patches per process; with fewer patches than processes every process builds the
      // whole space and assembles its range of cells (the report says which).
      if (c.domain.num_patches() >= ranks) return make_multipatch_tensor_part(c, s, rank, ranks);
      return make_multipatch_tensor_space(c, s);
    }
    return std::make_unique<TensorSpace>(c, s, RowShare{rank, ranks});
  };
  f.override_options = [](CaseDescription& c, int degree, int elements) {
    if (c.is_volume()) override_volume_space(family_section<VolumeSpaceSection>(c).space, degree, elements);
    else override_patch_space(patch_space(c), degree, elements);
  };
  f.check_converge = [](const CaseDescription& c, int levels) {
    if (c.is_volume()) {
      const TensorVolumeOptions finest = refined_volume(c, levels - 1);
      double cells = 1;
      for (int k = 0; k < 3; ++k) cells *= double(finest.elements_per_span[k]) * c.volume.bases[k].num_elements();
      if (cells > double(1L << 26)) throw InputError("--levels: the finest level would have more than 2^26 cells");
      check_tensor_volume_memory(c, finest);  // the finest level, before the first is solved
      return;
    }
    check_uniform_levels(patch_space(c), levels);
    TensorSpaceOptions finest = patch_space(c);
    finest.elements_per_span = {finest.elements_per_span[0] << (levels - 1), finest.elements_per_span[1] << (levels - 1)};
    check_tensor_memory(c, finest);  // the finest level, before the first is solved
  };
  return f;
}

}  // namespace knotwork
