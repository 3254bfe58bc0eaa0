// THB-splines on several patches: basis/thb's ThbMultiPatch behind the SplineSpace interface,
// one PatchGeometryMap per patch side by side.
#include "families/thb/thb_multipatch_space.hpp"

#include <optional>

#include <cstdio>

#include "basis/core/geometry_map.hpp"
#include "basis/core/input_error.hpp"
#include "basis/thb/thb_multipatch.hpp"
#include "cases/resource_limits.hpp"
#include "families/tensor/tensor_case.hpp"
#include "families/thb/thb_refine.hpp"

namespace knotwork {

namespace {

class ThbMultiPatchSpace final : public SplineSpace, public SpaceReport {
 public:
  ThbMultiPatchSpace(const CaseDescription& c, const TensorSpaceOptions& space, ThbMultiPatch hierarchy)
      : case_(std::make_shared<const CaseDescription>(c)), space_(space), hierarchy_(std::move(hierarchy)) {
    try {
      basis_ = hierarchy_.build();
    } catch (const GeometryError& e) {
      throw InputError(c.path + ": [geometry] file: " + e.what());
    } catch (const std::runtime_error& e) {
      throw InputError(c.path + ": [space]: " + e.what());
    }
    std::vector<std::unique_ptr<GeometryMap>> maps;
    try {
      for (size_t p = 0; p < basis_.patch_meshes.size(); ++p)
        maps.push_back(std::make_unique<PatchGeometryMap>(basis_.patch_meshes[p], c.domain.patches[p]));
    } catch (const GeometryError& e) {
      throw InputError(c.path + ": [geometry] file: " + e.what());
    }
    geometry_ = std::make_unique<PiecewiseGeometryMap>(std::move(maps), basis_.glued.first_cell);
  }
  const SpaceReport& presentation() const override { return *this; }
  const BezierMesh& mesh() const override { return basis_.glued.mesh; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::vector<int> degree() const override { return as_list(space_.degree); }
  std::string description() const override {
    const int m = hierarchy_.patches().front().admissibility();
    return "THB-splines, degree " + std::to_string(space_.degree[0]) + "x" + std::to_string(space_.degree[1]) + ", " +
           (m == 0 ? std::string("no grading") : "T-admissible of class " + std::to_string(m)) + ", " +
           std::to_string(hierarchy_.patches().size()) + " patches glued C^0";
  }
  std::vector<ReportField> report() const override {
    const long patches = static_cast<long>(hierarchy_.patches().size());
    return {{.key = "levels", .value = long(basis_.functions_per_level.size()), .column = true, .width = 7},
            {.key = "patches", .value = patches, .text = std::to_string(patches)}};
  }
  std::vector<ReportField> basis_report() const override { return {functions_per_level_field(basis_.functions_per_level)}; }
  std::unique_ptr<SplineSpace> refine(const std::vector<int>& marked, const std::vector<CellSplit>& /*split*/,
                                      int* extended, const ProgressFunction& /*progress*/) && override {
    ThbMultiPatch next = refined_hierarchy(*case_, hierarchy_, basis_.leaves, marked, extended);
    auto fine = std::make_unique<ThbMultiPatchSpace>(*case_, space_, std::move(next));
    if (keep_prolongations_) {
      fine->keep_prolongations_ = true;
      fine->prolongation_ = fine->hierarchy_.prolongation(basis_, fine->basis_);
    }
    return fine;
  }
  bool keep_prolongations() override { return keep_prolongations_ = true; }
  const Eigen::SparseMatrix<double>* prolongation_from_predecessor() const override {
    return prolongation_ ? &*prolongation_ : nullptr;
  }
  KnotLines knot_lines() const override { return knot_lines_of_cells(basis_.glued.mesh, *geometry_); }

 private:
  std::shared_ptr<const CaseDescription> case_;  // a copy: the space does not need the caller's case to live on
  TensorSpaceOptions space_;
  ThbMultiPatch hierarchy_;
  ThbMultiPatch::Basis basis_;  // its patch meshes are what the geometry maps read
  std::unique_ptr<GeometryMap> geometry_;
  bool keep_prolongations_ = false;
  std::optional<Eigen::SparseMatrix<double>> prolongation_;
};

}  // namespace

std::unique_ptr<SplineSpace> make_thb_multipatch_space(const CaseDescription& c, const TensorSpaceOptions& space,
                                                       int admissibility, int level) {
  std::vector<ThbHierarchy> patches;
  double cells = 0, functions = 0;
  for (const NurbsPatch& p : c.domain.patches) {
    DyadicKnots u = patch_dyadic_knots(p, space, 0, level), v = patch_dyadic_knots(p, space, 1, level);
    cells += double(u.base_elements()) * v.base_elements();
    functions += double(u.num_functions(0)) * double(v.num_functions(0));
    patches.emplace_back(std::move(u), std::move(v), admissibility);
  }
  char text[120];
  std::snprintf(text, sizeof text, "%.3g THB cells of degree %dx%d on %d patches", cells, space.degree[0], space.degree[1],
                c.domain.num_patches());
  check_memory(c.path + ": [space] elements", galerkin_bytes(cells, functions, space.degree[0], space.degree[1]), text);
  return std::make_unique<ThbMultiPatchSpace>(c, space, ThbMultiPatch(c.domain, std::move(patches)));
}

}  // namespace knotwork
