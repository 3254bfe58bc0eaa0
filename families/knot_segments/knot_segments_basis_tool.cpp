// `knotwork basis` on a T-mesh file (the semi-regular collection built on it, when one
// exists; it says why not) or a collection file (B-splines by their local knot vectors):
// Weller's checks, partition of unity, rank, and the dimension against brute force.
#include <cstdio>

#include "basis/core/bezier_mesh_checks.hpp"
#include "families/knot_segments/collection_checks.hpp"
#include "basis/knot_segments/collection_on_partition.hpp"
#include "families/knot_segments/knot_segments_case.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "cases/basis_tool.hpp"
#include "cases/json_output.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// What `knotwork basis` reports on a knot-segment collection.
struct BasisReport {
  std::string file, space;
  const BezierMesh* mesh = nullptr;
  const SemiRegularCollection* collection = nullptr;  // null for tensor-product spaces
  std::vector<std::string> violations;
  bool simple_knots = true;
  std::vector<std::string> extensions;  // segments the construction had to extend
  int segments = 0;                     // inserted by the construction
  bool from_partition = false;          // a T-mesh file
  bool partition_reached = false;
  int input_cells = 0;
  std::string order;
  std::vector<std::string> input_hypotheses_failed;  // Lemma 3.4 / Prop. 4.1 on the given T-mesh
};

