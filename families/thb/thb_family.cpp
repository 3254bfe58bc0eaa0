// Family "thb": truncated hierarchical B-splines on one patch's parameter domain (or on every
// patch of a multipatch domain, glued C0: thb_multipatch_space), starting
// from the tensor mesh of [space] degree and elements on the geometry's knot spans (its C0
// lines kept), refined by halving marked cells in both directions; graded to stay
// T-admissible of class [space] admissibility (2 by default, 0: no grading). On a volume the
// same with hexahedra halved in all three directions (thb_volume_space).
#include <cstdio>
#include <memory>
#include <optional>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "families/tensor/tensor_case.hpp"
#include "families/thb/thb_multipatch_space.hpp"
#include "families/thb/thb_refine.hpp"
#include "families/thb/thb_volume_space.hpp"
#include "basis/thb/thb_hierarchy.hpp"
#include "basis/thb/thb_prolongation.hpp"
#include "cases/case_reader.hpp"
#include "cases/resource_limits.hpp"
#include "cases/spline_space.hpp"
#include "basis/core/geometry_map.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

struct ThbSection : PatchSpaceSection {
  int admissibility = 2;
  std::unique_ptr<CaseSection> clone() const override { return std::make_unique<ThbSection>(*this); }
};

const std::vector<std::string>& thb_space_keys() {
  static const std::vector<std::string> keys{"family", "degree", "elements", "admissibility", "quadrature_points",
                                             "error_quadrature_points"};
  return keys;
}

void read_thb_case(const CaseDocument& doc, CaseDescription& c) {
  if (is_volume_geometry(doc)) return read_thb_volume_case(doc, c, thb_space_keys());
  const CaseReader& r = doc.reader;
  const DocumentNode& s = read_dyadic_patch_start(doc, c, "thb", thb_space_keys(), "new knots are C^(d-1)", true);
  ThbSection& t = c.section.emplace<ThbSection>();
  t.space.rational = false;
  if (const DocumentNode* a = s.get("admissibility")) {
    const long m = r.integer(*a, "[space] admissibility");
    if (m != 0 && (m < 2 || m > 8))
      r.fail("[space] admissibility", "must be 0 (no grading) or a class m in 2..8, not " + std::to_string(m));
    t.admissibility = static_cast<int>(m);
  }
  read_patch_degree_elements(doc, t.space, false);
  read_quadrature(r, s, c);
  read_patch_problem(doc, c);
}

const ThbSection& thb_section(const CaseDescription& c) { return family_section<ThbSection>(c); }

// One patch's or one volume's THB space: the hierarchy's basis on the case's NURBS patch or
// volume (whose removed parts the hierarchy already left out).
class ThbSpace final : public SplineSpace, public SpaceReport {
 public:
  const SpaceReport& presentation() const override { return *this; }
  ThbSpace(const CaseDescription& c, ThbHierarchy hierarchy) : case_(std::make_shared<const CaseDescription>(c)), hierarchy_(std::move(hierarchy)) {
    ThbHierarchy::Basis b = built_basis(c, hierarchy_);
    mesh_ = std::move(b.mesh);
    leaves_ = std::move(b.leaves);
    per_level_ = std::move(b.functions_per_level);
    if (hierarchy_.dimension() == 2) {
      geometry_ = finish_patch_mesh(c, mesh_);
      return;
    }
    mesh_.set_interface_rule(&interfaces_from_parameter_boxes);  // for the estimator, built when it asks
    try {
      geometry_ = std::make_unique<VolumeGeometryMap>(mesh_, c.volume);
    } catch (const GeometryError& e) {
      throw InputError(c.path + ": [geometry]: " + e.what());
    }
  }

