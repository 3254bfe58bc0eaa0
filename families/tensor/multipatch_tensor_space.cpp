// The tensor family's space on a multipatch domain: basis/tensor's conforming construction,
// one PatchGeometryMap per patch side by side, reported like the one-patch space.
#include "families/tensor/multipatch_tensor_space.hpp"

#include "basis/core/geometry_map.hpp"
#include "basis/core/input_error.hpp"
#include "basis/tensor/multipatch_tensor.hpp"

namespace knotwork {

namespace {

class MultiPatchTensorSpace final : public SplineSpace, public SpaceReport {
 public:
  MultiPatchTensorSpace(const CaseDescription& c, const TensorSpaceOptions& options) : options_(options) {
    try {
      d_ = build_multipatch_tensor(c.domain, options);
    } catch (const GeometryError& e) {
      throw InputError(c.path + ": [geometry] file: " + e.what());
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": [space]: " + e.what());
    }
    std::vector<std::unique_ptr<GeometryMap>> maps;
    for (const TensorDiscretization& p : d_.patches)
      maps.push_back(std::make_unique<PatchGeometryMap>(
          p.mesh, p.patch, PatchGeometryMap::ElementGrid{p.space_u.breakpoints(), p.space_v.breakpoints(), 0}));
    geometry_ = std::make_unique<PiecewiseGeometryMap>(std::move(maps), d_.first_cell);
  }
  const SpaceReport& presentation() const override { return *this; }
  const BezierMesh& mesh() const override { return d_.mesh; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::array<int, 2> degree() const override { return options_.degree; }
  std::string description() const override {
    const int ru = options_.continuity[0] < 0 ? options_.degree[0] - 1 : options_.continuity[0];
    return std::string(options_.rational ? "NURBS" : "B-spline") + ", degree " + std::to_string(options_.degree[0]) + "x" +
           std::to_string(options_.degree[1]) + ", C^" + std::to_string(ru) + " at new knots, " +
           std::to_string(d_.patches.size()) + " patches glued C^0";
  }
  std::vector<ReportField> report() const override {
    return {{.key = "elements", .value = long(options_.elements_per_span[0]), .column = true, .width = 9},
            {.key = "patches", .value = long(d_.patches.size()), .text = std::to_string(d_.patches.size())}};
  }

 private:
  TensorSpaceOptions options_;
  MultiPatchTensorDiscretization d_;
  std::unique_ptr<GeometryMap> geometry_;
};

}  // namespace

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
