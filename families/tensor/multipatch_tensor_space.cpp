// The tensor family's space on a multipatch domain: basis/tensor's conforming construction,
// one PatchGeometryMap per patch side by side, reported like the one-patch space.
#include "families/tensor/multipatch_tensor_space.hpp"

#include "basis/core/geometry_map.hpp"
#include "basis/core/input_error.hpp"
#include "basis/tensor/multipatch_tensor.hpp"
#include "families/tensor/patch_separable_coefficients.hpp"
#include "solver/additive_schwarz.hpp"
#include "solver/fast_diagonalization.hpp"
#include "solver/glued_operator.hpp"
#include "solver/patchwise_multigrid.hpp"
#include "solver/tensor_operator.hpp"

namespace knotwork {

namespace {

constexpr const char* kPatchFastDiagonalization = "fast_diagonalization";
constexpr const char* kPatchMultigrid = "multigrid";

std::string describe_multipatch(const TensorSpaceOptions& o, int patches) {
  const int ru = o.continuity[0] < 0 ? o.degree[0] - 1 : o.continuity[0];
  return std::string(o.rational ? "NURBS" : "B-spline") + ", degree " + std::to_string(o.degree[0]) + "x" +
         std::to_string(o.degree[1]) + ", C^" + std::to_string(ru) + " at new knots, " + std::to_string(patches) +
         " patches glued C^0";
}

std::vector<ReportField> multipatch_report(const TensorSpaceOptions& o, int patches) {
  return {{.key = "elements", .value = long(o.elements_per_span[0]), .column = true, .width = 9},
          {.key = "patches", .value = long(patches), .text = std::to_string(patches)}};
}

// The map of a patch's whole space, on the grid of its elements.
std::unique_ptr<PatchGeometryMap> patch_grid_map(const TensorDiscretization& t) {
  return std::make_unique<PatchGeometryMap>(
      t.mesh, t.patch, PatchGeometryMap::ElementGrid{t.space_u.breakpoints(), t.space_v.breakpoints(), 0});
}

// Patch k's sides whose Dirichlet data `problem` imposes by Nitsche's method (`exterior`:
// boundary id -> patch side).
NitscheEnds nitsche_ends(const std::vector<PatchSideRef>& exterior, int k, const PoissonProblem& problem) {
  NitscheEnds ends;
  ends.factor = problem.nitsche_penalty;
  const std::array<int, 4> boundary_id = boundary_ids_of_patch(exterior, k);
  for (int s = 0; s < 4; ++s)
    ends.sides[s] = problem.dirichlet_method == DirichletMethod::kNitsche && boundary_id[s] >= 0 &&
                    problem.boundary.at(boundary_id[s]).kind == BoundaryKind::kDirichlet;
  return ends;
}

// What basis/tensor's builders throw, as the case's errors.
template <class Build>
auto built(const CaseDescription& c, Build build) {
  try {
    return build();
  } catch (const GeometryError& e) {
    throw InputError(c.path + ": [geometry] file: " + e.what());
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": [space]: " + e.what());
  }
}

class MultiPatchTensorSpace final : public SplineSpace, public SpaceReport {
 public:
  MultiPatchTensorSpace(const CaseDescription& c, const TensorSpaceOptions& options)
      : options_(options), d_(built(c, [&] { return build_multipatch_tensor(c.domain, options); })) {
    std::vector<std::unique_ptr<GeometryMap>> maps;
    for (const TensorDiscretization& p : d_.patches) {
      auto map = patch_grid_map(p);
      patch_maps_.push_back(map.get());
      maps.push_back(std::move(map));
    }
    exterior_ = exterior_sides(c.domain);
    geometry_ = std::make_unique<PiecewiseGeometryMap>(std::move(maps), d_.first_cell);
  }
  const SpaceReport& presentation() const override { return *this; }
  const BezierMesh& mesh() const override { return d_.mesh; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::vector<int> degree() const override { return as_list(options_.degree); }
  std::string description() const override { return describe_multipatch(options_, static_cast<int>(d_.patches.size())); }
  // Multigrid first, the one "auto" takes (from 10 000 functions): measured (docs/SOLVERS.md,
  // "On several patches") 6-11 CG iterations from 3 000 to 3.2M dofs and for p = 2..6, and
  // faster than CHOLMOD and BoomerAMG from about 10 000 dofs at p = 2 (2.2x faster than CHOLMOD
  // at 0.8M). The per-patch fast diagonalization has no coarse space: by name only.
  std::vector<std::string> structured_preconditioners() const override {
    return {kPatchMultigrid, kPatchFastDiagonalization};
  }
  bool structured_preconditioner_needs_only_diagonal(const std::string& name) const override {
    return name != kPatchMultigrid;
  }
  std::unique_ptr<Preconditioner> make_structured_preconditioner(const std::string& name, const DofLayout& layout,
                                                                 const Eigen::SparseMatrix<double>& lower,
                                                                 const PoissonProblem& problem) const override {
    if (name == kPatchMultigrid) return multigrid(layout, lower, problem);
    return patch_schwarz(layout, lower, problem);
  }
  std::vector<ReportField> report() const override { return multipatch_report(options_, static_cast<int>(d_.patches.size())); }
  // Each patch's operator (as one patch's space makes it), glued by the shared numbering: its
  // matrix written patch by patch (the Kronecker form or sum factorization) instead of the
  // element loop, and CG without a matrix with "jacobi".
  std::unique_ptr<MatrixFreePoisson> matrix_free_operator(double stiffness, double reaction,
                                                          const QuadratureOptions& quadrature) const override {
    std::vector<std::unique_ptr<MatrixFreePoisson>> pieces;
    for (const TensorDiscretization& p : d_.patches) {
      const Eigen::VectorXd* weights = p.mesh.is_rational() ? &p.mesh.weights() : nullptr;
      // (The operators live within a solve on this space: they may read the patches' nets in place.)
      pieces.push_back(std::make_unique<TensorPoissonOperator>(
          TensorPatch{&p.space_u, &p.space_v, weights, &p.geometry_u, &p.geometry_v, &p.geometry_homogeneous,
                      /*geometry_outlives_operator=*/true},
          stiffness, reaction, quadrature.points_u, quadrature.points_v));
    }
    return std::make_unique<GluedPoissonOperator>(d_.mesh.num_functions(), std::move(pieces), d_.global_function);
  }

 private:
  // One fast diagonalization per patch, summed (additive Schwarz, no coarse space): each
  // patch's block is its free functions, interface functions included (so they overlap), the
  // tensor hull of them inverted and restricted to them.
  std::unique_ptr<Preconditioner> patch_schwarz(const DofLayout& layout, const Eigen::SparseMatrix<double>& lower,
                                                const PoissonProblem& problem) const {
    const Eigen::VectorXd diagonal = lower.diagonal();
    std::vector<SchwarzBlock> blocks;
    for (size_t k = 0; k < d_.patches.size(); ++k) {
      const TensorDiscretization& t = d_.patches[k];
      const int nu = t.space_u.num_functions(), nv = t.space_v.num_functions();
      std::vector<bool> free_u(nu, false), free_v(nv, false);
      for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i)
          if (layout.dof[d_.global_function[k][i + nu * j]] >= 0) free_u[i] = free_v[j] = true;
      DofLayout hull;
      hull.dof.assign(static_cast<size_t>(nu) * nv, -1);
      SchwarzBlock b;
      std::vector<double> diag;
      for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
          if (!free_u[i] || !free_v[j]) continue;
          const int f = i + nu * j, global = layout.dof[d_.global_function[k][f]];
          hull.dof[f] = hull.num_free();
          hull.function_of_dof.push_back(f);
          b.dofs.push_back(global);
          diag.push_back(global >= 0 ? diagonal[global] : 0.0);
        }
      b.local = fast_diagonalization(t.space_u, t.space_v, hull, Eigen::Map<const Eigen::VectorXd>(diag.data(), diag.size()),
                                     patch_separable_coefficients(t, *patch_maps_[k], &problem),
                                     nitsche_ends(exterior_, static_cast<int>(k), problem));
      if (!b.local) throw std::logic_error("fast diagonalization of a patch: its free functions' hull is not a tensor product");
      blocks.push_back(std::move(b));
    }
    return additive_schwarz(std::move(blocks), layout.num_free());
  }