  const BezierMesh& mesh() const override { return mesh_; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::string description() const override {
    std::string degrees;
    for (int d : degree()) degrees += (degrees.empty() ? "" : "x") + std::to_string(d);
    const int m = hierarchy_.admissibility();
    return "THB-splines, degree " + degrees + (hierarchy_.dimension() == 3 ? " on hexahedra" : "") + ", " +
           (m == 0 ? std::string("no grading") : "T-admissible of class " + std::to_string(m));
  }
  std::vector<int> degree() const override {
    std::vector<int> d;
    for (int k = 0; k < hierarchy_.dimension(); ++k) d.push_back(hierarchy_.knots(k).degree());
    return d;
  }
  std::vector<ReportField> report() const override {
    return {{.key = "levels", .value = long(per_level_.size()), .column = true, .width = 7}};
  }
  std::vector<ReportField> basis_report() const override { return {functions_per_level_field(per_level_)}; }
  std::unique_ptr<SplineSpace> refine(const std::vector<int>& marked, const std::vector<CellSplit>& /*split*/,
                                      int* extended, const ProgressFunction& /*progress*/) && override {
    ThbHierarchy next = refined_hierarchy(*case_, hierarchy_, leaves_, marked, extended);
    auto fine = std::make_unique<ThbSpace>(*case_, std::move(next));
    if (keep_prolongations_) {
      fine->keep_prolongations_ = true;
      fine->prolongation_ = thb_prolongation(fine->hierarchy_, mesh_, leaves_, fine->mesh_, fine->leaves_, fine->per_level_);
    }
    return fine;
  }
  bool keep_prolongations() override { return keep_prolongations_ = true; }
  const Eigen::SparseMatrix<double>* prolongation_from_predecessor() const override {
    return prolongation_ ? &*prolongation_ : nullptr;
  }
  // A volume's hexahedra show their sides in ParaView themselves: no lines drawn.
  KnotLines knot_lines() const override { return hierarchy_.dimension() == 2 ? knot_lines_of_cells(mesh_, *geometry_) : KnotLines{}; }

 private:
  std::shared_ptr<const CaseDescription> case_;  // a copy: the space does not need the caller's case to live on
  ThbHierarchy hierarchy_;
  BezierMesh mesh_;
  std::vector<ThbCell> leaves_;
  std::vector<int> per_level_;
  std::unique_ptr<GeometryMap> geometry_;
  bool keep_prolongations_ = false;
  std::optional<Eigen::SparseMatrix<double>> prolongation_;
};

std::unique_ptr<SplineSpace> build_thb(const CaseDescription& c, int level) {
  if (c.is_volume()) return make_thb_volume_space(c, level);
  const ThbSection& t = thb_section(c);
  if (c.multipatch()) return make_thb_multipatch_space(c, t.space, t.admissibility, level);
  DyadicKnots u = patch_dyadic_knots(c.geometry, t.space, 0, level), v = patch_dyadic_knots(c.geometry, t.space, 1, level);
  check_dyadic_start_memory(c, u, v, "THB");
  return make_thb_space(c, ThbHierarchy(std::move(u), std::move(v), t.admissibility));
}

}  // namespace

std::unique_ptr<SplineSpace> make_thb_space(const CaseDescription& c, ThbHierarchy hierarchy) {
  return std::make_unique<ThbSpace>(c, std::move(hierarchy));
}

SpaceFamily thb_family() {
  SpaceFamily f;
  f.name = "thb";
  f.read_case = read_thb_case;
  f.space_keys = thb_space_keys();
  f.build = [](const CaseDescription& c, int level, const ProgressFunction&) { return build_thb(c, level); };
  f.local_refinement = true;
  f.override_options = [](CaseDescription& c, int degree, int elements) {
    if (c.is_volume()) return override_thb_volume_space(c, degree, elements);
    override_patch_space(family_section<ThbSection>(c).space, degree, elements);
  };
  f.check_converge = [](const CaseDescription& c, int levels) {
    if (c.is_volume()) return check_thb_volume_levels(c, levels);
    check_uniform_levels(thb_section(c).space, levels);
  };
  return f;
}

}  // namespace knotwork
