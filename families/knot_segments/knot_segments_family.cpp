// Family "knot_segments": Weller's semi-regular collections on one patch's parameter domain,
// from a tensor start with the case's knot segments inserted (extended where needed), or a
// collection given explicitly; refined locally by halving marked cells with knot segments.
#include <array>
#include <cstdio>
#include <optional>

#include "families/knot_segments/collection_checks.hpp"
#include "families/knot_segments/knot_segments_case.hpp"
#include "basis/knot_segments/semi_regular_collection.hpp"
#include "basis/tmesh/knot_polylines.hpp"
#include "cases/basis_tool.hpp"
#include "cases/resource_limits.hpp"
#include "cases/spline_space.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

std::unique_ptr<BasisTool> knot_segments_basis_tool(CLI::App& basis);  // knot_segments_basis_tool.cpp

namespace {

// The knots of the collection's partition as physical polylines, with their kind and multiplicity.
KnotLines knot_lines_of(const SemiRegularCollection& collection, const NurbsPatch& geometry) {
  KnotPolylines k = knot_polylines(collection.partition(), geometry, [&](bool vertical, double at, double from, double to) {
    return collection.knot_multiplicity(vertical, at, from, to);
  });
  return {std::move(k.lines), std::move(k.kind), std::move(k.multiplicity)};
}


std::string degree_text(const CaseDescription& c) {
  const auto& d = patch_space(c).degree;
  return std::to_string(d[0]) + "x" + std::to_string(d[1]);
}

class KnotSegmentSpace final : public SplineSpace, public SpaceReport {
 public:
  const SpaceReport& presentation() const override { return *this; }
  // The case's own space at uniform level `level` (elements per span doubled `level` times).
  KnotSegmentSpace(const CaseDescription& c, int level) : case_(std::make_shared<const CaseDescription>(c)) {
    if (!knot_segments_section(c).collection_file.empty()) build_explicit(c);
    else build_from_segments(c, level);
  }
  // The case's geometry on a given collection (a step of adaptive refinement).
  KnotSegmentSpace(const CaseDescription& c, SemiRegularCollection collection)
      : case_(std::make_shared<const CaseDescription>(c)), collection_(std::move(collection)) {
    finish();
  }

