// Family "lr": LR B-splines on one patch's parameter domain, starting from the tensor mesh of
// [space] degree and elements on the geometry's knot spans (its C0 lines kept), refined by
// meshline insertion ([space] refinement: structured_mesh by default, minimal_span, full_span).
// Every space is checked for linear dependence; a dependent one is refused unless the
// command was given --allow-dependent.
#include <cstdio>
#include <memory>
#include <optional>

#include "basis/lr/lr_mesh.hpp"
#include "families/tensor/tensor_case.hpp"
#include "cases/case_reader.hpp"
#include "cases/resource_limits.hpp"
#include "cases/spline_space.hpp"
#include "basis/core/geometry_map.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// A meshline of [space] meshlines, in parameter coordinates.
struct MeshlineInput {
  bool vertical = true;
  double position = 0, from = 0, to = 0;
};

struct LrSection : PatchSpaceSection {
  DyadicLrMesh::Strategy strategy = DyadicLrMesh::Strategy::kStructuredMesh;
  std::vector<MeshlineInput> meshlines;  // inserted in order into the start mesh
  std::unique_ptr<CaseSection> clone() const override { return std::make_unique<LrSection>(*this); }
};

const std::vector<std::string>& lr_space_keys() {
  static const std::vector<std::string> keys{"family",   "degree",           "elements",
                                             "refinement", "meshlines",      "quadrature_points",
                                             "error_quadrature_points"};
  return keys;
}

const char* strategy_name(DyadicLrMesh::Strategy s) {
  switch (s) {
    case DyadicLrMesh::Strategy::kMinimalSpan: return "minimal_span";
    case DyadicLrMesh::Strategy::kFullSpan: return "full_span";
    case DyadicLrMesh::Strategy::kStructuredMesh: return "structured_mesh";
  }
  return "";
}

void read_lr_case(const CaseDocument& doc, CaseDescription& c) {
  const CaseReader& r = doc.reader;
  const DocumentNode& s = read_dyadic_patch_start(doc, c, "lr", lr_space_keys(), "inserted meshlines are simple knots");
  LrSection& l = c.section.emplace<LrSection>();
  l.space.rational = false;
  if (const DocumentNode* x = s.get("refinement")) {
    const std::string name = r.string(*x, "[space] refinement");
    bool found = false;
    for (auto st : {DyadicLrMesh::Strategy::kMinimalSpan, DyadicLrMesh::Strategy::kFullSpan,
                    DyadicLrMesh::Strategy::kStructuredMesh})
      if (name == strategy_name(st)) l.strategy = st, found = true;
    if (!found)
      r.fail("[space] refinement", "must be \"minimal_span\", \"full_span\" or \"structured_mesh\", not \"" + name + "\"");
  }
  if (const DocumentNode* m = s.get("meshlines")) {
    const DocumentNode* a = m->as_array();
    if (!a) r.fail("[space] meshlines", "must be a list of { direction, position, from, to }");
    for (size_t i = 0; i < a->size(); ++i) {
      const std::string field = "[space] meshlines[" + std::to_string(i) + "]";
      const DocumentNode* t = a->get(i)->as_table();
      if (!t) r.fail(field, "must be a table { direction = \"vertical\", position = ..., from = ..., to = ... }");
      r.check_keys(*t, "space] meshlines[" + std::to_string(i), {"direction", "position", "from", "to"});
      for (const char* key : {"direction", "position", "from", "to"})
        if (!t->get(key)) r.fail(field + " " + key, "missing");
      MeshlineInput line;
      const std::string dir = r.string(*t->get("direction"), field + " direction");
      if (dir != "vertical" && dir != "horizontal") r.fail(field + " direction", "must be \"vertical\" or \"horizontal\"");
      line.vertical = dir == "vertical";
      line.position = r.number(*t->get("position"), field + " position");
      line.from = r.number(*t->get("from"), field + " from");
      line.to = r.number(*t->get("to"), field + " to");
      l.meshlines.push_back(line);
    }
  }
  read_patch_degree_elements(doc, l.space, false);
  if (l.space.degree[0] > DyadicLrMesh::kMaxDegree || l.space.degree[1] > DyadicLrMesh::kMaxDegree)
    r.fail("[space] degree", "LR B-splines are built here up to degree " + std::to_string(DyadicLrMesh::kMaxDegree));
  read_quadrature(r, s, c);
  read_patch_problem(doc, c);
}

const LrSection& lr_section(const CaseDescription& c) { return family_section<LrSection>(c); }


class LrSpace final : public SplineSpace, public SpaceReport {
 public:
  const SpaceReport& presentation() const override { return *this; }
  LrSpace(const CaseDescription& c, DyadicLrMesh lr) : case_(std::make_shared<const CaseDescription>(c)), lr_(std::move(lr)) {
    mesh_ = lr_.bezier_mesh();
    dependence_ = DyadicLrMesh::dependence(mesh_);
    geometry_ = finish_patch_mesh(c, mesh_);
  }

