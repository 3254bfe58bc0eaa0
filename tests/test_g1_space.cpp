// Quad meshes of arbitrary topology and the G1 spline space S_k^{1,r} on them
// (Blidia, Mourrain, Villamizar): topology checks, gluing data, dimensions.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <tuple>

#include "basis/g1/g1_refine.hpp"
#include "basis/g1/g1_space.hpp"
#include "basis/g1/quad_mesh.hpp"
#include "tests/g1_test_meshes.hpp"

using namespace knotwork;
using namespace knotwork::test;

TEST_CASE("Quad mesh topology: rings, valences, boundary, Euler characteristic", "[g1][mesh]") {
  const QuadMesh m = three_quads();
  REQUIRE(m.num_faces() == 3);
  REQUIRE(m.num_edges() == 9);
  REQUIRE(!m.boundary_vertex(0));
  REQUIRE(m.valence(0) == 3);
  for (int i = 1; i <= 3; ++i) {
    REQUIRE(m.boundary_vertex(i));
    REQUIRE(m.ring(i).faces.size() == 2);
    REQUIRE(m.valence(i) == 3);
  }
  REQUIRE(m.euler_characteristic() == 1);
  // Around gamma, consecutive faces share the edge that is the first one's previous edge.
  const auto& ring = m.ring(0);
  for (size_t i = 0; i < ring.faces.size(); ++i) {
    const int e = ring.edges[(i + 1) % ring.faces.size()];
    const auto& E = m.edge(e);
    REQUIRE(((E.face[0] == ring.faces[i]) || (E.face[1] == ring.faces[i])));
  }
  const QuadMesh c = cube();
  REQUIRE(c.closed());
  REQUIRE(c.euler_characteristic() == 2);
  for (int v = 0; v < 8; ++v) REQUIRE(c.valence(v) == 3);
  const QuadMesh t = torus(5, 4);
  REQUIRE(t.closed());
  REQUIRE(t.euler_characteristic() == 0);
  for (int v = 0; v < t.num_vertices(); ++v) REQUIRE(t.valence(v) == 4);
  const QuadMesh g = grid(3);
  REQUIRE(g.valence(0) == 2);
  REQUIRE(g.valence(5) == 4);
  REQUIRE(g.valence(1) == 3);
}

TEST_CASE("Quad meshes that are not valid oriented quad meshes are refused", "[g1][mesh][bad-input]") {
  auto refused = [](std::vector<Eigen::Vector3d> v, std::vector<std::array<int, 4>> f, const std::string& why) {
    try {
      QuadMesh::from_faces(v, f, "m");
      FAIL("accepted, expected: " << why);
    } catch (const std::invalid_argument& e) {
      INFO(e.what());
      REQUIRE(std::string(e.what()).find(why) != std::string::npos);
    }
  };
  const std::vector<Eigen::Vector3d> sq{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}, {2, 1, 0}};
  refused(sq, {{0, 1, 2, 3}}, "vertex 5 is in no face");
  refused({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, 0, 0}}, {{0, 1, 2, 3}}, "same point");
  refused(sq, {{0, 3, 2, 1}, {1, 4, 5, 2}}, "clockwise");
  refused(sq, {{0, 1, 2, 1}, {1, 4, 5, 2}}, "twice");
  refused({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}}, {{0, 1, 2, 3}}, "zero area");
  // Two faces traversing their common edge the same way (a surface, so orientation is
  // not decided by the plane).
  const std::vector<Eigen::Vector3d> bent{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, 0, 1}, {0, 0, 1}};
  refused(bent, {{0, 1, 2, 3}, {0, 1, 4, 5}}, "inconsistent");
  // An edge in three faces.
  const std::vector<Eigen::Vector3d> fan{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, -1, 0}, {0, -1, 0},
                                         {1, 0, 1}, {0, 0, 1}};
  refused(fan, {{0, 1, 2, 3}, {1, 0, 5, 4}, {0, 1, 6, 7}}, "edge 1-2 is traversed the same way");
  // Two fans meeting in one vertex (a bow tie).
  const std::vector<Eigen::Vector3d> bow{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {-1, 0, 0}, {-1, -1, 0}, {0, -1, 0}};
  refused(bow, {{0, 1, 2, 3}, {0, 4, 5, 6}}, "non-manifold");
}

