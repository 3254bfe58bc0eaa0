// `knotwork basis TMESH --pt`: the PT-spline basis of S(m, n, m-1, n-1) over a T-mesh, with
// the checks a user needs to trust it (count against the brute-force dimension, exact rank,
// smoothness residual, non-negativity, support sizes) and an export of every function.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>

#include <CLI/CLI.hpp>

#include "cases/basis_tool.hpp"
#include "cases/json_output.hpp"
#include "cases/output_files.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/pt/pt_reference.hpp"
#include "basis/pt/pt_spline.hpp"
#include "basis/exact/sparse_rank.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "basis/tmesh/tmesh_conformality.hpp"
#include "cases/case_file.hpp"
#include "quadrature/bernstein.hpp"
#include "basis/core/input_error.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

namespace {

// The request with the tool's own options.
struct BasisOptions : BasisRequest {
  std::string pt_extension = "auto";  // auto | minimal | horizontal | vertical | diagonalizable
  bool pt_non_negative = true;        // Prop. 1 (--no-prop1 keeps the EEE combinations)
  bool pt_reference = false;          // also the full-extension reference's support sizes
};

struct SupportStats {
  int max = 0;
  double mean = 0;
};

SupportStats support_stats(const std::vector<int>& cells_per_function) {
  SupportStats s;
  for (int c : cells_per_function) s.max = std::max(s.max, c), s.mean += c;
  if (!cells_per_function.empty()) s.mean /= static_cast<double>(cells_per_function.size());
  return s;
}

// Cells of T where each full-extension function is not zero (exact, at interior points).
std::vector<int> reference_support(const RectangularPartition& mesh, const TensorCombinationBasis& R) {
  std::vector<int> out;
  for (int f = 0; f < static_cast<int>(R.functions.size()); ++f) {
    int count = 0;
    for (const auto& c : mesh.cells()) {
      bool nonzero = false;
      for (int i = 1; i <= R.m + 1 && !nonzero; ++i)
        for (int j = 1; j <= R.n + 1 && !nonzero; ++j)
          nonzero = evaluate(R, f, c.x0 + (c.x1 - c.x0) * i / (R.m + 2), c.y0 + (c.y1 - c.y0) * j / (R.n + 2)) != 0;
      count += nonzero;
    }
    out.push_back(count);
  }
  return out;
}

// Which functions --vtk writes: "all", 0-based indices "3,17", or by default
// ("extraordinary", the --g1 default) the four with the largest supports.
std::vector<int> shown_functions(const std::string& show, const PtCellPolynomials& polys) {
  const int nf = static_cast<int>(polys.size());
  std::vector<int> out;
  if (show == "all") {
    for (int f = 0; f < nf; ++f) out.push_back(f);
  } else if (show == "largest" || show == "extraordinary") {
    for (int f = 0; f < nf; ++f) out.push_back(f);
    std::stable_sort(out.begin(), out.end(), [&](int a, int b) { return polys[a].size() > polys[b].size(); });
    out.resize(std::min(nf, 4));
  } else {
    size_t at = 0;
    while (at <= show.size()) {
      const size_t comma = std::min(show.find(',', at), show.size());
      const std::string item = show.substr(at, comma - at);
      size_t used = 0;
      int f = -1;
      try {
        f = std::stoi(item, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != item.size() || item.empty() || f < 0 || f >= nf)
        throw InputError("--show: '" + item + "' is not a function index in [0, " + std::to_string(nf - 1) +
                         "] (give all, or indices such as 0,5)");
      out.push_back(f);
      at = comma + 1;
    }
  }
  return out;
}

// The T-mesh as Bezier cells of the parameter plane with the shown functions as exact fields.
void write_vtk(const std::string& file, const RectangularPartition& mesh, const PtCellPolynomials& polys, int p,
               const std::vector<int>& show) {
  BezierSurface s;
  Eigen::VectorXd alive = Eigen::VectorXd::Zero(mesh.num_cells());
  for (const auto& f : polys)
    for (const auto& [k, c] : f) alive[k] += 1;
  for (const auto& c : mesh.cells()) {
    Eigen::MatrixXd points = Eigen::MatrixXd::Zero((p + 1) * (p + 1), 3);
    for (int b = 0; b <= p; ++b)
      for (int a = 0; a <= p; ++a) {
        points(a + (p + 1) * b, 0) = mpq_class(c.x0 + (c.x1 - c.x0) * a / p).get_d();
        points(a + (p + 1) * b, 1) = mpq_class(c.y0 + (c.y1 - c.y0) * b / p).get_d();
      }
    s.points.push_back(points);
    s.degree.push_back(p);
  }
  s.cell_fields.emplace_back("functions_alive", alive);
  for (int f : show) {
    std::vector<Eigen::VectorXd> per_cell(mesh.num_cells(), Eigen::VectorXd::Zero((p + 1) * (p + 1)));
    for (const auto& [k, c] : polys[f]) per_cell[k] = Eigen::Map<const Eigen::VectorXd>(c.data(), static_cast<Eigen::Index>(c.size()));
    s.point_fields.emplace_back("function_" + std::to_string(f), std::move(per_cell));
  }
  write_file_atomically(file, "--vtk", [&](const std::string& path) { write_bezier_surface_vtu(path, s); });
}

}  // namespace

int pt_basis_command(const BasisOptions& o) {
  if (o.file.empty()) throw InputError("basis --pt: give the T-mesh file (cells = [...], degree)");
  const PartitionDescription p = load_partition(o.file);
  require_highest_smoothness(p, o.file, "PT-splines span S(m, n, m-1, n-1)");
  if (!o.vtk_file.empty() && std::filesystem::path(o.vtk_file).extension() != ".vtu")
    throw InputError(o.vtk_file + ": --vtk: the file must end in .vtu");
  if (!o.vtk_file.empty() && p.m != p.n)
    throw InputError(o.file + ": degree: --vtk writes Bezier cells of one degree, and this T-mesh has degree [" +
                     std::to_string(p.m) + ", " + std::to_string(p.n) + "]");
  const std::optional<PtExtension> parsed = parse_pt_extension(o.pt_extension);
  if (!parsed) throw InputError("--extension: '" + o.pt_extension + "' is not one of auto, minimal, horizontal, vertical, diagonalizable");
  const PtExtension extension = *parsed;
  const RectangularPartition mesh(p.cells);  // load_partition validated the cells
  try {
    check_brute_force_size(mesh.num_cells(), p.m, p.n, RankMethod::kModular);
  } catch (const std::length_error& e) {
    throw InputError(o.file + ": cells: " + e.what());
  }
  PtSplineBasis B = pt_spline_basis(mesh, p.m, p.n, extension);
  const long local_bsplines = static_cast<long>(B.splines.size());  // before Prop. 1 appends the cross-cut ones
  // Is T^e diagonalizable (the paper's premise for its local B-splines; knotwork's ordering test)?
  const bool extension_diagonalizable =
      diagonalizable_by_ordering(partition_topology(RectangularPartition(B.extension_cells)), p.m, p.n);
  const long brute = spline_space_dimension(mesh, p.m, p.n, p.m - 1, p.n - 1).dimension;
  int cross_cut_functions = 0;
  if (o.pt_non_negative) cross_cut_functions = make_non_negative(B, mesh);

  const auto exact = pt_cell_polynomials_exact(B, mesh);
  const int per_cell = (p.m + 1) * (p.n + 1);
  std::vector<SparseRationalRow> rows;
  mpq_class lowest_coefficient = 0;
  bool first = true;
  for (const auto& f : exact) {
    SparseRationalRow r;
    for (const auto& [k, c] : f)
      for (int a = 0; a < per_cell; ++a)
        if (c[a] != 0) {
          r.terms.emplace_back(static_cast<long>(k) * per_cell + a, c[a]);
          if (first || c[a] < lowest_coefficient) lowest_coefficient = c[a], first = false;
        }
    rows.push_back(std::move(r));
  }
  const long rank = rank_reliable(rows, static_cast<long>(mesh.num_cells()) * per_cell);
  const auto polys = to_double(exact);
  const double residual = pt_smoothness_residual(polys, mesh, p.m, p.n);
  // Values on a 5 x 5 grid of every cell (the Bernstein coefficients bound them from below),
  // and the partition-of-unity error there.
  // The tensor Bernstein polynomials at the 25 points, tabulated once (points x functions).
  Eigen::VectorXd su(25), sv(25);
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 5; ++i) su[i + 5 * j] = i / 4.0, sv[i + 5 * j] = j / 4.0;
  Eigen::MatrixXd at_points, d_u, d_v;
  tensor_bernstein(p.m, p.n, su, sv, at_points, d_u, d_v);
  double min_value = 0, pu_error = 0;
  std::vector<Eigen::VectorXd> sums(mesh.num_cells(), Eigen::VectorXd::Zero(25));
  bool first_value = true;
  for (const auto& f : polys)
    for (const auto& [k, c] : f) {
      const Eigen::VectorXd v = at_points * Eigen::Map<const Eigen::VectorXd>(c.data(), static_cast<Eigen::Index>(c.size()));
      if (first_value || v.minCoeff() < min_value) min_value = v.minCoeff(), first_value = false;
      sums[k] += v;
    }
  for (const auto& cell : sums) pu_error = std::max(pu_error, (cell.array() - 1).abs().maxCoeff());
  std::vector<int> support;
  for (const auto& f : polys) support.push_back(static_cast<int>(f.size()));
  const SupportStats stats = support_stats(support);
  SupportStats reference;
  long reference_functions = -1;
  if (o.pt_reference) {
    const TensorCombinationBasis R = pt_full_extension_basis(mesh, p.m, p.n);
    reference_functions = static_cast<long>(R.functions.size());
    reference = support_stats(reference_support(mesh, R));
  }
  const PartitionTopology topo = partition_topology(mesh);