  const BezierMesh& mesh() const override { return mesh_; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::string description() const override {
    const auto d = degree();
    return "LR B-splines, degree " + std::to_string(d[0]) + "x" + std::to_string(d[1]) + ", " +
           strategy_name(lr_section(*case_).strategy) + " refinement";
  }
  std::vector<int> degree() const override { return as_list(lr_section(*case_).space.degree); }
  std::vector<ReportField> report() const override {
    return {{.key = "overloaded", .value = long(dependence_.overloaded), .column = true, .width = 10}};
  }
  std::vector<std::string> notes() const override {
    if (dependence_.dependent > 0 || dependence_.dependent < 0) return {dependence_text()};
    return {};
  }
  std::vector<ReportField> basis_report() const override {
    std::string text = dependence_.overloaded == 0
                           ? "independent (no B-spline is overloaded)"
                           : dependence_.dependent == 0
                                 ? "independent (" + std::to_string(dependence_.overloaded) +
                                       " overloaded B-splines, ranked: full rank)"
                                 : dependence_text();
    return {{.key = "overloaded", .value = long(dependence_.overloaded), .text = text, .label = "independence"},
            {.key = "dependent", .value = long(dependence_.dependent)}};
  }
  void check_solvable() const override {
    if (dependence_.dependent == 0) return;
    if (!case_->allow_unverified_space)
      throw InputError(case_->path + (refined_ ? ": [space] refinement: " : ": [space] meshlines: ") + dependence_text() +
                       "; refusing to solve (--allow-dependent solves anyway)");
    std::fprintf(stderr, "knotwork: warning: %s: %s; solving anyway as asked: the matrix may be singular\n",
                 case_->path.c_str(), dependence_text().c_str());
  }
  std::unique_ptr<SplineSpace> refine(const std::vector<int>& marked, const std::vector<CellSplit>& /*split*/,
                                      int* extended, const ProgressFunction& /*progress*/) && override {
    DyadicLrMesh next = lr_;
    next.record_splits(keep_prolongations_);
    try {
      next.refine(marked, lr_section(*case_).strategy);
    } catch (const std::invalid_argument& e) {
      throw InputError(case_->path + ": [space]: " + e.what());
    }
    if (extended) *extended = next.extended() - lr_.extended();
    check_refined_memory(*case_, double(next.elements().size()), "LR");
    std::optional<Eigen::SparseMatrix<double>> prolongation;
    if (keep_prolongations_) prolongation = next.prolongation_from(lr_);
    next.record_splits(false);
    auto out = std::make_unique<LrSpace>(*case_, std::move(next));
    out->refined_ = true;
    out->keep_prolongations_ = keep_prolongations_;
    out->prolongation_ = std::move(prolongation);
    return out;
  }
  bool keep_prolongations() override { return keep_prolongations_ = true; }
  const Eigen::SparseMatrix<double>* prolongation_from_predecessor() const override {
    return prolongation_ ? &*prolongation_ : nullptr;
  }

  KnotLines knot_lines() const override { return knot_lines_of_cells(mesh_, *geometry_); }

 private:
  std::string dependence_text() const {
    if (dependence_.dependent < 0)
      return std::to_string(dependence_.overloaded) + " overloaded B-splines, too many to rank: linear independence "
                                                      "is not established";
    char b[200];
    const BezierCell& c = mesh_.cell(dependence_.element);
    std::snprintf(b, sizeof b, "the LR B-splines are linearly dependent: %d relation%s among %d overloaded B-splines, "
                               "one on the cell [%g, %g] x [%g, %g]",
                  dependence_.dependent, dependence_.dependent == 1 ? "" : "s", dependence_.overloaded, c.u0, c.u1,
                  c.v0, c.v1);
    return b;
  }

  std::shared_ptr<const CaseDescription> case_;  // a copy: the space does not need the caller's case to live on
  DyadicLrMesh lr_;
  BezierMesh mesh_;
  DyadicLrMesh::Dependence dependence_;
  std::unique_ptr<PatchGeometryMap> geometry_;
  bool refined_ = false;  // made by adaptive refinement (a dependence is the refinement's)
  bool keep_prolongations_ = false;
  std::optional<Eigen::SparseMatrix<double>> prolongation_;
};

std::unique_ptr<SplineSpace> build_lr(const CaseDescription& c, int level) {
  DyadicKnots u = patch_dyadic_knots(c.geometry, lr_section(c).space, 0, level),
              v = patch_dyadic_knots(c.geometry, lr_section(c).space, 1, level);
  check_dyadic_start_memory(c, u, v, "LR");
  DyadicLrMesh lr(std::move(u), std::move(v));
  const LrSection& l = lr_section(c);
  for (size_t i = 0; i < l.meshlines.size(); ++i) {
    const MeshlineInput& m = l.meshlines[i];
    try {
      const int d = m.vertical ? 0 : 1;
      lr.insert({{d, lr.grid(d, m.position), lr.grid(1 - d, m.from), lr.grid(1 - d, m.to)}});
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": [space] meshlines[" + std::to_string(i) + "]: " + e.what());
    }
  }
  return std::make_unique<LrSpace>(c, std::move(lr));
}

}  // namespace

SpaceFamily lr_family() {
  SpaceFamily f;
  f.name = "lr";
  f.read_case = read_lr_case;
  f.space_keys = lr_space_keys();
  f.build = [](const CaseDescription& c, int level, const ProgressFunction&) { return build_lr(c, level); };
  f.local_refinement = true;
  f.override_options = [](CaseDescription& c, int degree, int elements) {
    override_patch_space(family_section<LrSection>(c).space, degree, elements);
  };
  f.check_converge = [](const CaseDescription& c, int levels) { check_uniform_levels(lr_section(c).space, levels); };
  return f;
}

}  // namespace knotwork