  // Geometric multigrid over the space's uniform refinements (solver/patchwise_multigrid.hpp,
  // which makes the coarser levels from this one).
  std::unique_ptr<Preconditioner> multigrid(const DofLayout& layout, const Eigen::SparseMatrix<double>& lower,
                                            const PoissonProblem& problem) const {
    PatchwiseLevel finest;
    for (size_t k = 0; k < d_.patches.size(); ++k) {
      const TensorDiscretization& t = d_.patches[k];
      finest.patches.push_back(planar_multigrid_patch(t.space_u, t.space_v, patch_separable_coefficients(t, *patch_maps_[k]),
                                                      nitsche_ends(exterior_, static_cast<int>(k), problem), d_.global_function[k]));
    }
    finest.layout = layout;
    return patchwise_multigrid(std::move(finest), lower);
  }

  TensorSpaceOptions options_;
  MultiPatchTensorDiscretization d_;
  std::unique_ptr<GeometryMap> geometry_;
  std::vector<const PatchGeometryMap*> patch_maps_;  // owned by geometry_
  std::vector<PatchSideRef> exterior_;               // boundary id -> patch side
};

// Some cells of another map, renumbered: cell k here is cell cells[k] there.
class SubsetGeometryMap final : public GeometryMap {
 public:
  SubsetGeometryMap(const GeometryMap& whole, std::vector<int> cells) : whole_(whole), cells_(std::move(cells)) {}
  int dimension() const override { return whole_.dimension(); }
  void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const override {
    whole_.evaluate_at_rule(cells_[cell], nu, nv, out);
  }
  void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v, GeometryAtPoints& out) const override {
    whole_.evaluate(cells_[cell], u, v, out);
  }
  BezierGeometryCell bezier_cell(int cell) const override { return whole_.bezier_cell(cells_[cell]); }
  bool second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v, Eigen::MatrixXd& out) const override {
    return whole_.second_derivatives(cells_[cell], u, v, out);
  }

 private:
  const GeometryMap& whole_;
  std::vector<int> cells_;
};