int print_report(const BasisReport& r, const BasisRequest& o) {
  const BezierMesh& mesh = *r.mesh;
  const double pu = partition_of_unity_error(mesh);
  const long rank = bezier_rank(mesh);
  long formula = -1, brute = -1;
  if (r.collection) {
    CollectionChecks checks;
    try {
      checks = check_collection(*r.collection, r.simple_knots);
    } catch (const std::length_error& e) {
      throw InputError(r.file + ": " + e.what());
    }
    formula = checks.dimension_formula;
    brute = checks.dimension_bruteforce;
  }
  if (o.json) {
    Json j = Json::object();
    j.set("file", r.file).set("space", r.space).set("functions", mesh.num_functions()).set("cells", mesh.num_cells());
    if (r.collection) j.set_bool("semi_regular", r.violations.empty());
    else j.set_null("semi_regular");  // a tensor-product space: the question does not arise
    j.set("violations", Json::strings(r.violations)).set("partition_of_unity_error", pu);
    if (rank >= 0) j.set("rank", rank); else j.set_null("rank");
    if (formula >= 0) j.set("dimension_formula", formula); else j.set_null("dimension_formula");
    if (brute >= 0) j.set("dimension_bruteforce", brute); else j.set_null("dimension_bruteforce");
    j.set("extended_segments", static_cast<int>(r.extensions.size())).set("extensions", Json::strings(r.extensions));
    if (r.from_partition)
      j.set("input_cells", r.input_cells).set_bool("partition_reached", r.partition_reached)
          .set("insertion_order", r.order).set("input_hypotheses_failed", Json::strings(r.input_hypotheses_failed));
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("knotwork basis %s\n  space      %s\n  functions  %d on %d cells\n", r.file.c_str(), r.space.c_str(),
              mesh.num_functions(), mesh.num_cells());
  if (r.from_partition) {
    if (r.partition_reached)
      std::printf("  partition  the collection lives on the given %d cells (order: %s)\n", r.input_cells, r.order.c_str());
    else
      std::printf("  partition  NOT reached: no insertion order tried gives a semi-regular collection on the given %d\n"
                  "             cells; the closest one (%s) extends the segments below\n", r.input_cells, r.order.c_str());
    if (!r.input_hypotheses_failed.empty())
      std::printf("             the given cells fail Weller's necessary conditions, so none exists there:\n");
    for (const auto& h : r.input_hypotheses_failed) std::printf("               %s\n", h.c_str());
  }
  if (r.collection) {
    std::printf("  semi-regular  %s\n", r.violations.empty() ? "yes (Def. 3.1 and 3.3 hold on every cell)" : "NO");
    for (const auto& s : r.violations) std::printf("    %s\n", s.c_str());
    if (r.segments > 0 || !r.extensions.empty())
      std::printf("  segments   %d, %zu of them extended to keep the basis semi-regular\n", r.segments, r.extensions.size());
    for (const auto& s : r.extensions) std::printf("    %s\n", s.c_str());
  }
  std::printf("  partition of unity  max error %.3e\n", pu);
  if (rank >= 0) std::printf("  rank       %ld (%s)\n", rank, rank == mesh.num_functions() ? "linearly independent" : "DEPENDENT");
  if (brute >= 0) std::printf("  dimension  %ld by brute force over the partition", brute);
  if (formula >= 0) std::printf(", %ld by Weller's Prop. 4.2", formula);
  if (brute >= 0) std::printf("\n");
  if (!o.export_file.empty()) std::printf("  output     %s\n", o.export_file.c_str());
  return 0;
}

int basis_of_partition(const BasisRequest& o) {
  const PartitionDescription p = load_partition(o.file);
  require_highest_smoothness(p, o.file, "knot-segment collections are C^(d-1)");
  const RectangularPartition partition(p.cells);
  CollectionOnPartition built;
  try {
    built = collection_on_partition(partition, p.m, p.n);
  } catch (const std::exception& e) {
    throw InputError(o.file + ": cells: " + e.what());
  }
  const BezierMesh mesh = built.collection.bezier_mesh();
  BasisReport r;
  r.file = o.file;
  r.space = "knot segments on the T-mesh, degree " + std::to_string(p.m) + "x" + std::to_string(p.n) + ", C^(d-1)";
  r.mesh = &mesh;
  r.collection = &built.collection;
  for (const auto& v : built.collection.violations()) r.violations.push_back(v.reason);
  r.segments = static_cast<int>(built.insertions.size());
  for (const auto& i : built.insertions)
    if (i.extended) r.extensions.push_back(describe_insertion(i.requested) + " extended to " + describe_insertion(i.inserted));
  r.from_partition = true;
  r.partition_reached = built.reached;
  r.input_cells = partition.num_cells();
  r.order = built.order;
  if (p.m == p.n) r.input_hypotheses_failed = weller_hypotheses_violations(partition_topology(partition), p.m);
  if (!o.export_file.empty()) export_collection(o.export_file, o.file, built.collection);
  return print_report(r, o);
}

int basis_of_collection(const BasisRequest& o) {
  const CollectionDescription cd = load_collection(o.file);
  std::unique_ptr<SemiRegularCollection> collection;
  try {
    collection = std::make_unique<SemiRegularCollection>(SemiRegularCollection::from_splines(cd.dx, cd.dy, cd.splines));
  } catch (const std::invalid_argument& e) {
    throw InputError(o.file + ": functions: " + e.what());
  }
  BasisReport r;
  r.file = o.file;
  r.space = "collection of " + std::to_string(cd.splines.size()) + " B-splines given by local knot vectors, degree " +
            std::to_string(cd.dx) + "x" + std::to_string(cd.dy) + " (numbered in lexicographic order of their knot vectors)";
  r.collection = collection.get();
  for (const auto& v : collection->violations()) r.violations.push_back(v.reason);
  r.simple_knots = interior_knots_simple(cd.splines);
  BezierMesh mesh;
  try {
    mesh = collection->bezier_mesh();
  } catch (const std::runtime_error& e) {
    throw InputError(o.file + ": functions: the supports do not induce a partition: " + e.what());
  }
  r.mesh = &mesh;
  if (!o.export_file.empty()) export_collection(o.export_file, o.file, *collection);
  return print_report(r, o);
}

class KnotSegmentsBasisTool final : public BasisTool {
 public:
  bool requested() const override { return false; }
  bool claims(const std::string& file) const override {
    return !file.empty() && document_has_key(file, {"functions", "cells", "grid"});
  }
  std::string selector() const override { return "a T-mesh or collection file"; }
  void refuse_unused_options() const override {}
  int run(const BasisRequest& o) const override {
    if (!o.vtk_file.empty()) throw InputError("--vtk: not written for knot-segment collections (--pt --vtk writes a T-mesh's PT-splines)");
    if (!o.show.empty()) throw InputError("--show: only with --vtk");
    if (document_has_key(o.file, {"functions"})) return basis_of_collection(o);
    return basis_of_partition(o);
  }
};

}  // namespace

std::unique_ptr<BasisTool> knot_segments_basis_tool(CLI::App&) { return std::make_unique<KnotSegmentsBasisTool>(); }

}  // namespace knotwork