TEST_CASE("Reading OBJ files: quads, and one-line errors with the line number", "[g1][mesh][bad-input]") {
  const auto dir = std::filesystem::temp_directory_path() / "knotwork-test-obj";
  std::filesystem::create_directories(dir);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  };
  const QuadMesh m = QuadMesh::read_obj(write("sq.obj", "# a square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n"));
  REQUIRE(m.num_faces() == 1);
  REQUIRE(m.planar());
  auto refused = [&](const std::string& text, const std::string& why) {
    const std::string f = write("bad.obj", text);
    try {
      QuadMesh::read_obj(f);
      FAIL("accepted");
    } catch (const std::invalid_argument& e) {
      INFO(e.what());
      REQUIRE(std::string(e.what()).find(why) != std::string::npos);
    }
  };
  refused("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n", "bad.obj:4: face with 3 vertices");
  refused("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 5\n", "bad.obj:5: face index 5");
  refused("v 0 0 x\n", "bad.obj:1: vertex coordinate 'x'");
  refused("v 0 0 0\nl 1 2\n", "bad.obj:2: 'l' is not supported");
  refused("v 0 0 0\n", "no faces");
  std::filesystem::remove_all(dir);
}

TEST_CASE("Symmetric gluing satisfies Condition 3.1, perturbed data fail at the named vertex", "[g1][gluing]") {
  for (const QuadMesh& m : {three_quads(), grid(3), cube(), torus(5, 4)}) {
    const GluingData g = symmetric_gluing(m);
    REQUIRE(gluing_violations(m, g).empty());
  }
  const QuadMesh m = three_quads();
  GluingData g = symmetric_gluing(m);
  const int e = m.ring(0).edges[0];
  g.edges[e]->a = PiecewisePolynomial::constant(mpq_class(1, 3));
  const auto v = gluing_violations(m, g);
  REQUIRE(v.size() == 1);
  REQUIRE(v[0].find("vertex 1 (valence 3)") != std::string::npos);
  g.edges[e].reset();
  REQUIRE(gluing_violations(m, g).front().find("without gluing data") != std::string::npos);
}

TEST_CASE("G1 space on a regular grid is the tensor-product C1 spline space", "[g1][dimension]") {
  for (int n : {1, 2, 3})
    for (int k = 2; k <= 5; ++k)
      for (int r = 0; r < k; ++r) {
        const QuadMesh m = grid(n);
        const G1SpaceDimension d = g1_space_dimension(m, symmetric_gluing(m), k, r);
        const long expected = univariate_dimension(n, k, r) * univariate_dimension(n, k, r);
        INFO("n = " << n << ", k = " << k << ", r = " << r);
        REQUIRE(d.exact);
        REQUIRE(d.dimension == expected);
      }
}

TEST_CASE("The paper's Section 8 example: dim S_4^{1,1} = 141 around a valence-3 vertex", "[g1][dimension]") {
  const QuadMesh m = three_quads();
  const GluingData g = symmetric_gluing(m);
  // The symmetric data here are the paper's: a = -1 + 4u^2 on [0, 1/2], 0 on [1/2, 1],
  // b = -1, c = 1 with u = 0 at gamma.
  for (int e : m.ring(0).edges) {
    const auto& a = g.edges[e]->a;
    const double sign_u = m.edge(e).v[0] == 0 ? 1 : -1;  // orientation of the stored edge
    const auto at = [&](double u) { return sign_u > 0 ? a(u) : a(1 - u); };
    REQUIRE(at(0) == Approx(-1));
    REQUIRE(at(0.25) == Approx(-1 + 4 * 0.0625));
    REQUIRE(at(0.75) == Approx(0).margin(1e-15));
  }
  const G1SpaceDimension d = g1_space_dimension(m, g, 4, 1);
  REQUIRE(d.exact);
  REQUIRE(d.unknowns == 3 * 64);
  REQUIRE(d.dimension == 141);
}