  std::vector<int> show;
  if (!o.vtk_file.empty()) {
    show = shown_functions(o.show, polys);
    write_vtk(o.vtk_file, mesh, polys, p.m, show);
  }
  if (!o.export_file.empty()) {
    Json cells = Json::array(), fs = Json::array();
    for (const auto& c : mesh.cells())
      cells.push(Json::array().push(c.x0.get_str()).push(c.y0.get_str()).push(c.x1.get_str()).push(c.y1.get_str()));
    for (const auto& f : polys) {
      Json on = Json::array(), coefficients = Json::array();
      for (const auto& [k, c] : f) {
        on.push(double(k));
        Json b = Json::array();
        for (double v : c) b.push(v);
        coefficients.push(b);
      }
      fs.push(Json::object().set("cells", on).set("bernstein", coefficients));
    }
    Json root = Json::object();
    root.set("tmesh", o.file)
        .set("degree", Json::array().push(double(p.m)).push(double(p.n)))
        .set("bernstein_order", "a + (m+1)*b on each cell [x0,x1]x[y0,y1], a along x")
        .set("cells", cells)
        .set("functions", fs);
    write_file_atomically(o.export_file, "--export", [&](const std::string& path) {
      std::ofstream out(path);
      out << root.dump() << "\n";
      if (!out) throw std::runtime_error("write failed");
    });
  }

