// knotwork basis --g1 MESH.obj: the G1 macro-patch spline space on a quad mesh — topology,
// gluing data and their compatibility, the dimension of S_k^{1,r}(M), its local basis
// (checked: count, rank, G1 residual), export, and ParaView output.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>

#include <CLI/CLI.hpp>

#include "cases/basis_tool.hpp"
#include "cases/json_output.hpp"
#include "cases/output_files.hpp"
#include "basis/g1/g1_basis.hpp"
#include "basis/g1/g1_space.hpp"
#include "basis/g1/quad_mesh.hpp"
#include "families/g1/gluing_file.hpp"
#include "basis/core/input_error.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

namespace {

// The request with the tool's own options.
struct BasisOptions : BasisRequest {
  std::string g1_mesh;
  int degree = 4;
  int split_smoothness = 1;
  std::string gluing = "symmetric";  // analysis_suitable | symmetric | symmetric_c1 | geometric | regular_fans | FILE.json
};

const char* kind_name(G1BasisFunction::Kind k) {
  switch (k) {
    case G1BasisFunction::Kind::vertex: return "vertex";
    case G1BasisFunction::Kind::edge: return "edge";
    case G1BasisFunction::Kind::face: return "face";
    case G1BasisFunction::Kind::vertex_pair: return "vertex_pair";
    case G1BasisFunction::Kind::coupled: return "coupled";
  }
  return "?";
}

// What a function is attached to, in the OBJ's 1-based numbering: a vertex or face number,
// an edge's two vertices, or null (coupled functions).
void set_attached_to(Json& object, const QuadMesh& mesh, const G1BasisFunction& f) {
  using K = G1BasisFunction::Kind;
  if (f.kind == K::vertex || f.kind == K::face) {
    object.set("attached_to", f.owner + 1);
  } else if (f.kind == K::coupled) {
    object.set_null("attached_to");
  } else {
    const auto& e = mesh.edge(f.owner);
    object.set("attached_to", Json::array().push(double(e.v[0] + 1)).push(double(e.v[1] + 1)));
  }
}

std::string label(const QuadMesh& mesh, const G1BasisFunction& f) {
  using K = G1BasisFunction::Kind;
  if (f.kind == K::vertex) return "vertex" + std::to_string(f.owner + 1);
  if (f.kind == K::face) return "face" + std::to_string(f.owner + 1);
  if (f.kind == K::coupled) return "coupled";
  const auto& e = mesh.edge(f.owner);
  return std::string(f.kind == K::edge ? "edge" : "pair") + std::to_string(e.v[0] + 1) + "-" + std::to_string(e.v[1] + 1);
}

// The functions --show selects.
std::vector<int> selected_functions(const QuadMesh& mesh, const G1Basis& basis, const std::string& show,
                                    std::string& description) {
  using K = G1BasisFunction::Kind;
  std::smatch m;
  std::vector<int> out;
  auto pick = [&](K kind, int owner) {
    for (size_t j = 0; j < basis.functions.size(); ++j)
      if (basis.functions[j].kind == kind && basis.functions[j].owner == owner) out.push_back(static_cast<int>(j));
  };
  auto bad = [&](const std::string& why) { return InputError("--show " + show + ": " + why); };
  if (show == "all") {
    if (basis.functions.size() > 400) throw bad(std::to_string(basis.functions.size()) + " functions are too many fields for one file (at most 400); choose vertex:N, edge:I-J or face:N");
    for (size_t j = 0; j < basis.functions.size(); ++j) out.push_back(static_cast<int>(j));
    description = "all functions";
  } else if (show == "extraordinary") {
    int chosen = 0;
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (!mesh.boundary_vertex(v) && mesh.valence(v) != 4) {
        chosen = v;
        break;
      }
    pick(K::vertex, chosen);
    description = "the vertex functions of vertex " + std::to_string(chosen + 1) + " (valence " +
                  std::to_string(mesh.valence(chosen)) + ")";
  } else if (std::regex_match(show, m, std::regex(R"(vertex:(\d{1,9}))"))) {
    const int v = std::stoi(m[1]) - 1;
    if (v < 0 || v >= mesh.num_vertices()) throw bad("the mesh has vertices 1.." + std::to_string(mesh.num_vertices()));
    pick(K::vertex, v);
    description = "the vertex functions of vertex " + std::to_string(v + 1);
  } else if (std::regex_match(show, m, std::regex(R"(edge:(\d{1,9})-(\d{1,9}))"))) {
    const int a = std::stoi(m[1]) - 1, b = std::stoi(m[2]) - 1;
    const int e = (a >= 0 && b >= 0 && a < mesh.num_vertices() && b < mesh.num_vertices()) ? mesh.find_edge(a, b) : -1;
    if (e < 0) throw bad("no edge between vertices " + std::string(m[1]) + " and " + std::string(m[2]));
    pick(K::edge, e);
    pick(K::vertex_pair, e);
    description = "the edge functions of edge " + std::string(m[1]) + "-" + std::string(m[2]);
  } else if (std::regex_match(show, m, std::regex(R"(face:(\d{1,9}))"))) {
    const int f = std::stoi(m[1]) - 1;
    if (f < 0 || f >= mesh.num_faces()) throw bad("the mesh has faces 1.." + std::to_string(mesh.num_faces()));
    pick(K::face, f);
    description = "the face functions of face " + std::to_string(f + 1);
  } else {
    throw bad("expected vertex:N, edge:I-J, face:N, all or extraordinary");
  }
  return out;
}

void export_basis(const std::string& file, const BasisOptions& o, const QuadMesh& mesh, const G1Basis& basis) {
  const int n = 2 * basis.k - basis.r + 1;
  Json fs = Json::array();
  for (const auto& f : basis.functions) {
    std::map<int, std::vector<double>> per_face;
    for (const auto& [c, v] : f.coefficients) {
      auto& coefficients = per_face[static_cast<int>(c / (n * n))];
      coefficients.resize(static_cast<size_t>(n) * n, 0.0);
      coefficients[c % (n * n)] = v;
    }
    Json faces = Json::array();
    for (const auto& [face, coefficients] : per_face) {
      Json a = Json::array();
      for (double v : coefficients) a.push(v);
      faces.push(Json::object().set("face", face + 1).set("coefficients", a));
    }
    Json entry = Json::object();
    entry.set("kind", kind_name(f.kind));
    set_attached_to(entry, mesh, f);
    fs.push(entry.set("faces", faces));
  }
  Json root = Json::object();
  root.set("mesh", o.g1_mesh).set("degree", basis.k).set("split_smoothness", basis.r).set("gluing", o.gluing)
      .set("coefficients_per_face", n * n)
      .set("layout", "faces numbered 1.. in the OBJ's order; coefficient (i, j) of the face's B-spline basis "
                     "N_i(s) N_j(t) (knots 0^(k+1), (1/2)^(k-r), 1^(k+1); s from the face's 1st to 2nd vertex, "
                     "t from its 1st to 4th) at index i * n + j (row-major in s), n = 2k - r + 1")
      .set("functions", fs);
  write_file_atomically(file, "--export", [&](const std::string& path) {
    std::ofstream out(path);
    out << root.dump() << "\n";
    if (!out) throw std::runtime_error("write failed");
  });
}

// The fitted G1 surface as Bezier cells with the selected functions as point fields.
void write_vtk(const std::string& file, const QuadMesh& mesh, const G1Basis& basis, const std::vector<int>& show,
               double& deviation) {
  const Eigen::MatrixX3d fit = g1_fit_bilinear(mesh, basis, &deviation);
  const BezierMesh bm = g1_bezier_mesh(mesh, basis);
  const std::vector<Eigen::MatrixXd> points = g1_cell_bernstein(bm, fit);
  BezierSurface s;
  s.points = points;
  s.degree.assign(bm.num_cells(), basis.k);
  Eigen::VectorXd face(bm.num_cells());
  for (int c = 0; c < bm.num_cells(); ++c) face(c) = bm.cell(c).patch + 1;
  s.cell_fields.emplace_back("face", face);
  std::map<std::string, int> used;
  for (int j : show) {
    std::vector<Eigen::VectorXd> per_cell(bm.num_cells());
    for (int c = 0; c < bm.num_cells(); ++c) {
      per_cell[c] = Eigen::VectorXd::Zero(bm.extraction(c).cols());
      const auto ids = bm.functions(c);
      for (size_t a = 0; a < ids.size(); ++a)
        if (ids[a] == j) per_cell[c] = bm.extraction(c).row(static_cast<Eigen::Index>(a)).transpose();
    }
    const std::string base = label(mesh, basis.functions[j]);
    s.point_fields.emplace_back(base + "_" + std::to_string(++used[base]), std::move(per_cell));
  }
  write_file_atomically(file, "--vtk", [&](const std::string& path) { write_bezier_surface_vtu(path, s); });
}

}  // namespace