TEST_CASE("Linear gluing data with bicubic patches: the paper's dimension 72 is r = 1", "[g1][dimension]") {
  // a = u - 1, b = -1, c = 1 with u = 0 at gamma (Section 8, second example).
  const QuadMesh m = three_quads();
  GluingData g = symmetric_gluing(m);
  for (int e : m.ring(0).edges) {
    const bool from_gamma = m.edge(e).v[0] == 0;
    // In the stored edge's own parameter: u - 1 from gamma, or -u when gamma is at u = 1
    // (then a' = a/b with b = -1 at the far end, seen from the other side).
    const std::vector<mpq_class> a = from_gamma ? std::vector<mpq_class>{-1, 1} : std::vector<mpq_class>{0, 1};
    g.edges[e]->a = PiecewisePolynomial::from_exact({a, a});
  }
  REQUIRE(gluing_violations(m, g).empty());
  std::vector<long> dims;
  for (int r = 0; r < 3; ++r) dims.push_back(g1_space_dimension(m, g, 3, r).dimension);
  WARN("three quads, a = u - 1, k = 3: dim for r = 0, 1, 2: " << dims[0] << ", " << dims[1] << ", " << dims[2]);
  REQUIRE(dims[1] == 72);
}

TEST_CASE("Exact and floating-point ranks agree on closed surfaces and extraordinary vertices", "[g1][dimension]") {
  for (const QuadMesh& m : {cube(), torus(4, 3), three_quads()})
    for (int k = 3; k <= 4; ++k)
      for (int r = 0; r <= 1; ++r) {
        const GluingData g = symmetric_gluing(m);
        const G1SpaceDimension exact = g1_space_dimension(m, g, k, r);
        const G1SpaceDimension floating = g1_space_dimension(m, g, k, r, true);
        INFO(m.num_faces() << " faces, k = " << k << ", r = " << r);
        REQUIRE(exact.exact);
        REQUIRE(!floating.exact);
        REQUIRE(exact.dimension == floating.dimension);
      }
}

TEST_CASE("Geometric gluing from the mesh's edge directions satisfies Condition 3.1", "[g1][gluing]") {
  // A planar mesh with a valence-5 vertex: five quads around the origin.
  std::vector<Eigen::Vector3d> v{{0, 0, 0}};
  for (int i = 0; i < 5; ++i) v.emplace_back(std::cos(2 * M_PI * i / 5 + 0.1 * i), std::sin(2 * M_PI * i / 5 + 0.1 * i), 0);
  for (int i = 0; i < 5; ++i) v.push_back(0.9 * (v[1 + i] + v[1 + (i + 1) % 5]));
  std::vector<std::array<int, 4>> f;
  for (int i = 0; i < 5; ++i) f.push_back({0, 1 + i, 6 + i, 1 + (i + 1) % 5});
  const QuadMesh five = QuadMesh::from_faces(v, f, "five");
  for (const QuadMesh& m : {five, three_quads(), cube(), torus(5, 4), grid(2)}) {
    const GluingData g = geometric_gluing(m);
    const auto bad = gluing_violations(m, g);
    INFO((bad.empty() ? "" : bad.front()));
    REQUIRE(bad.empty());
  }
  // On a regular grid the geometric data are the C1 data: a = 0, b = -1 (c = 1).
  const QuadMesh gr = grid(2);
  const GluingData g = geometric_gluing(gr);
  for (int e = 0; e < gr.num_edges(); ++e)
    if (g.edges[e]) {
      REQUIRE(g.edges[e]->a(0.3) == Approx(0).margin(1e-14));
      REQUIRE(g.edges[e]->b(0.7) == Approx(-1));
    }
  // The valence-5 space with geometric data (floating point): reported, no reference value.
  const long geo = g1_space_dimension(five, geometric_gluing(five), 4, 1).dimension;
  WARN("five quads around a valence-5 vertex, k = 4, r = 1, geometric gluing: dim " << geo);
  REQUIRE(geo > 0);
}