  const BezierMesh& mesh() const override { return mesh_; }
  const GeometryMap& geometry() const override { return *geometry_; }
  std::string description() const override {
    const CaseDescription& c = *case_;
    const KnotSegmentsSection& k = knot_segments_section(c);
    if (!k.collection_file.empty())
      return "knot segments (Weller), degree " + degree_text(c) + ", collection of " + std::to_string(k.collection.size()) +
             " B-splines from " + k.collection_file;
    return "knot segments (Weller), degree " + degree_text(c) + ", " + std::to_string(k.segments.size()) +
           " segments, " + KnotSegmentsSection::kExtensionNames[static_cast<int>(k.extension)] + " extension";
  }
  std::vector<int> degree() const override { return as_list(patch_space(*case_).degree); }
  std::vector<ReportField> report() const override {
    if (elements_ == 0) return {};
    return {{.key = "elements", .value = long(elements_), .column = true, .width = 9}};
  }
  std::vector<std::string> notes() const override {
    std::vector<std::string> out;
    for (const auto& r : insertions_)
      if (r.extended) {
        char b[240];
        std::snprintf(b, sizeof b, "segment %s = %g, [%g, %g] was extended to [%g, %g] to keep the basis semi-regular",
                      r.requested.vertical ? "x" : "y", r.requested.position, r.requested.from, r.requested.to,
                      r.inserted.from, r.inserted.to);
        out.push_back(b);
      }
    return out;
  }
  void check_solvable() const override {
    if (violations_.empty()) return;
    const CaseDescription& c = *case_;
    const std::string more = violations_.size() > 1 ? " (and " + std::to_string(violations_.size() - 1) +
                                                          " more; knotwork basis lists them)"
                                                    : "";
    const std::string& file = knot_segments_section(c).collection_file;
    if (!c.allow_unverified_space)
      throw InputError(c.path + ": [space] collection: " + file + " is not semi-regular: " +
                       violations_.front() + more + "; refusing to solve (--allow-non-semi-regular solves anyway)");
    std::fprintf(stderr, "knotwork: warning: %s: the collection is not semi-regular (%s%s); solving anyway as asked: "
                         "the functions may be linearly dependent and the matrix singular\n",
                 file.c_str(), violations_.front().c_str(), more.c_str());
  }
  std::unique_ptr<SplineSpace> refine(const std::vector<int>& marked, const std::vector<CellSplit>& split,
                                      int* extended, const ProgressFunction& /*progress*/) && override {
    if (!violations_.empty())
      throw InputError(case_->path + ": [space]: adaptive refinement needs a semi-regular start, and the collection is "
                       "not: " + violations_.front());
    SemiRegularCollection next = *collection_;
    next.record_splits(keep_prolongations_);
    std::vector<SemiRegularCollection::Split> how;
    for (CellSplit s : split) how.push_back(s == CellSplit::kAcrossU ? SemiRegularCollection::kSplitX : SemiRegularCollection::kSplitY);
    int count = 0;
    for (const auto& r : next.refine_cells(marked, how)) count += r.extended;
    if (extended) *extended = count;
    std::optional<Eigen::SparseMatrix<double>> prolongation;
    if (keep_prolongations_) prolongation = next.prolongation_from(*collection_);
    next.record_splits(false);
    auto out = std::make_unique<KnotSegmentSpace>(*case_, std::move(next));
    out->keep_prolongations_ = keep_prolongations_;
    out->prolongation_ = std::move(prolongation);
    return out;
  }
  // The refinement records its knot insertions (B = a B_left + b B_right per split B-spline),
  // and the prolongation replays them (SemiRegularCollection::prolongation_from). Not for a
  // collection that is not semi-regular: refine refuses it.
  bool keep_prolongations() override { return keep_prolongations_ = violations_.empty(); }
  const Eigen::SparseMatrix<double>* prolongation_from_predecessor() const override {
    return prolongation_ ? &*prolongation_ : nullptr;
  }
  // By name only: cells halved in one direction make the stiffness anisotropic, where
  // Gauss-Seidel smooths poorly (44-90 CG iterations at the last step, against THB's 12-18), and
  // recording the splits costs refinement time: the loops were no faster than with CHOLMOD
  // (docs/ADAPTIVITY.md, "Multigrid over the steps").
  bool multigrid_over_steps_is_automatic() const override { return false; }
  std::vector<ReportField> basis_report() const override {
    CollectionChecks checks;
    try {
      checks = check_collection(*collection_, simple_knots_);
    } catch (const std::length_error& e) {
      throw InputError(case_->path + ": [space]: " + e.what());
    }
    std::vector<std::string> extensions;
    for (const auto& i : insertions_)
      if (i.extended) extensions.push_back(describe_insertion(i.requested) + " extended to " + describe_insertion(i.inserted));
    std::string violation_lines;
    for (const auto& v : checks.violations) violation_lines += "\n    " + v;
    auto count = [](long n) { return n >= 0 ? ReportValue(n) : ReportValue(); };
    std::string dimension;
    if (checks.dimension_bruteforce >= 0) {
      dimension = std::to_string(checks.dimension_bruteforce) + " by brute force over the partition";
      if (checks.dimension_formula >= 0) dimension += ", " + std::to_string(checks.dimension_formula) + " by Weller's Prop. 4.2";
    }
    return {
        {.key = "semi_regular",
         .value = checks.violations.empty(),
         .text = (checks.violations.empty() ? "yes (Def. 3.1 and 3.3 hold on every cell)" : "NO") + violation_lines,
         .label = "semi-regular"},
        {.key = "violations", .value = checks.violations},
        {.key = "dimension_formula", .value = count(checks.dimension_formula)},
        {.key = "dimension_bruteforce", .value = count(checks.dimension_bruteforce), .text = dimension, .label = "dimension"},
        {.key = "extended_segments",
         .value = long(extensions.size()),
         .text = insertions_.empty() ? "" : std::to_string(insertions_.size()) + ", " + std::to_string(extensions.size()) +
                                                " of them extended to keep the basis semi-regular (see the notes)",
         .label = "segments"},
        {.key = "extensions", .value = extensions},
    };
  }
  void export_functions(const std::string& file, const std::string& source) const override {
    export_collection(file, source, *collection_);
  }
  KnotLines knot_lines() const override { return knot_lines_of(*collection_, case_->geometry); }
  // Drawing the knots takes the partition and its topology in exact arithmetic: 1.9 s at
  // 50 000 dofs, more than the step's solve. Adapt draws them on its writer thread, from a copy.
  std::function<KnotLines()> knot_lines_later() const override {
    auto collection = std::make_shared<const SemiRegularCollection>(*collection_);
    std::shared_ptr<const CaseDescription> c = case_;
    return [collection, c] { return knot_lines_of(*collection, c->geometry); };
  }

 private:
  // A collection given explicitly ([space] collection): its domain must be the geometry's
  // parameter domain; semi-regularity is checked here and enforced before solving.
  void build_explicit(const CaseDescription& c) {
    const KnotSegmentsSection& k = knot_segments_section(c);
    const std::string where = c.path + ": [space] collection: " + k.collection_file;
    try {
      collection_ = SemiRegularCollection::from_splines(k.space.degree[0], k.space.degree[1], k.collection);
      collection_->set_extension(k.extension);
    } catch (const std::invalid_argument& e) {
      throw InputError(where + ": " + e.what());
    }
    const auto box = collection_->domain();
    const double u0 = c.geometry.basis_u.domain_begin(), u1 = c.geometry.basis_u.domain_end();
    const double v0 = c.geometry.basis_v.domain_begin(), v1 = c.geometry.basis_v.domain_end();
    if (box[0] != u0 || box[2] != u1 || box[1] != v0 || box[3] != v1) {
      char msg[240];
      std::snprintf(msg, sizeof msg, "the supports cover [%g,%g]x[%g,%g], not the geometry's parameter domain [%g,%g]x[%g,%g]",
                    box[0], box[2], box[1], box[3], u0, u1, v0, v1);
      throw InputError(where + ": " + msg);
    }
    for (const auto& v : collection_->violations()) violations_.push_back(v.reason);
    simple_knots_ = interior_knots_simple(k.collection);
    try {
      finish();
    } catch (const GeometryError& e) {
      throw InputError(where + ": " + e.what());
    } catch (const InputError&) {
      throw;
    } catch (const std::runtime_error& e) {
      throw InputError(where + ": the supports do not induce a partition: " + e.what());
    }
  }