int g1_basis_command(const BasisOptions& o) {
  if (!o.file.empty())
    throw InputError("basis --g1: give one input, the quad mesh; drop '" + o.file + "' (or drop --g1 to check that file)");
  if (o.degree < 2 || o.degree > 10) throw InputError("--degree: k must be in [2, 10] for G1 splines, got " + std::to_string(o.degree));
  if (o.split_smoothness < 0 || o.split_smoothness >= o.degree)
    throw InputError("--split-smoothness: r must be in [0, k-1] = [0, " + std::to_string(o.degree - 1) + "], got " +
                     std::to_string(o.split_smoothness));
  if (!o.vtk_file.empty() && std::filesystem::path(o.vtk_file).extension() != ".vtu")
    throw InputError(o.vtk_file + ": --vtk: the file must end in .vtu");
  if (o.vtk_file.empty() && o.show != "extraordinary") throw InputError("--show " + o.show + ": needs --vtk FILE.vtu");
  // Refuse unwritable targets before any work (and before VTK reports it in its own words).
  for (const auto& [file, option] : {std::pair{o.vtk_file, "--vtk"}, std::pair{o.export_file, "--export"}}) {
    if (file.empty()) continue;
    const std::filesystem::path dir = std::filesystem::path(file).parent_path();
    if (!dir.empty() && !std::filesystem::is_directory(dir))
      throw InputError(file + ": " + option + ": the folder " + dir.string() + " does not exist");
  }
  QuadMesh mesh;
  try {
    mesh = QuadMesh::read_obj(o.g1_mesh);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  const GluingData gluing = make_gluing(o.gluing, mesh, o.g1_mesh + ": --gluing");
  const std::vector<std::string> violations = gluing_violations(mesh, gluing);
  // Incompatible data give a space too small to be useful (Sec. 3): refused, naming the
  // first edge or vertex that fails.
  if (!violations.empty())
    throw InputError((is_named_gluing(o.gluing) ? o.g1_mesh : o.gluing) + ": " +
                     violations.front() +
                     (violations.size() > 1 ? " (and " + std::to_string(violations.size() - 1) + " more)" : ""));
  try {
    check_g1_construction_size(mesh.num_faces(), o.degree, o.split_smoothness);
  } catch (const std::length_error& e) {
    throw InputError(o.g1_mesh + ": " + e.what());
  }
  const auto t0 = std::chrono::steady_clock::now();
  G1Basis basis;
  try {
    basis = g1_basis(mesh, gluing, o.degree, o.split_smoothness);
  } catch (const std::runtime_error& e) {
    throw InputError(o.g1_mesh + ": --gluing " + o.gluing + ": " + e.what());
  }
  const G1SpaceDimension& d = basis.space;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto t1 = std::chrono::steady_clock::now();
  const double residual = g1_residual_max(mesh, gluing, basis);
  std::string rank_method;
  const long rank = g1_basis_rank(basis, &rank_method);
  const double check_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  std::vector<int> show;
  std::string show_description;
  if (!o.vtk_file.empty()) show = selected_functions(mesh, basis, o.show, show_description);
  if (!o.export_file.empty()) export_basis(o.export_file, o, mesh, basis);
  const std::optional<long> formula = theorem_7_1_dimension(mesh, gluing, o.degree, o.split_smoothness);
  double deviation = 0;
  if (!o.vtk_file.empty()) write_vtk(o.vtk_file, mesh, basis, show, deviation);
  std::map<int, int> interior_valences, boundary_valences;
  int boundary_edges = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    ++(mesh.boundary_vertex(v) ? boundary_valences : interior_valences)[mesh.valence(v)];
  for (int e = 0; e < mesh.num_edges(); ++e) boundary_edges += mesh.edge(e).boundary();
  auto histogram = [](const std::map<int, int>& h) {
    std::string s;
    for (const auto& [val, count] : h) s += (s.empty() ? "" : ", ") + std::to_string(count) + " of valence " + std::to_string(val);
    return s.empty() ? std::string("none") : s;
  };
  if (o.json) {
    Json j = Json::object();
    j.set("mesh", o.g1_mesh).set("degree", o.degree).set("split_smoothness", o.split_smoothness).set("gluing", o.gluing)
        .set("skewed_fans", static_cast<long>(gluing.skewed_fans.size()))
        .set("vertices", mesh.num_vertices()).set("edges", mesh.num_edges()).set("faces", mesh.num_faces())
        .set("boundary_edges", boundary_edges).set("euler_characteristic", mesh.euler_characteristic())
        .set("unknowns", d.unknowns).set("constraints", d.constraints).set("dimension", d.dimension)
        .set("rank_method", d.exact        ? "exact data, rank modulo two primes"
                            : d.cyclotomic ? "sums of cosines, rank modulo two primes with roots of unity"
                                           : "floating point, local SVDs")
        .set("functions", static_cast<double>(basis.functions.size()))
        .set("counts", Json::object()
                           .set("vertex", basis.counts[0]).set("edge", basis.counts[1]).set("face", basis.counts[2])
                           .set("vertex_pair", basis.counts[3]).set("coupled", basis.counts[4]))
        .set("g1_residual_max", residual).set("rank", rank).set("rank_method_basis", rank_method)
        .set_bool("basis_exact", basis.exact).set("seconds", seconds).set("check_seconds", check_seconds);
    if (!d.exact && !d.cyclotomic) j.set("svd_tolerance", d.tolerance);
    if (d.local) j.set("svd_smallest_kept", d.smallest_kept).set("svd_largest_dropped", d.largest_dropped);
    if (d.cyclotomic) j.set("root_of_unity_order", d.cyclotomic);
    // Theorem 7.1 on closed meshes (its count of boundary edges and vertices is not stated).
    if (formula)
      j.set("dimension_formula", *formula);
    else
      j.set_null("dimension_formula");
    if (!o.export_file.empty()) j.set("export", o.export_file);
    if (!o.vtk_file.empty()) j.set("vtk", o.vtk_file).set("vtk_functions", static_cast<double>(show.size())).set("fit_deviation", deviation);
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("knotwork basis --g1 %s\n", o.g1_mesh.c_str());
  std::printf("  mesh       %d vertices, %d edges (%d on the boundary), %d faces; Euler characteristic %d%s\n",
              mesh.num_vertices(), mesh.num_edges(), boundary_edges, mesh.num_faces(), mesh.euler_characteristic(),
              mesh.planar() ? ", planar" : "");
  std::printf("             interior vertices: %s\n             boundary vertices: %s\n",
              histogram(interior_valences).c_str(), histogram(boundary_valences).c_str());
  std::printf("  gluing     %s: Condition 3.1 holds at every interior vertex%s\n", o.gluing.c_str(),
              gluing.skewed_fans.empty()
                  ? ""
                  : ("; " + std::to_string(gluing.skewed_fans.size()) + " crossings given a skewed fan (" +
                     gluing.skewed_fans_list() +
                     "), where Condition 3.2 fails otherwise")
                        .c_str());
  std::printf("  space      S_%d^{1,%d}: degree %d per face, C^%d at the 4-split, %d coefficients per face\n", o.degree,
              o.split_smoothness, o.degree, o.split_smoothness,
              (2 * o.degree - o.split_smoothness + 1) * (2 * o.degree - o.split_smoothness + 1));
  char margin[160];
  std::snprintf(margin, sizeof margin,
                "floating-point data, local SVDs at 1e-10: singular values kept down to %.2g, dropped up to %.2g",
                d.smallest_kept, d.largest_dropped);
  const std::string method = d.exact ? "rational data, rank modulo two primes which agree"
                             : d.cyclotomic ? "sums of cosines, rank modulo two primes with a " + std::to_string(d.cyclotomic) +
                                                  "th root of unity, which agree"
                                            : std::string(margin);
  std::printf("  dimension  %ld = %ld unknowns - rank %ld (%ld G1 conditions; %s, %.3f s)\n", d.dimension, d.unknowns,
              d.rank, d.constraints, method.c_str(), seconds);
  if (formula)
    std::printf("  Thm 7.1    %ld%s\n", *formula,
                *formula == d.dimension ? " (agrees)"
                                        : " (differs: k is below the separability of the gluing data, see docs/G1.md)");
  else
    std::printf("  Thm 7.1    not applied: the mesh has a boundary\n");
  std::printf("  basis      %zu functions: %ld vertex, %ld edge, %ld face", basis.functions.size(), basis.counts[0],
              basis.counts[1], basis.counts[2]);
  if (basis.counts[3]) std::printf(", %ld vertex-pair", basis.counts[3]);
  if (basis.counts[4]) std::printf(", %ld coupled (not local)", basis.counts[4]);
  std::printf("\n             rank %ld (%s), largest relative G1 residual %.2e (%.3f s)\n", rank,
              rank_method.c_str(), residual, check_seconds);
  if (basis.counts[3] || basis.counts[4])
    std::printf("             the degree is below the separability of some edges: vertex functions alone do not\n"
                "             span the Taylor data there (see docs/G1.md)\n");
  if (!o.export_file.empty()) std::printf("  export     %s\n", o.export_file.c_str());
  if (!o.vtk_file.empty())
    std::printf("  vtk        %s: the G1 surface fitted to the bilinear faces (largest coefficient deviation %.3g),\n"
                "             with %s as point fields\n",
                o.vtk_file.c_str(), deviation, show_description.c_str());
  return 0;
}

namespace {

class G1BasisTool final : public BasisTool {
 public:
  explicit G1BasisTool(CLI::App& basis) {
    options_.push_back(basis.add_option("--g1", o_.g1_mesh,
                                        "Quad mesh (Wavefront OBJ): the G1 spline space S_k^{1,r} on it (4-split macro-patches)"));
    options_.push_back(basis.add_option("--degree", o_.degree, "--g1: degree k of the face splines (>= 2)")->capture_default_str());
    options_.push_back(basis.add_option("--split-smoothness", o_.split_smoothness, "--g1: smoothness r at the 4-split, 0 <= r < k")
                           ->capture_default_str());
    options_.push_back(basis.add_option("--gluing", o_.gluing,
                                        "--g1: symmetric (the paper's data, whose counts docs/G1.md checks) | analysis_suitable (the "
                                        "default of case files) | symmetric_c1 | geometric | regular_fans | FILE.json "
                                        "(per-edge a, b, c)")
                           ->capture_default_str());
  }
  bool requested() const override { return options_[0]->count() > 0; }
  std::string selector() const override { return "--g1 MESH.obj"; }
  std::string show_help() const override {
    return "the G1 surface fitted to the mesh with vertex:N (OBJ index), edge:I-J, face:N (1-based), all, or "
           "extraordinary (default: the first interior vertex of valence != 4)";
  }
  void refuse_unused_options() const override {
    for (size_t i = 1; i < options_.size(); ++i)
      if (options_[i]->count()) throw InputError(options_[i]->get_name() + ": only with --g1 MESH.obj");
  }
  int run(const BasisRequest& request) const override {
    BasisOptions o = o_;
    static_cast<BasisRequest&>(o) = request;
    if (o.show.empty()) o.show = "extraordinary";
    else if (o.vtk_file.empty()) throw InputError("--show " + o.show + ": needs --vtk FILE.vtu");
    return g1_basis_command(o);
  }

 private:
  BasisOptions o_;
  std::vector<CLI::Option*> options_;
};

}  // namespace

std::unique_ptr<BasisTool> g1_basis_tool(CLI::App& basis) { return std::make_unique<G1BasisTool>(basis); }

}  // namespace knotwork