TEST_CASE("Fans of F quads around a non-crossing vertex: dim = (3 + F) + F (4 + 5 + 36)", "[g1][dimension]") {
  // The Section 8 decomposition for k = 4, r = 1 and symmetric data around a vertex of
  // valence F != 4: the vertex part has dimension 3 + F (Prop. 5.1, no crossing edge), and
  // each face adds 4 functions at its boundary vertex delta_i, 5 on the edge tau_i and 36
  // others. F = 3 is the paper's 141; F = 5 needs the floating-point rank (2cos(2pi/5)).
  for (int F : {3, 5, 6, 7}) {
    std::vector<Eigen::Vector3d> v{{0, 0, 0}};
    for (int i = 0; i < F; ++i) v.emplace_back(std::cos(2 * M_PI * i / F), std::sin(2 * M_PI * i / F), 0);
    for (int i = 0; i < F; ++i) v.push_back(0.9 * (v[1 + i] + v[1 + (i + 1) % F]));
    std::vector<std::array<int, 4>> f;
    for (int i = 0; i < F; ++i) f.push_back({0, 1 + i, 1 + F + i, 1 + (i + 1) % F});
    const QuadMesh m = QuadMesh::from_faces(v, f, "fan");
    const G1SpaceDimension d = g1_space_dimension(m, symmetric_gluing(m), 4, 1);
    INFO("F = " << F << (d.exact ? " (exact)" : " (floating point)"));
    REQUIRE(d.dimension == (3 + F) + F * (4 + 5 + 36));
  }
}

TEST_CASE("Reversing an edge's orientation keeps the G1 space", "[g1][gluing]") {
  const QuadMesh m = cube();
  const GluingData g = symmetric_gluing(m);
  for (int e = 0; e < m.num_edges(); ++e) {
    const EdgeGluing back = reversed(reversed(*g.edges[e]));
    for (double u : {0.1, 0.4, 0.6, 0.9}) {
      REQUIRE(back.a(u) == Approx(g.edges[e]->a(u)));
      REQUIRE(back.b(u) == Approx(g.edges[e]->b(u)));
    }
    // Seen from the other end, bold a' = a/b and b' = 1/b at the same point of the edge.
    const EdgeGluing r = reversed(*g.edges[e]);
    for (double u : {0.2, 0.7}) {
      const auto& o = *g.edges[e];
      REQUIRE(r.a(1 - u) / r.c(1 - u) == Approx(o.a(u) / o.b(u)));
      REQUIRE(r.b(1 - u) / r.c(1 - u) == Approx(o.c(u) / o.b(u)));
    }
  }
}

TEST_CASE("G1 space on an all-valence-4 torus is the periodic tensor-product C1 space", "[g1][dimension]") {
  // Symmetric data on a torus are the C1 data (a = 0, b = -1, c = 1) on every edge, so the
  // space is the tensor product of periodic univariate splines on 2n intervals: degree k,
  // C1 at the n mesh knots and C^r at the n midpoints, 2n(k+1) - 2n - n(r+1) functions.
  auto periodic = [](int n, int k, int r) { return 2L * n * (k + 1) - 2L * n - long(n) * (r + 1); };
  for (const auto& [n, m] : {std::pair{4, 3}, std::pair{3, 5}})
    for (int k = 2; k <= 4; ++k)
      for (int r = 0; r < k; ++r) {
        const QuadMesh t = torus(n, m);
        const G1SpaceDimension d = g1_space_dimension(t, symmetric_gluing(t), k, r);
        INFO(n << " x " << m << " torus, k = " << k << ", r = " << r);
        REQUIRE(d.dimension == periodic(n, k, r) * periodic(m, k, r));
      }
}