  const char* direction = pt_extension_name(B.extension);
  const ConformalityCount cofactor = conformality_count(topo, p.m, p.n);
  if (o.json) {
    Json j = Json::object();
    j.set("file", o.file)
        .set("space", "PT-splines S(" + std::to_string(p.m) + ", " + std::to_string(p.n) + ", " + std::to_string(p.m - 1) +
                          ", " + std::to_string(p.n - 1) + ")")
        .set("cells", mesh.num_cells())
        .set("functions", static_cast<long>(B.functions.size()))
        .set("dimension_bruteforce", brute);
    if (cofactor.formula) j.set("dimension_formula", *cofactor.formula); else j.set_null("dimension_formula");
    j.set_bool("diagonalizable", cofactor.diagonalizable).set("dimension_cofactor", cofactor.dimension);
    j.set("rank", rank)
        .set("max_smoothness_residual", residual)
        .set("min_value", min_value)
        .set("min_bernstein_coefficient", lowest_coefficient.get_d())
        .set_bool("non_negative_transform", o.pt_non_negative)
        .set("cross_cut_functions", cross_cut_functions)
        .set("partition_of_unity_error", pu_error)
        .set("support_cells_max", stats.max)
        .set("support_cells_mean", stats.mean)
        .set("extension", direction)
        .set("minimal_refused", B.minimal_refused)
        .set("local_bsplines", local_bsplines)
        .set_bool("extension_diagonalizable", extension_diagonalizable)
        .set("extended_edges", B.extended_edges)
        .set("eee_equations", B.equations)
        .set("eee_rank", B.rank)
        .set("eee_blocks", B.blocks)
        .set("eee_largest_block", B.largest_block)
        .set("untouched_bsplines", B.untouched)
        .set("dropped_dependent", B.dropped_dependent)
        .set("independence_proof", std::string(B.extension == PtExtension::kHorizontal || B.extension == PtExtension::kVertical
                                       ? "full extension (a basis by construction)"
                                   : B.splines_independent ? "peeling the LR B-splines"
                                                            : "rank of the cell polynomials"))
        .set("cross_cuts", topo.count(PartitionTopology::KnotKind::kLine))
        .set("rays", topo.count(PartitionTopology::KnotKind::kRay))
        .set("t_l_edges", topo.count(PartitionTopology::KnotKind::kSegment))
        .set("vanished_l_edges", topo.vanished_segments(p.m, p.n));
    if (o.pt_reference)
      j.set("reference_functions", reference_functions)
          .set("reference_support_cells_max", reference.max)
          .set("reference_support_cells_mean", reference.mean);
    if (!o.vtk_file.empty()) {
      Json shown = Json::array();
      for (int f : show) shown.push(static_cast<double>(f));
      j.set("vtk", o.vtk_file).set("vtk_functions", shown);
    }
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("knotwork basis %s --pt\n", o.file.c_str());
  std::printf("  space      PT-splines S(%d, %d, %d, %d) on %d cells\n", p.m, p.n, p.m - 1, p.n - 1, mesh.num_cells());
  std::printf("  functions  %zu; brute-force dimension %ld; exact rank %ld (%s)\n", B.functions.size(), brute, rank,
              rank == static_cast<long>(B.functions.size()) ? "linearly independent" : "DEPENDENT");
  if (cofactor.formula)
    std::printf("  formula    %ld (diagonalizable mesh); smoothing-cofactor count %ld\n", *cofactor.formula,
                cofactor.dimension);
  else
    std::printf("  formula    none (not diagonalizable); smoothing-cofactor count %ld\n", cofactor.dimension);
  std::printf("  extension  %s%s: %ld local B-splines, %ld extended edges, %ld EEE equations of rank %ld in %d "
              "blocks (largest %d B-splines); %d B-splines untouched\n",
              direction, B.extension == PtExtension::kHorizontal || B.extension == PtExtension::kVertical ? " l-edges to cross-cuts" : " (LR meshlines)",
              local_bsplines, B.extended_edges, B.equations, B.rank, B.blocks, B.largest_block, B.untouched);
  std::printf("  T^e        %zu cells, %s\n", B.extension_cells.size(),
              extension_diagonalizable ? "diagonalizable (an ordering of its T l-edges keeps deg+1 vertices on each)"
                                       : "not shown diagonalizable (no ordering keeps deg+1 vertices on each T l-edge)");
  if (B.extension != PtExtension::kHorizontal && B.extension != PtExtension::kVertical)
    std::printf("  certified  count = smoothing-cofactor dimension; independent by %s\n",
                B.splines_independent ? "peeling the LR B-splines (no cell polynomials)" : "the rank of the cell polynomials");
  if (B.dropped_dependent > 0)
    std::printf("  dependent  %d dropped: the local B-splines of the extension span, but are dependent\n",
                B.dropped_dependent);
  if (!B.minimal_refused.empty()) std::printf("  note       minimal extension not used: %s\n", B.minimal_refused.c_str());
  std::printf("  smoothness largest relative jump %.3e\n", residual);
  std::printf("  values     min %.6g (smallest Bernstein coefficient %.6g)%s; partition-of-unity error %.3e\n", min_value,
              lowest_coefficient.get_d(), o.pt_non_negative ? " after Prop. 1" : "", pu_error);
  std::printf("  support    cells per function: max %d, mean %.2f\n", stats.max, stats.mean);
  if (o.pt_reference)
    std::printf("  reference  full extension: %ld functions, cells per function max %d, mean %.2f\n", reference_functions,
                reference.max, reference.mean);
  if (!o.export_file.empty()) std::printf("  output     %s\n", o.export_file.c_str());
  if (!o.vtk_file.empty()) std::printf("  output     %s (%zu functions as fields)\n", o.vtk_file.c_str(), show.size());
  return 0;
}

namespace {

class PtBasisTool final : public BasisTool {
 public:
  explicit PtBasisTool(CLI::App& basis) {
    options_.push_back(basis.add_flag("--pt", pt_, "PT-splines of the T-mesh file (edge extension + Extended Edge Elimination)"));
    options_.push_back(basis.add_option("--extension", o_.pt_extension,
                                        "--pt: minimal (l-edges lengthened as LR meshlines, certified), horizontal or vertical "
                                        "(those l-edges extended to cross-cuts), diagonalizable (LR meshlines lengthened until the "
                                        "extended mesh is diagonalizable, certified), or auto: minimal, else the full extension with "
                                        "fewer extended edges")
                           ->capture_default_str());
    options_.push_back(basis.add_flag("!--no-prop1", o_.pt_non_negative,
                                      "--pt: keep the EEE combinations instead of the non-negative basis of Prop. 1"));
    options_.push_back(basis.add_flag("--reference", o_.pt_reference,
                                      "--pt: also build the full-extension reference and report its support sizes (slow)"));
  }
  bool requested() const override { return options_[0]->count() > 0; }
  std::string selector() const override { return "--pt TMESH"; }
  std::string show_help() const override {
    return "the T-mesh cells with all, 0-based indices such as 0,5, or largest (default: the four functions with the "
           "largest supports)";
  }
  void refuse_unused_options() const override {
    for (size_t i = 1; i < options_.size(); ++i)
      if (options_[i]->count()) throw InputError(options_[i]->get_name() + ": only with --pt");
  }
  int run(const BasisRequest& request) const override {
    BasisOptions o = o_;
    static_cast<BasisRequest&>(o) = request;
    if (o.show.empty()) o.show = "largest";
    else if (o.vtk_file.empty()) throw InputError("--show " + o.show + ": needs --vtk FILE.vtu");
    return pt_basis_command(o);
  }

 private:
  BasisOptions o_;
  bool pt_ = false;
  std::vector<CLI::Option*> options_;
};

}  // namespace

std::unique_ptr<BasisTool> pt_basis_tool(CLI::App& basis) { return std::make_unique<PtBasisTool>(basis); }

}  // namespace knotwork
