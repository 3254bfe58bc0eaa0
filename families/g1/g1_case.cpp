// Reading a case of family "g1": [space] mesh/degree/split_smoothness/gluing/refine/
// smoothness, [geometry] shape, [problem] operator/exact/source/reaction/dirichlet/
// dirichlet_method (Nitsche by default on planar meshes)/nitsche_penalty.
#include <filesystem>

#include "families/g1/g1_case.hpp"


#include "families/g1/gluing_file.hpp"
#include "basis/g1/patches_as_quad_mesh.hpp"
#include "basis/g1/quad_mesh.hpp"
#include "basis/core/input_error.hpp"
#include "cases/geometry_file.hpp"
#include "cases/case_reader.hpp"

namespace knotwork {

const std::vector<std::string>& g1_space_keys() {
  static const std::vector<std::string> keys{"family", "mesh", "degree", "split_smoothness", "gluing", "refine", "smoothness",
                                             "quadrature_points", "error_quadrature_points"};
  return keys;
}

void read_g1_case(const CaseDocument& doc, CaseDescription& c) {
  const CaseReader& r = doc.reader;
  const DocumentNode& root = doc.root;
  G1Section& g = c.section.emplace<G1Section>();
  const DocumentNode& s = r.table(root, "space", true);
  r.check_keys(s, "space", g1_space_keys());
  const DocumentNode* m = s.get("mesh");
  const DocumentNode& geo = r.table(root, "geometry", false);
  const DocumentNode* file = geo.get("file");
  if (!m && !file)
    r.fail("[space] mesh", "missing: the quad mesh (.obj) the G1 space lives on (or a [geometry] file of bilinear patches)");
  if (m && file) r.fail("[geometry] file", "the quad mesh is given once: [space] mesh or [geometry] file, not both");
  QuadMesh mesh;
  if (m) {
    g.mesh_file = r.readable_file(*m, "[space] mesh");
    try {
      mesh = QuadMesh::read_obj(g.mesh_file);
    } catch (const std::invalid_argument& e) {
      r.fail("[space] mesh", e.what());
    }
  } else {
    // G+Smo XML or GeoPDEs text whose patches are bilinear: exactly a quad mesh.
    g.mesh_file = r.readable_file(*file, "[geometry] file");
    try {
      mesh = quad_mesh_of_bilinear_patches(read_geometry_file(g.mesh_file), g.mesh_file);
    } catch (const InputError& e) {
      throw InputError(c.path + ": [geometry] file: " + e.what());
    } catch (const std::invalid_argument& e) {
      r.fail("[geometry] file", e.what());
    }
  }
  if (file) g.coarse = std::make_shared<const QuadMesh>(mesh);  // an OBJ is read again from mesh_file
  g.faces = mesh.num_faces();
  if (const DocumentNode* d = s.get("degree")) g.degree = static_cast<int>(r.integer(*d, "[space] degree"));
  if (g.degree < 2 || g.degree > 12) r.fail("[space] degree", "must be in [2, 12] (one integer: the bidegree k of the patches)");
  if (const DocumentNode* d = s.get("split_smoothness")) {
    g.split_smoothness = static_cast<int>(r.integer(*d, "[space] split_smoothness"));
    g.split_smoothness_given = true;
  } else
    g.split_smoothness = default_split_smoothness(g.degree);
  if (g.split_smoothness < 1 || g.split_smoothness > g.degree - 1)
    r.fail("[space] split_smoothness", "must be in [1, degree-1] (C^r across the 4-split lines; r >= 1 for "
                                       "refinement to nest the spaces), got " + std::to_string(g.split_smoothness));
  if (const DocumentNode* d = s.get("gluing")) {
    g.gluing = r.string(*d, "[space] gluing");
    if (!is_named_gluing(g.gluing) && !std::filesystem::exists(r.resolve(g.gluing)))
      r.fail("[space] gluing", "'" + g.gluing + "' is neither a construction (analysis_suitable, symmetric, "
                               "symmetric_c1, geometric, regular_fans) nor a gluing file (relative paths start at the case file's folder)");
    if (!is_named_gluing(g.gluing)) g.gluing = r.readable_file(g.gluing, "[space] gluing");
  }
  if (const DocumentNode* d = s.get("refine")) g.refine = static_cast<int>(r.integer(*d, "[space] refine"));
  if (const DocumentNode* d = s.get("smoothness")) {
    const std::string v = r.string(*d, "[space] smoothness");
    if (v != "g1" && v != "c0") r.fail("[space] smoothness", "must be \"g1\" (default) or \"c0\" (the C0 multipatch baseline)");
    g.c0 = v == "c0";
  }
  if (g.refine < 0 || g.refine > 6) r.fail("[space] refine", "must be in [0, 6]");
  read_quadrature(r, s, c, 1);

  r.check_keys(geo, "geometry", {"shape", "center", "radius", "major_radius", "minor_radius", "file"});
  if (const DocumentNode* n = geo.get("shape")) g.shape = r.string(*n, "[geometry] shape");
  if (g.shape != "bilinear" && g.shape != "sphere" && g.shape != "torus")
    r.fail("[geometry] shape", "unknown shape '" + g.shape + "' (" + closest_name(g.shape, {"bilinear", "sphere", "torus"}) + ")");
  if (const DocumentNode* n = geo.get("center")) {
    const DocumentNode* a = n->as_array();
    if (!a || a->size() != 3) r.fail("[geometry] center", "must be [x, y, z]");
    for (int i = 0; i < 3; ++i) g.center(i) = r.number(*a->get(i), "[geometry] center");
  }
  auto positive = [&](const char* key, double& out) {
    if (const DocumentNode* n = geo.get(key)) {
      out = r.number(*n, std::string("[geometry] ") + key);
      if (!(out > 0)) r.fail(std::string("[geometry] ") + key, "must be > 0");
    }
  };
  positive("radius", g.radius);
  positive("major_radius", g.major_radius);
  positive("minor_radius", g.minor_radius);
  if (g.shape == "torus" && !(g.minor_radius < g.major_radius))
    r.fail("[geometry] minor_radius", "must be smaller than major_radius");
  if (g.shape != "sphere" && (geo.get("radius")))
    r.fail("[geometry] radius", "only with shape = \"sphere\"");

  const DocumentNode& t = r.table(root, "problem", true);
  r.check_keys(t, "problem",
               {"operator", "exact", "source", "coefficient", "reaction", "dirichlet", "dirichlet_method", "nitsche_penalty"});
  std::string op = "laplace";
  if (const DocumentNode* n = t.get("operator")) op = r.string(*n, "[problem] operator");
  if (op != "laplace" && op != "laplace_beltrami")
    r.fail("[problem] operator", "'" + op + "' (" + closest_name(op, {"laplace", "laplace_beltrami"}) + ")");
  g.surface = op == "laplace_beltrami";
  const std::string& f = r.path();
  if (!g.surface) {
    if (!mesh.planar()) {
      int v = 0;
      while (v < mesh.num_vertices() && mesh.vertex(v).z() == 0) ++v;
      r.fail("[space] mesh", g.mesh_file + ": vertex " + std::to_string(v + 1) + " has z = " +
                                 std::to_string(mesh.vertex(v).z()) +
                                 "; operator = \"laplace\" needs a planar mesh (z = 0), surfaces take "
                                 "operator = \"laplace_beltrami\"");
    }
    if (mesh.closed()) r.fail("[space] mesh", "a planar mesh without boundary");
    if (g.shape != "bilinear") r.fail("[geometry] shape", "planar cases use shape = \"bilinear\"");
    PoissonProblem& pb = c.problem;
    read_planar_exact_and_source(r, t, c);
    // Nitsche by default: a C1 space fixes the gradient at a boundary vertex from the traces
    // of its two boundary edges, so the strong projection's derivative error there spreads
    // into the solution (H1 error 1.4-1.8x larger on the coarse pentagon and valence-8/6
    // meshes; docs/G1_POISSON.md).
    pb.dirichlet_method = DirichletMethod::kNitsche;
    read_dirichlet_method(r, t, pb);
    pb.boundary.assign(1, BoundaryCondition{});  // one boundary: the whole of it
    if (const DocumentNode* d = t.get("dirichlet")) {
      const auto text = d->value_exact<std::string>();
      if (!text) r.fail("[problem] dirichlet", "must be \"exact\" or an expression (G1 domains have one boundary)");
      if (*text != "exact") {
        pb.boundary[0].from_exact = false;
        pb.boundary[0].value = Expression::parse(*text, f + ": [problem] dirichlet");
      }
    }
    if (pb.boundary[0].from_exact && !pb.exact)
      r.fail("[problem] dirichlet", "the boundary data come from the exact solution, but [problem] exact is not given");
    return;
  }
  for (const char* key : {"dirichlet_method", "nitsche_penalty"})
    if (t.get(key))
      r.fail(std::string("[problem] ") + key, "the surface " + g.mesh_file + " has no boundary to impose Dirichlet data on");
  if (t.get("dirichlet"))
    r.fail("[problem] dirichlet", mesh.closed() ? "the surface " + g.mesh_file + " is closed: it has no boundary to "
                                                  "put Dirichlet data on"
                                                : "Dirichlet data on surfaces are not supported (closed surfaces only)");
  if (!mesh.closed())
    r.fail("[space] mesh", g.mesh_file + " has a boundary; Laplace-Beltrami problems are solved on closed surfaces");
  PoissonProblem& pb = c.problem;
  // -div_G(A grad_G u) + c u: a scalar a(x, y, z) > 0 or a 3x3 matrix whose tangential part is
  // positive definite; c a number >= 0 (0: zero-mean solution) or a function c(x, y, z) >= 0.
  read_coefficient_and_reaction(r, t, 3, pb);
  if (const DocumentNode* e = t.get("exact"))
    pb.exact = differentiate_surface_solution(Expression::parse(r.string(*e, "[problem] exact"), f + ": [problem] exact"));
  // No source: derived from the exact solution on the discrete surface by the assembler.
  if (const DocumentNode* e = t.get("source"))
    pb.source = Expression::parse(r.string(*e, "[problem] source"), f + ": [problem] source");
  if (!pb.exact && pb.source.empty())
    r.fail("[problem] source", "missing: give `source`, or `exact` to derive it on the surface");
}

}  // namespace knotwork