namespace {
// The coefficients of a face's bilinear map in the face's B-spline basis (knots
// g1_face_knots(k, r) in s and t): a bilinear function is reproduced by its values at the
// Greville abscissae, so coefficient (i, j) is the map at (xi_i, xi_j).
Eigen::MatrixX2d bilinear_coefficients(const QuadMesh& m, int k, int r) {
  const std::vector<double> knots = g1_face_knots(k, r);
  const int n = static_cast<int>(knots.size()) - k - 1;
  std::vector<double> xi(n);
  for (int i = 0; i < n; ++i) {
    xi[i] = 0;
    for (int j = 1; j <= k; ++j) xi[i] += knots[i + j] / k;
  }
  Eigen::MatrixX2d c(static_cast<Eigen::Index>(m.num_faces()) * n * n, 2);
  for (int f = 0; f < m.num_faces(); ++f) {
    const auto& q = m.face(f);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const double s = xi[i], t = xi[j];
        const Eigen::Vector3d p = (1 - s) * (1 - t) * m.vertex(q[0]) + s * (1 - t) * m.vertex(q[1]) +
                                  s * t * m.vertex(q[2]) + (1 - s) * t * m.vertex(q[3]);
        c.row(g1_unknown(f, i, j, k, r)) = p.head<2>().transpose();
      }
  }
  return c;
}
}  // namespace

// The analysis-suitable data are derived from the faces; this checks them against the G1
// conditions the space is made of (g1_condition_rows), not against their derivation: the
// bilinear faces, written in each face's B-spline basis independently, must satisfy every row,
// i.e. the geometry lies in the space. Condition 3.1 must then hold at every vertex (the
// data come from a geometry), which pins the order of its product around a vertex. The
// degrees are those of analysis-suitable data: b and c linear, a quadratic, one polynomial.
TEST_CASE("Analysis-suitable gluing: the bilinear faces satisfy the G1 conditions", "[g1][gluing]") {
  const std::string meshes = std::string(KNOTWORK_SOURCE_DIR) + "/cases/meshes/";
  std::vector<QuadMesh> all{three_quads(), fan(5, 0.1), fan(7, 0.05), fan(8, 0.02), grid(3)};
  for (const char* name : {"pentagon.obj", "mixed_valences.obj", "valences_6_8.obj", "lshape_split.obj"})
    all.push_back(QuadMesh::read_obj(meshes + name));
  for (const QuadMesh& m : all) {
    const GluingData g = analysis_suitable_gluing(m);
    REQUIRE(g.exact());
    const auto bad = gluing_violations(m, g);
    INFO(m.num_faces() << " faces: " << (bad.empty() ? "" : bad.front()));
    REQUIRE(bad.empty());
    for (const auto& e : g.edges)
      if (e) {
        REQUIRE(e->a.degree() <= 2);
        REQUIRE(e->b.degree() <= 1);
        REQUIRE(e->c.degree() <= 1);
        REQUIRE((*e->a.exact)[0] == (*e->a.exact)[1]);  // no split at 1/2
      }
    for (const auto& [k, r] : {std::pair{4, 1}, std::pair{5, 2}}) {
      const Eigen::MatrixX2d x = bilinear_coefficients(m, k, r);
      double worst = 0, scale = x.cwiseAbs().maxCoeff();
      for (const auto& row : g1_condition_rows(m, g, k, r))
        for (int d = 0; d < 2; ++d) {
          double sum = 0, size = 0;
          for (const auto& [col, value] : row) sum += value * x(col, d), size += std::abs(value);
          worst = std::max(worst, std::abs(sum) / (size * scale));
        }
      REQUIRE(worst < 1e-13);
    }
  }
  // The fan constructions, made from the same edge directions, agree with them at the vertices.
  const QuadMesh five = fan(5, 0.1);
  const GluingData as = analysis_suitable_gluing(five), geo = geometric_gluing(five);
  for (int e = 0; e < five.num_edges(); ++e)
    if (as.edges[e])
      for (double u : {0.0, 1.0}) {
        REQUIRE(geo.edges[e]->a(u) / geo.edges[e]->c(u) == Approx(as.edges[e]->a(u) / as.edges[e]->c(u)).margin(1e-12));
        REQUIRE(geo.edges[e]->b(u) / geo.edges[e]->c(u) == Approx(as.edges[e]->b(u) / as.edges[e]->c(u)).margin(1e-12));
      }
}

