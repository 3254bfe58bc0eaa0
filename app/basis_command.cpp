#include <Eigen/QR>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "app/commands.hpp"
#include "app/discretize.hpp"
#include "app/json_writer.hpp"
#include "basis/partition_topology.hpp"
#include "basis/spline_dimension.hpp"
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

}  // namespace

int basis_command(const BasisOptions& o) {
  const CaseDescription c = load_case(o.case_file);
  const Discretization d = discretize(c);
  const BezierMesh& mesh = d.mesh();
  const bool segments = d.segments != nullptr;
  std::vector<std::string> violations;
  if (segments)
    for (const auto& v : d.segments->violations()) violations.push_back(v.reason);
  const double pu = partition_of_unity_error(mesh);
  const long rank = bezier_rank(mesh);
  long formula = -1, brute = -1;
  const int dx = c.space.degree[0], dy = c.space.degree[1];
  if (segments && d.simple_knots) {
    const RectangularPartition part = d.segments->partition();
    brute = spline_space_dimension(part, dx, dy, dx - 1, dy - 1).dimension;
    if (dx == dy) formula = weller_dimension_formula(partition_topology(part), dx);
  }
  int extended = 0;
  for (const auto& r : d.insertions) extended += r.extended;

  if (!o.export_file.empty()) {
    if (!segments) throw InputError("--export: writes local knot vectors of family = \"knot_segments\" spaces");
    Json fs = Json::array();
    for (const auto& b : d.segments->splines()) {
      Json x = Json::array(), y = Json::array();
      for (double v : b.x) x.push(v);
      for (double v : b.y) y.push(v);
      fs.push(Json::object().set("x", x).set("y", y));
    }
    Json root = Json::object();
    root.set("case", c.path).set("degree", Json::array().push(double(dx)).push(double(dy))).set("functions", fs);
    const std::string tmp = o.export_file + ".partial";
    {
      std::ofstream out(tmp);
      out << root.dump() << "\n";
      if (!out) {
        std::filesystem::remove(tmp);
        throw InputError(o.export_file + ": --export: cannot write the file");
      }
    }
    std::filesystem::rename(tmp, o.export_file);
  }

  if (o.json) {
    Json v = Json::array();
    for (const auto& s : violations) v.push(s);
    Json j = Json::object();
    j.set("case", c.path).set("space", describe_space(c)).set("functions", mesh.num_functions())
        .set("cells", mesh.num_cells());
    if (segments) j.set_bool("semi_regular", violations.empty());
    else j.set_null("semi_regular");  // a tensor-product space: the question does not arise
    j.set("violations", v).set("partition_of_unity_error", pu);
    if (rank >= 0) j.set("rank", rank); else j.set_null("rank");
    if (formula >= 0) j.set("dimension_formula", formula); else j.set_null("dimension_formula");
    if (brute >= 0) j.set("dimension_bruteforce", brute); else j.set_null("dimension_bruteforce");
    j.set("extended_segments", extended);
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("knotwork basis %s\n  space      %s\n  functions  %d on %d cells\n", c.path.c_str(),
              describe_space(c).c_str(), mesh.num_functions(), mesh.num_cells());
  if (segments) {
    std::printf("  semi-regular  %s\n", violations.empty() ? "yes (Def. 3.1 and 3.3 hold on every cell)" : "NO");
    for (const auto& s : violations) std::printf("    %s\n", s.c_str());
    std::printf("  segments   %zu, %d of them extended to keep the basis semi-regular\n", d.insertions.size(), extended);
  }
  std::printf("  partition of unity  max error %.3e\n", pu);
  if (rank >= 0) std::printf("  rank       %ld (%s)\n", rank, rank == mesh.num_functions() ? "linearly independent" : "DEPENDENT");
  if (brute >= 0) std::printf("  dimension  %ld by brute force over the partition", brute);
  if (formula >= 0) std::printf(", %ld by Weller's Prop. 4.2", formula);
  if (brute >= 0) std::printf("\n");
  if (!o.export_file.empty()) std::printf("  output     %s\n", o.export_file.c_str());
  return 0;
}

}  // namespace knotwork
