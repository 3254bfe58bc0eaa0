// knotwork basis --g1 MESH.obj: the G1 macro-patch spline space on a quad mesh — topology,
// gluing data and their compatibility, and the dimension of S_k^{1,r}(M).
#include <chrono>
#include <cstdio>
#include <map>

#include "app/commands.hpp"
#include "app/json_writer.hpp"
#include "basis/g1_space.hpp"
#include "basis/quad_mesh.hpp"
#include "cases/gluing_file.hpp"
#include "solver/input_error.hpp"

namespace knotwork {

int g1_basis_command(const BasisOptions& o) {
  if (o.degree < 2 || o.degree > 10) throw InputError("--degree: k must be in [2, 10] for G1 splines, got " + std::to_string(o.degree));
  if (o.split_smoothness < 0 || o.split_smoothness >= o.degree)
    throw InputError("--split-smoothness: r must be in [0, k-1] = [0, " + std::to_string(o.degree - 1) + "], got " +
                     std::to_string(o.split_smoothness));
  if (!o.export_file.empty()) throw InputError("--export: not available with --g1 yet (the local basis is not built)");
  QuadMesh mesh;
  try {
    mesh = QuadMesh::read_obj(o.g1_mesh);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  GluingData gluing;
  if (o.gluing == "symmetric") {
    gluing = symmetric_gluing(mesh);
  } else if (o.gluing == "geometric") {
    try {
      gluing = geometric_gluing(mesh);
    } catch (const std::invalid_argument& e) {
      throw InputError(o.g1_mesh + ": --gluing geometric: " + e.what());
    }
  } else {
    gluing = load_gluing_file(o.gluing, mesh);
  }
  const std::vector<std::string> violations = gluing_violations(mesh, gluing);
  // Incompatible data give a space too small to be useful (Sec. 3): refused, naming the
  // first edge or vertex that fails.
  if (!violations.empty())
    throw InputError((o.gluing == "symmetric" || o.gluing == "geometric" ? o.g1_mesh : o.gluing) + ": " +
                     violations.front() +
                     (violations.size() > 1 ? " (and " + std::to_string(violations.size() - 1) + " more)" : ""));
  const auto t0 = std::chrono::steady_clock::now();
  const G1SpaceDimension d = g1_space_dimension(mesh, gluing, o.degree, o.split_smoothness);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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
        .set("vertices", mesh.num_vertices()).set("edges", mesh.num_edges()).set("faces", mesh.num_faces())
        .set("boundary_edges", boundary_edges).set("euler_characteristic", mesh.euler_characteristic())
        .set("unknowns", d.unknowns).set("constraints", d.constraints).set("dimension", d.dimension)
        .set("rank_method", d.exact ? "exact data, rank modulo two primes" : "floating point SVD")
        .set("seconds", seconds);
    if (!d.exact) j.set("svd_tolerance", d.tolerance);
    // The explicit local basis (vertex, edge and face functions) is not built yet.
    j.set_null("functions").set_null("dimension_formula").set_null("counts").set_null("g1_residual_max").set_null("rank");
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("knotwork basis --g1 %s\n", o.g1_mesh.c_str());
  std::printf("  mesh       %d vertices, %d edges (%d on the boundary), %d faces; Euler characteristic %d%s\n",
              mesh.num_vertices(), mesh.num_edges(), boundary_edges, mesh.num_faces(), mesh.euler_characteristic(),
              mesh.planar() ? ", planar" : "");
  std::printf("             interior vertices: %s\n             boundary vertices: %s\n",
              histogram(interior_valences).c_str(), histogram(boundary_valences).c_str());
  std::printf("  gluing     %s: Condition 3.1 holds at every interior vertex\n", o.gluing.c_str());
  std::printf("  space      S_%d^{1,%d}: degree %d per face, C^%d at the 4-split, %d coefficients per face\n", o.degree,
              o.split_smoothness, o.degree, o.split_smoothness,
              (2 * o.degree - o.split_smoothness + 1) * (2 * o.degree - o.split_smoothness + 1));
  std::printf("  dimension  %ld = %ld unknowns - rank %ld (%ld G1 conditions; %s, %.3f s)\n", d.dimension, d.unknowns,
              d.rank, d.constraints,
              d.exact ? "rational data, rank modulo two primes which agree" : "floating-point data, SVD rank at 1e-10",
              seconds);
  return 0;
}

}  // namespace knotwork