TEST_CASE("Analysis-suitable gluing refuses faces that are not convex, and on surfaces is linear symmetric", "[g1][gluing]") {
  // A dart: the corner at vertex 5 has a reflex angle.
  std::vector<Eigen::Vector3d> v{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1.75, 1.75, 0},
                                 {2, 1, 0}, {0, 2, 0}, {1, 2, 0}, {2, 2, 0}};
  const QuadMesh dart = QuadMesh::from_faces(v, {{0, 1, 4, 3}, {1, 2, 5, 4}, {3, 4, 7, 6}, {4, 5, 8, 7}}, "dart");
  REQUIRE_THROWS_WITH(analysis_suitable_gluing(dart), Catch::Contains("face 4 is not a convex quad") &&
                                                          Catch::Contains("vertex 5"));
  // The cube: valence 3 everywhere, a = 2cos(2pi/3)(1 - u) - 2cos(2pi/3) u = 2u - 1.
  const QuadMesh c = cube();
  const GluingData g = analysis_suitable_gluing(c);
  REQUIRE(gluing_violations(c, g).empty());
  for (const auto& e : g.edges) {
    REQUIRE(e);
    REQUIRE(e->a(0.25) == Approx(-0.5));
    REQUIRE(e->b(0.5) == -1);
    REQUIRE(e->c(0.5) == 1);
  }
  // The torus: valence 4 everywhere, a = 0.
  const QuadMesh t = torus(6, 4);
  for (const auto& e : analysis_suitable_gluing(t).edges) REQUIRE(e->a(0.3) == 0);
  // The cube subdivided once: its edge midpoints (valence 4) neighbour the corners (valence
  // 3); the linear data still pass Conditions 3.1 and 3.2 there (docs/G1_POISSON.md measures
  // optimal rates on that sphere too).
  const QuadMesh fine = refine_g1(c, g, 1).mesh;
  REQUIRE(gluing_violations(fine, analysis_suitable_gluing(fine)).empty());
}

TEST_CASE("Sums of cosines: values, and residues that satisfy the minimal polynomials", "[g1][gluing][exact]") {
  // 2cos(2 pi / 5) is a root of x^2 + x - 1, 2cos(2 pi / 7) of x^3 + x^2 - 2x - 1,
  // 2cos(pi / 4) of x^2 - 2, 2cos(19 pi / 5) = 2cos(pi / 5) of x^2 - x - 1 (their minimal
  // polynomials over Q; 19/5 is reduced modulo 2).
  struct Case {
    long p, q;
    std::vector<long> minimal;  // coefficients, constant first
  };
  for (const Case& c : {Case{2, 5, {-1, 1, 1}}, Case{2, 7, {-1, -2, 1, 1}}, Case{1, 4, {-2, 0, 1}}, Case{19, 5, {-1, -1, 1}}}) {
    CAPTURE(c.p, c.q);
    const CosineSum x = CosineSum::two_cos_pi(c.p, c.q);
    REQUIRE(x.value() == Approx(2 * std::cos(M_PI * c.p / c.q)).epsilon(1e-15));
    const long M = x.denominators_lcm();
    REQUIRE(M == c.q);
    for (uint64_t prime : primes_congruent_to_one(2 * M, 2)) {
      REQUIRE((prime - 1) % (2 * M) == 0);
      const uint64_t zeta = primitive_root_of_unity(2 * M, prime);
      REQUIRE(power_modulo(zeta, 2 * M, prime) == 1);
      REQUIRE(power_modulo(zeta, M, prime) == prime - 1);  // primitive: zeta^M = -1
      const ResidueMap residue_of(prime);
      const uint64_t r = x.residue(residue_of, zeta, M);
      uint64_t value = 0;  // the minimal polynomial at r, by Horner
      for (size_t i = c.minimal.size(); i-- > 0;)
        value = (multiply_modulo(value, r, prime) + (c.minimal[i] >= 0 ? c.minimal[i] : prime + c.minimal[i])) % prime;
      CHECK(value == 0);
    }
  }
  // Linear combinations: 2cos(2pi/5) + 2cos(4pi/5) = -1.
  const CosineSum s = CosineSum::two_cos_pi(2, 5) + CosineSum::two_cos_pi(4, 5);
  const uint64_t prime = primes_congruent_to_one(10, 1).front();
  CHECK(s.residue(ResidueMap(prime), primitive_root_of_unity(10, prime), 5) == prime - 1);
  CHECK(s.value() == Approx(-1));
}

