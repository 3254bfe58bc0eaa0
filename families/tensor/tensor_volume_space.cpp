// The tensor family on a volume: the trivariate space of basis/tensor (build_tensor_volume) on
// the case's NURBS volume, evaluated exactly by VolumeGeometryMap.
#include "families/tensor/tensor_volume_space.hpp"

#include <cstdio>
#include <stdexcept>

#include "basis/core/input_error.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "cases/resource_limits.hpp"

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
  TensorVolumeSpace(const CaseDescription& c, const TensorVolumeOptions& options) : options_(options) {
    check_tensor_volume_memory(c, options);
    try {
      d_ = build_tensor_volume(c.volume, options);
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
  const BezierMesh& mesh() const override { return d_.mesh; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::vector<int> degree() const override { return as_list(options_.degree); }
  std::string description() const override { return describe(options_, d_.mesh.is_rational()); }
  std::vector<ReportField> report() const override {
    return {{.key = "elements", .value = long(options_.elements_per_span[0]), .column = true, .width = 9}};
  }

 private:
  TensorVolumeOptions options_;
  TensorVolumeDiscretization d_;
  std::unique_ptr<VolumeGeometryMap> geometry_;
};

}  // namespace

void check_tensor_volume_memory(const CaseDescription& c, const TensorVolumeOptions& o) {
  double cells = 1, functions = 1;
  for (int k = 0; k < 3; ++k) {
    const double elements = double(c.volume.bases[k].num_elements()) * o.elements_per_span[k];
    cells *= elements;
    functions *= elements * (o.degree[k] - continuity_of(o, k)) + continuity_of(o, k) + 1;
  }
  // The path the solve takes: a volume has no structured preconditioner, so "auto" is the
  // direct solve; "iterative" is CG with BoomerAMG (or the named one) on the assembled matrix.
  const bool iterative = c.solver.method == "iterative";
  const std::string preconditioner = c.solver.preconditioner == "auto" ? "boomeramg" : c.solver.preconditioner;
  char what[200];
  std::snprintf(what, sizeof what, "%.3g hexahedra of degree %dx%dx%d (%.3g unknowns, %s)", cells, o.degree[0], o.degree[1],
                o.degree[2], functions, iterative ? ("CG + " + preconditioner).c_str() : "direct solve; CG with --solver iterative needs less");
  // The ordering "auto" takes on volumes is METIS; "default" (CHOLMOD's own choice) counted as AMD's fill.
  const bool metis = c.solver.ordering == "auto" || c.solver.ordering == "metis" || c.solver.ordering == "nesdis";
  check_memory(c.path + ": [space] elements",
               iterative ? volume_iterative_bytes(cells, functions, o.degree, preconditioner, !c.solver.petsc_options.empty())
                         : volume_galerkin_bytes(cells, functions, o.degree, metis),
               what);
}

std::unique_ptr<SplineSpace> make_tensor_volume_space(const CaseDescription& c, const TensorVolumeOptions& options) {
  return std::make_unique<TensorVolumeSpace>(c, options);
}

}  // namespace knotwork
