#include <Eigen/QR>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "app/commands.hpp"
#include "app/pipeline.hpp"
#include "app/report.hpp"
#include "basis/knot_segments/collection_checks.hpp"
#include "cases/json_output.hpp"
#include "cases/output_files.hpp"
#include "basis/knot_segments/collection_on_partition.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "solver/input_error.hpp"

namespace knotwork {

namespace {

// Largest |sum_i R_i - 1| over the cells' Bernstein coefficients: the functions are a
// partition of unity exactly when every column of the (rational-adjusted) extraction sums to 1.
double partition_of_unity_error(const BezierMesh& mesh) {
  double worst = 0;
  Eigen::VectorXd wb;
  Eigen::MatrixXd C;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    rational_cell_extraction(mesh, c, wb, C);
    worst = std::max(worst, (C.colwise().sum().array() - 1.0).abs().maxCoeff());
  }
  return worst;
}

// Numerical rank of all functions' Bezier coefficients over all cells (-1 when too large
// for a dense factorization).
long bezier_rank(const BezierMesh& mesh) {
  const long n = mesh.num_functions();
  long columns = 0;
  for (int c = 0; c < mesh.num_cells(); ++c) columns += mesh.extraction(c).cols();
  if (n * columns > 40'000'000L) return -1;
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(columns, n);
  long offset = 0;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const Eigen::MatrixXd& C = mesh.extraction(c);
    const auto ids = mesh.functions(c);
    for (size_t a = 0; a < ids.size(); ++a) G.block(offset, ids[a], C.cols(), 1) = C.row(a).transpose();
    offset += C.cols();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(G);
  qr.setThreshold(1e-10);
  return qr.rank();
}

// What `knotwork basis` reports, whatever the input was.
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

int print_report(const BasisReport& r, const BasisOptions& o) {
  const BezierMesh& mesh = *r.mesh;
  const double pu = partition_of_unity_error(mesh);
  const long rank = bezier_rank(mesh);
  long formula = -1, brute = -1;
  if (r.collection) {
    const CollectionChecks checks = check_collection(*r.collection, r.simple_knots);
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

// A case file: its space through the family interface; the family adds its own checks.
int basis_of_case(const BasisOptions& o) {
  const CaseDescription c = load_case(o.case_file);
  const std::unique_ptr<SplineSpace> space = build_space(c);
  const BezierMesh& mesh = space->mesh();
  const std::vector<ReportField> fields = space->basis_report();
  if (!o.export_file.empty()) space->export_functions(o.export_file, c.path);
  const double pu = partition_of_unity_error(mesh);
  const long rank = bezier_rank(mesh);
  if (o.json) {
    Json j = Json::object();
    j.set("file", c.path).set("family", c.family).set("space", space->description())
        .set("functions", mesh.num_functions()).set("cells", mesh.num_cells());
    add_fields(j, fields);
    j.set("partition_of_unity_error", pu);
    if (rank >= 0) j.set("rank", rank); else j.set_null("rank");
    j.set("notes", Json::strings(space->notes()));
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("knotwork basis %s\n  space      %s\n  functions  %d on %d cells\n", c.path.c_str(),
              space->description().c_str(), mesh.num_functions(), mesh.num_cells());
  for (const auto& n : space->notes()) std::printf("  note       %s\n", n.c_str());
  print_field_lines(fields, 10);
  std::printf("  partition of unity  max error %.3e\n", pu);
  if (rank >= 0) std::printf("  rank       %ld (%s)\n", rank, rank == mesh.num_functions() ? "linearly independent" : "DEPENDENT");
  else std::printf("  rank       not computed (too large for the dense rank check)\n");
  if (!o.export_file.empty()) std::printf("  output     %s\n", o.export_file.c_str());
  return 0;
}

int basis_of_partition(const BasisOptions& o) {
  const PartitionDescription p = load_partition(o.case_file);
  require_highest_smoothness(p, o.case_file, "knot-segment collections are C^(d-1)");
  const RectangularPartition partition(p.cells);
  CollectionOnPartition built;
  try {
    built = collection_on_partition(partition, p.m, p.n);
  } catch (const std::exception& e) {
    throw InputError(o.case_file + ": cells: " + e.what());
  }
  const BezierMesh mesh = built.collection.bezier_mesh();
  BasisReport r;
  r.file = o.case_file;
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
  if (!o.export_file.empty()) export_collection(o.export_file, o.case_file, built.collection);
  return print_report(r, o);
}

int basis_of_collection(const BasisOptions& o) {
  const CollectionDescription cd = load_collection(o.case_file);
  std::unique_ptr<SemiRegularCollection> collection;
  try {
    collection = std::make_unique<SemiRegularCollection>(SemiRegularCollection::from_splines(cd.dx, cd.dy, cd.splines));
  } catch (const std::invalid_argument& e) {
    throw InputError(o.case_file + ": functions: " + e.what());
  }
  BasisReport r;
  r.file = o.case_file;
  r.space = "collection of " + std::to_string(cd.splines.size()) + " B-splines given by local knot vectors, degree " +
            std::to_string(cd.dx) + "x" + std::to_string(cd.dy) + " (numbered in lexicographic order of their knot vectors)";
  r.collection = collection.get();
  for (const auto& v : collection->violations()) r.violations.push_back(v.reason);
  r.simple_knots = interior_knots_simple(cd.splines);
  BezierMesh mesh;
  try {
    mesh = collection->bezier_mesh();
  } catch (const std::runtime_error& e) {
    throw InputError(o.case_file + ": functions: the supports do not induce a partition: " + e.what());
  }
  r.mesh = &mesh;
  if (!o.export_file.empty()) export_collection(o.export_file, o.case_file, *collection);
  return print_report(r, o);
}

}  // namespace

int basis_command(const BasisOptions& o) {
  switch (input_kind(o.case_file)) {
    case InputKind::kPartition: return basis_of_partition(o);
    case InputKind::kCollection: return basis_of_collection(o);
    case InputKind::kCase: break;
  }
  return basis_of_case(o);
}

}  // namespace knotwork