TEST_CASE("Irrational symmetric data: the dimension modulo primes with roots of unity equals the SVD's", "[g1][dimension]") {
  // The two computations share nothing but the mesh and the data's doubles: a sparse rank of
  // the conditions reduced into Z/p (zeta_N -> a root of unity) against the dense SVD of the
  // conditions in double precision.
  std::vector<std::pair<std::string, QuadMesh>> meshes;
  for (int F : {5, 7, 8}) meshes.emplace_back("fan of " + std::to_string(F), fan(F));
  meshes.emplace_back("five quads", QuadMesh::read_obj(std::string(KNOTWORK_SOURCE_DIR) + "/cases/meshes/five_quads.obj"));
  for (const auto& [name, mesh] : meshes)
    for (const SymmetricBlend blend : {SymmetricBlend::kC0, SymmetricBlend::kC1, SymmetricBlend::kLinear})
      for (const auto& [k, r] : {std::pair{4, 1}, std::pair{5, 2}}) {
        CAPTURE(name, static_cast<int>(blend), k, r);
        const GluingData g = symmetric_gluing(mesh, blend);
        REQUIRE(!g.exact());
        REQUIRE(g.algebraic());
        const G1SpaceDimension modular = g1_space_dimension_cyclotomic(mesh, g, k, r);
        const G1SpaceDimension svd = g1_space_dimension(mesh, g, k, r, true);
        CHECK(modular.cyclotomic % 2 == 0);
        CHECK(modular.dimension == svd.dimension);
        CHECK(modular.constraints == svd.constraints);
      }
  // The Section 8 count for a fan of F = 5 (above, by SVD) holds for the modular rank too.
  const QuadMesh five = fan(5);
  CHECK(g1_space_dimension_cyclotomic(five, symmetric_gluing(five), 4, 1).dimension == (3 + 5) + 5 * (4 + 5 + 36));
}