  // A tensor-product start on the geometry's knot spans (cut into `elements` parts; geometry
  // knots of low continuity become knot lines of the needed multiplicity, e.g. the L-shape's
  // C0 fold), then the listed segments.
  void build_from_segments(const CaseDescription& c, int level) {
    const KnotSegmentsSection& k = knot_segments_section(c);
    const int dx = k.space.degree[0], dy = k.space.degree[1];
    std::array<std::vector<double>, 2> breaks;
    std::array<std::vector<int>, 2> mults;  // per interior breakpoint
    elements_ = k.space.elements_per_span[0] << level;
    for (int dir = 0; dir < 2; ++dir) {
      PatchBreaks b = patch_breaks(c.geometry, k.space, dir, level);
      for (int m : b.interior_multiplicity) simple_knots_ = simple_knots_ && m == 1;
      breaks[dir] = std::move(b.breaks);
      mults[dir] = std::move(b.interior_multiplicity);
    }
    check_knot_segments_memory(c, breaks, dx, dy);
    try {
      collection_ = SemiRegularCollection::tensor_product(dx, dy, breaks[0], breaks[1], mults[0], mults[1]);
      collection_->set_extension(k.extension);
    } catch (const std::invalid_argument& e) {
      throw InputError(c.path + ": [space]: " + e.what());
    }
    for (size_t i = 0; i < k.segments.size(); ++i) {
      try {
        insertions_.push_back(collection_->insert(k.segments[i]));
        simple_knots_ = simple_knots_ && k.segments[i].multiplicity == 1;
      } catch (const std::invalid_argument& e) {
        throw InputError(c.path + ": [space] segments[" + std::to_string(i) + "]: " + e.what());
      }
    }
    finish();
  }

  // Before the collection is built: the Galerkin pipeline's estimate plus the collection's own
  // B-splines, knot lines and induced cells (measured: 0.97 GB for 262 144 biquadratic cells,
  // of which the pipeline's estimate is 0.61 GB; 2 KB per cell keeps a margin).
  static void check_knot_segments_memory(const CaseDescription& c, const std::array<std::vector<double>, 2>& breaks,
                                         int dx, int dy) {
    const double nu = double(breaks[0].size()) - 1, nv = double(breaks[1].size()) - 1;
    const double cells = nu * nv, functions = (nu + dx) * (nv + dy);
    char what[120];
    std::snprintf(what, sizeof what, "%.3g knot-segment cells of degree %dx%d", cells, dx, dy);
    check_memory(c.path + ": [space] elements", galerkin_bytes(cells, functions, dx, dy) + 2048 * cells, what);
  }

  void finish() {
    mesh_ = collection_->bezier_mesh();
    mesh_.set_interfaces(interfaces_from_parameter_boxes(mesh_));
    geometry_ = std::make_unique<PatchGeometryMap>(mesh_, case_->geometry);
  }

  std::shared_ptr<const CaseDescription> case_;  // a copy: the space does not need the caller's case to live on
  std::optional<SemiRegularCollection> collection_;
  bool keep_prolongations_ = false;
  std::optional<Eigen::SparseMatrix<double>> prolongation_;
  BezierMesh mesh_;
  std::unique_ptr<PatchGeometryMap> geometry_;
  std::vector<InsertionReport> insertions_;
  std::vector<std::string> violations_;
  bool simple_knots_ = true;  // every interior knot of multiplicity 1: the counts of S(d-1) apply
  int elements_ = 0;          // per span, for a tensor start (0: an explicit or refined collection)
};

}  // namespace

SpaceFamily knot_segments_family() {
  SpaceFamily f;
  f.name = "knot_segments";
  f.read_case = read_knot_segments_case;
  f.space_keys = knot_segments_space_keys();
  f.add_basis_tool = knot_segments_basis_tool;
  f.build = [](const CaseDescription& c, int level, const ProgressFunction&) -> std::unique_ptr<SplineSpace> {
    return std::make_unique<KnotSegmentSpace>(c, level);
  };
  f.local_refinement = true;
  f.override_options = [](CaseDescription& c, int degree, int elements) {
    KnotSegmentsSection& k = knot_segments_section(c);
    override_patch_space(k.space, degree, elements, k.collection_file);
  };
  f.check_converge = [](const CaseDescription& c, int levels) {
    if (!knot_segments_section(c).collection_file.empty())
      throw InputError(c.path + ": [space] collection: a convergence study refines uniformly, and a collection given "
                       "explicitly has fixed functions (use knotwork run, or knotwork adapt to refine it)");
    check_uniform_levels(patch_space(c), levels);
  };
  return f;
}

}  // namespace knotwork