// One rank's part (basis/tensor's build_multipatch_tensor_part): the owned patches and the
// halo cells of later ones, each patch's map over the cells the part holds.
class MultiPatchTensorPartSpace final : public SplineSpace, public SpaceReport {
 public:
  MultiPatchTensorPartSpace(const CaseDescription& c, const TensorSpaceOptions& options, int rank, int ranks)
      : options_(options), d_(built(c, [&] { return build_multipatch_tensor_part(c.domain, options, rank, ranks); })) {
    std::vector<std::unique_ptr<GeometryMap>> maps;
    for (size_t k = 0; k < d_.built.size(); ++k) {
      patch_maps_.push_back(patch_grid_map(d_.built[k]));
      maps.push_back(std::make_unique<SubsetGeometryMap>(*patch_maps_.back(), d_.cells_of_piece[k]));
    }
    geometry_ = std::make_unique<PiecewiseGeometryMap>(std::move(maps), d_.first_cell);
    patches_ = c.domain.num_patches();
    domain_ = c.domain;
    exterior_ = exterior_sides(c.domain);
  }
  const SpaceReport& presentation() const override { return *this; }
  const BezierMesh& mesh() const override { return d_.mesh; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::vector<int> degree() const override { return as_list(options_.degree); }
  const MeshPart* part() const override { return &d_.part; }
  std::string description() const override { return describe_multipatch(options_, patches_); }
  std::vector<ReportField> report() const override { return multipatch_report(options_, patches_); }
  // Multigrid on several patches as a PCShell (method = "petsc"): every process builds it over
  // the whole space from the whole matrix, gathered (studies/pipeline.cpp), and from every
  // patch's bases, fit and glued numbering, which need no cell (number_multipatch_functions).
  // What "auto" takes: on 2 processes 1.3-8x faster than BoomerAMG at p = 2..6, for 1.5-1.7x
  // the memory per process (docs/SOLVERS.md, "Multigrid under PETSc").
  std::vector<std::string> structured_preconditioners() const override { return {kPatchMultigrid}; }
  bool structured_preconditioner_needs_only_diagonal(const std::string&) const override { return false; }
  std::unique_ptr<Preconditioner> make_structured_preconditioner(const std::string& /*name: the one*/,
                                                                 const DofLayout& layout,
                                                                 const Eigen::SparseMatrix<double>& lower,
                                                                 const PoissonProblem& problem) const override {
    const MultiPatchNumbering numbering = number_multipatch_functions(domain_, options_);
    PatchwiseLevel finest;
    for (int k = 0; k < domain_.num_patches(); ++k) {
      const BSplineBasis1D &u = numbering.bases[k][0], &v = numbering.bases[k][1];
      std::vector<int> function(numbering.number.begin() + numbering.first_function[k],
                                numbering.number.begin() + numbering.first_function[k + 1]);
      finest.patches.push_back(planar_multigrid_patch(u, v, patch_separable_coefficients(domain_.patches[k], u, v),
                                                      nitsche_ends(exterior_, k, problem), std::move(function)));
    }
    finest.layout = layout;
    return patchwise_multigrid(std::move(finest), lower);
  }
  // The operators of the patches this process holds (whole: a neighbour's patch too, where the
  // halo takes cells of it), glued by the part's numbering; a neighbour's functions that the
  // part does not hold are left out. The owned functions' rows are whole (their cells are all
  // held), and the driver writes them from it (solver/poisson_solver.cpp).
  std::unique_ptr<MatrixFreePoisson> matrix_free_operator(double stiffness, double reaction,
                                                          const QuadratureOptions& quadrature) const override {
    const MultiPatchNumbering numbering = number_multipatch_functions(domain_, options_);
    const MeshPart& share = d_.part;
    const int held = d_.mesh.num_functions();
    const auto local_of = [&](int global) {
      if (share.global_function.empty()) {
        const int local = global - share.function_offset;
        return local >= 0 && local < held ? local : -1;
      }
      const auto at = std::lower_bound(share.global_function.begin(), share.global_function.end(), global);
      return at != share.global_function.end() && *at == global ? int(at - share.global_function.begin()) : -1;
    };
    std::vector<std::unique_ptr<MatrixFreePoisson>> pieces;
    std::vector<std::vector<int>> local;
    for (size_t k = 0; k < d_.built.size(); ++k) {
      const TensorDiscretization& p = d_.built[k];
      const int patch = d_.patch_of_piece[k];
      const Eigen::VectorXd* weights = p.mesh.is_rational() ? &p.mesh.weights() : nullptr;
      pieces.push_back(std::make_unique<TensorPoissonOperator>(
          TensorPatch{&p.space_u, &p.space_v, weights, &p.geometry_u, &p.geometry_v, &p.geometry_homogeneous,
                      /*geometry_outlives_operator=*/true},
          stiffness, reaction, quadrature.points_u, quadrature.points_v));
      std::vector<int> numbers(numbering.number.begin() + numbering.first_function[patch],
                               numbering.number.begin() + numbering.first_function[patch + 1]);
      for (int& n : numbers) n = local_of(n);
      local.push_back(std::move(numbers));
    }
    return std::make_unique<GluedPoissonOperator>(held, std::move(pieces), std::move(local));
  }

 private:
  TensorSpaceOptions options_;
  MultiPatch domain_;                 // every patch: the multigrid's levels span them all
  std::vector<PatchSideRef> exterior_;  // boundary id -> patch side
  MultiPatchTensorPart d_;
  std::vector<std::unique_ptr<PatchGeometryMap>> patch_maps_;  // over each piece's whole patch
  std::unique_ptr<GeometryMap> geometry_;
  int patches_ = 0;
};

}  // namespace

std::unique_ptr<SplineSpace> make_multipatch_tensor_part(const CaseDescription& c, const TensorSpaceOptions& options,
                                                         int rank, int ranks) {
  return std::make_unique<MultiPatchTensorPartSpace>(c, options, rank, ranks);
}

std::unique_ptr<SplineSpace> make_multipatch_tensor_space(const CaseDescription& c, const TensorSpaceOptions& options) {
  return std::make_unique<MultiPatchTensorSpace>(c, options);
}

void multipatch_tensor_size(const CaseDescription& c, const TensorSpaceOptions& s, double& cells, double& functions) {
  cells = functions = 0;
  for (const NurbsPatch& p : c.domain.patches) {
    double pc = 1, pf = 1;
    for (int d = 0; d < 2; ++d) {
      const double elements = double((d == 0 ? p.basis_u : p.basis_v).num_elements()) * s.elements_per_span[d];
      pc *= elements;
      pf *= elements + s.degree[d];
    }
    cells += pc, functions += pf;
  }
}

}  // namespace knotwork