// The floating-point dimension of large meshes (g1_space_dimension_local) from local SVDs,
// against two computations that share nothing with it but the conditions' definition: the
// exact rank of rational data, and the dense SVD of all the conditions for data that are
// not rational. Degrees below the separability (k = 3, and r = k - 1) make inseparable
// edges, whose remainder rows join their two vertices: that branch is required to run.
TEST_CASE("Local SVDs give the exact dimension of rational data and the dense SVD's of floating-point data", "[g1][dimension]") {
  const std::string meshes = std::string(KNOTWORK_SOURCE_DIR) + "/cases/meshes/";
  std::vector<std::pair<std::string, QuadMesh>> planar{{"three quads", three_quads()}, {"grid", grid(3)}};
  for (const char* name : {"pentagon.obj", "mixed_valences.obj", "valences_6_8.obj", "lshape_split.obj"})
    planar.emplace_back(name, QuadMesh::read_obj(meshes + name));
  long coupled = 0, compared = 0;
  SECTION("rational data: analysis-suitable (planar), symmetric (cube, torus), once subdivided") {
    std::vector<std::tuple<std::string, QuadMesh, GluingData>> cases;
    for (const auto& [name, m] : planar) {
      if (name == "three quads") continue;  // irrational coordinates: below
      cases.emplace_back(name, m, analysis_suitable_gluing(m));
    }
    for (const QuadMesh& m : {cube(), torus(4, 3)}) cases.emplace_back("closed", m, symmetric_gluing(m));
    const QuadMesh pentagon = QuadMesh::read_obj(meshes + "pentagon.obj");
    const G1Refinement fine = refine_g1(pentagon, analysis_suitable_gluing(pentagon), 1);
    cases.emplace_back("pentagon, subdivided", fine.mesh, fine.gluing);
    for (const auto& [name, m, g] : cases)
      for (const auto& [k, r] : {std::pair{3, 0}, {3, 1}, {4, 1}, {4, 2}, {4, 3}, {5, 1}, {5, 3}}) {
        CAPTURE(name, k, r);
        REQUIRE(g.exact());
        const G1SpaceDimension exact = g1_space_dimension(m, g, k, r);
        const G1SpaceDimension local = g1_space_dimension_local(m, g, k, r);
        REQUIRE(exact.exact);
        REQUIRE(local.local);
        CHECK(local.dimension == exact.dimension);
        CHECK(local.constraints == exact.constraints);
        coupled += local.coupled_edges;
        ++compared;
      }
    CHECK(compared == 8 * 7);  // eight meshes, seven (k, r)
    CHECK(coupled > 0);
  }
  SECTION("floating-point data: geometric on irrational coordinates, cosine sums, against the dense SVD") {
    std::vector<std::tuple<std::string, QuadMesh, GluingData>> cases;
    cases.emplace_back("three quads, geometric", three_quads(), geometric_gluing(three_quads()));
    cases.emplace_back("uneven fan of 5, geometric", fan(5, 0.1), geometric_gluing(fan(5, 0.1)));
    cases.emplace_back("fan of 7, symmetric", fan(7), symmetric_gluing(fan(7)));
    cases.emplace_back("split pentagonal prism, linear symmetric", split_prism(5), analysis_suitable_gluing(split_prism(5)));
    for (const auto& [name, m, g] : cases)
      for (const auto& [k, r] : {std::pair{3, 1}, {4, 1}, {4, 3}, {5, 2}}) {
        CAPTURE(name, k, r);
        REQUIRE(!g.exact());
        const G1SpaceDimension dense = g1_space_dimension(m, g, k, r, true);
        const G1SpaceDimension local = g1_space_dimension_local(m, g, k, r);
        CHECK(local.dimension == dense.dimension);
        coupled += local.coupled_edges;
      }
    CHECK(coupled > 0);
  }
}

// Below the separability everywhere (k = 3), every edge joins its two vertices: the groups of
// the local SVDs grow with the mesh, and past kMaxG1FloatingGroup corner-block unknowns the
// dimension is refused rather than computed by one cubic SVD.
TEST_CASE("Local SVDs refuse a group of coupled vertices beyond their limit", "[g1][dimension][bad-input]") {
  const QuadMesh fan5 = fan(5, 0.1);
  const GluingData g = geometric_gluing(fan5);
  REQUIRE(!g.exact());
  // The five edges at the centre couple (the sub-edges along them after subdivision): at 5
  // subdivisions their chains hold 2 540 corner-block unknowns.
  const G1SpaceDimension coarse = g1_space_dimension_local(fan5, g, 3, 1);
  REQUIRE(coarse.coupled_edges == 5);
  // Below the limit a large group takes BDCSVD (more than 200 columns): rational data, the
  // exact dimension against it (the pentagon's spokes, three subdivisions, about 650 columns).
  const QuadMesh pentagon = QuadMesh::read_obj(std::string(KNOTWORK_SOURCE_DIR) + "/cases/meshes/pentagon.obj");
  const G1Refinement spokes = refine_g1(pentagon, analysis_suitable_gluing(pentagon), 3);
  const G1SpaceDimension local = g1_space_dimension_local(spokes.mesh, spokes.gluing, 3, 1);
  CHECK(local.coupled_edges >= 40);
  CHECK(local.dimension == g1_space_dimension(spokes.mesh, spokes.gluing, 3, 1).dimension);
  const G1Refinement fine = refine_g1(fan5, g, 5);
  REQUIRE_THROWS_WITH(g1_space_dimension_local(fine.mesh, fine.gluing, 3, 1),
                      Catch::Contains("2540 corner-block unknowns are coupled") && Catch::Contains("2000"));
}
