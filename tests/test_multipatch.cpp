// Multipatch domains: the two peer formats read to the same domain, G+Smo XML round-trips,
// a domain cut into patches gives the same discrete solution as the one patch it was cut from
// (the same space: C0 knots where the cuts are), and turning a patch's parameter square in
// the file changes nothing.
#include <catch2/catch.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "basis/core/bspline_basis.hpp"
#include "basis/core/input_error.hpp"
#include "basis/tensor/multipatch_tensor.hpp"
#include "cases/geometries.hpp"
#include "cases/geometry_file.hpp"
#include "cli_sandbox.hpp"

using namespace knotwork;
using namespace cli_test;

namespace {

const std::string kGeometries = std::string(KNOTWORK_SOURCE_DIR) + "/cases/geometries/";

void require_same_domain(const MultiPatch& a, const MultiPatch& b) {
  REQUIRE(a.num_patches() == b.num_patches());
  for (int p = 0; p < a.num_patches(); ++p) {
    const NurbsPatch &x = a.patches[p], &y = b.patches[p];
    REQUIRE(x.basis_u.knots() == y.basis_u.knots());
    REQUIRE(x.basis_v.knots() == y.basis_v.knots());
    REQUIRE(x.basis_u.degree() == y.basis_u.degree());
    REQUIRE(x.basis_v.degree() == y.basis_v.degree());
    // GeoPDEs stores w x (one rounding), G+Smo x: the points agree to a few ulps.
    REQUIRE((x.control_points - y.control_points).cwiseAbs().maxCoeff() <= 8e-16 * (1 + x.control_points.cwiseAbs().maxCoeff()));
    REQUIRE((x.weights - y.weights).cwiseAbs().maxCoeff() == 0);
  }
  REQUIRE(a.interfaces.size() == b.interfaces.size());
  for (size_t i = 0; i < a.interfaces.size(); ++i) {
    REQUIRE(a.interfaces[i].a == b.interfaces[i].a);
    REQUIRE(a.interfaces[i].b == b.interfaces[i].b);
    REQUIRE(a.interfaces[i].reversed == b.interfaces[i].reversed);
  }
  REQUIRE(a.boundaries.size() == b.boundaries.size());
  for (size_t i = 0; i < a.boundaries.size(); ++i) {
    REQUIRE(a.boundaries[i].name == b.boundaries[i].name);
    REQUIRE(a.boundaries[i].sides == b.boundaries[i].sides);
  }
}

// The patch with its parameter square turned by a quarter turn: (u, v) -> (v, 1 - u) in the
// parameters, so the new control net is the old one transposed and reversed along the new u.
NurbsPatch turned(const NurbsPatch& p) {
  NurbsPatch t;
  std::vector<double> ku = p.basis_v.knots(), kv = p.basis_u.knots();
  std::reverse(ku.begin(), ku.end());
  const double a = p.basis_v.domain_begin(), b = p.basis_v.domain_end();
  for (double& k : ku) k = a + b - k;
  t.basis_u = BSplineBasis1D(p.basis_v.degree(), ku);
  t.basis_v = BSplineBasis1D(p.basis_u.degree(), kv);
  const int nu = p.basis_u.num_functions(), nv = p.basis_v.num_functions();
  t.control_points.resize(nu * nv, 2);
  t.weights.resize(nu * nv);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {  // old (i, j) -> new (nv - 1 - j, i), the new u has nv functions
      const int to = (nv - 1 - j) + nv * i;
      t.control_points.row(to) = p.control_points.row(i + nu * j);
      t.weights[to] = p.weights[i + nu * j];
    }
  return t;
}

// Columns [from, to) of control points of a patch whose u knots are C0 at the cut: a patch of
// its own on [0, 1] (degree-1 or C0 pieces: the columns are the piece's net).
NurbsPatch columns(const NurbsPatch& p, int from, int to) {
  NurbsPatch c;
  const int du = p.basis_u.degree(), nu = p.basis_u.num_functions(), nv = p.basis_v.num_functions();
  std::vector<double> k(du + 1, 0.0);
  k.insert(k.end(), du + 1, 1.0);
  c.basis_u = BSplineBasis1D(du, k);
  c.basis_v = p.basis_v;
  const int n = to - from;
  c.control_points.resize(n * nv, 2);
  c.weights.resize(n * nv);
  for (int j = 0; j < nv; ++j)
    for (int i = from; i < to; ++i) {
      c.control_points.row((i - from) + n * j) = p.control_points.row(i + nu * j);
      c.weights[(i - from) + n * j] = p.weights[i + nu * j];
    }
  return c;
}

NurbsPatch transposed(const NurbsPatch& p) {  // u <-> v (orientation reversed)
  NurbsPatch t;
  t.basis_u = p.basis_v, t.basis_v = p.basis_u;
  const int nu = p.basis_u.num_functions(), nv = p.basis_v.num_functions();
  t.control_points.resize(nu * nv, 2);
  t.weights.resize(nu * nv);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) t.control_points.row(j + nv * i) = p.control_points.row(i + nu * j), t.weights[j + nv * i] = p.weights[i + nu * j];
  return t;
}

struct Errors {
  double l2, h1;
  double condition;  // of the Jacobi-scaled stiffness matrix (run --condition)
};

// Two solves of the same space in two numberings differ by rounding only: by backward
// stability their discrete solutions differ by about kappa eps |u_h|, and so do their errors.
// |u_h|_H1 <= 10 for the smooth solutions used here, and 1000 leaves room for the growth of
// rounding with the size of these small systems.
double same_space_tolerance(const Errors& a, const Errors& b) {
  return 1e4 * std::max(a.condition, b.condition) * std::numeric_limits<double>::epsilon();
}

// `knotwork run ARGS --json --no-output --condition` in the sandbox: its errors and condition.
Errors run_case(const Sandbox& box, const std::string& args) {
  const Result r = box.run("run --json --no-output --condition " + args);
  INFO(r.err);
  REQUIRE(r.code == 0);
  return {json_number_of(r.out, "l2_error"), json_number_of(r.out, "h1_seminorm_error"), json_number_of(r.out, "stiffness")};
}

Errors solve(const Sandbox& box, const MultiPatch& domain, const std::string& name, const std::string& problem) {
  write_gismo_xml(domain, (box.dir() / (name + ".xml")).string());
  box.file(name + ".toml", "[geometry]\nfile = \"" + name + ".xml\"\n[space]\ndegree = 2\nelements = 3\n[problem]\n" + problem);
  return run_case(box, name + ".toml");
}

MultiPatch one_patch(const NurbsPatch& p) {
  MultiPatch d;
  d.patches = {p};
  return d;
}

// The domain's interfaces from coinciding sides (as the case script finds them).
void glue(MultiPatch& d) {
  d.patch_labels.clear();
  for (int p = 0; p < d.num_patches(); ++p) d.patch_labels.push_back(std::to_string(p));
  d.interfaces.clear();
  auto corner = [&](int p, int s, bool last) {
    const NurbsPatch& patch = d.patches[p];
    const double t = last ? 1.0 : 0.0;
    const double u = s == 1 ? 0 : s == 2 ? 1 : t, v = s == 3 ? 0 : s == 4 ? 1 : t;
    return patch_point(patch, patch.basis_u.domain_begin() + u * (patch.basis_u.domain_end() - patch.basis_u.domain_begin()),
                       patch.basis_v.domain_begin() + v * (patch.basis_v.domain_end() - patch.basis_v.domain_begin()));
  };
  std::vector<PatchSideRef> used;
  for (int a = 0; a < d.num_patches(); ++a)
    for (int sa = 1; sa <= 4; ++sa)
      for (int b = a + 1; b < d.num_patches(); ++b)
        for (int sb = 1; sb <= 4; ++sb) {
          const bool same = (corner(a, sa, false) - corner(b, sb, false)).norm() < 1e-12 &&
                            (corner(a, sa, true) - corner(b, sb, true)).norm() < 1e-12;
          const bool opposite = (corner(a, sa, false) - corner(b, sb, true)).norm() < 1e-12 &&
                                (corner(a, sa, true) - corner(b, sb, false)).norm() < 1e-12;
          if (same || opposite) d.interfaces.push_back({{a, sa}, {b, sb}, opposite, ""});
        }
}

}  // namespace

TEST_CASE("GeoPDEs text and G+Smo XML of each shipped domain read to the same domain, and XML round-trips",
          "[multipatch]") {
  for (const char* name : {"lshape_3patches", "ring_4patches", "plate_with_hole", "plus_12patches"}) {
    INFO(name);
    const MultiPatch text = read_geometry_file(kGeometries + name + ".txt");
    const MultiPatch xml = read_geometry_file(kGeometries + name + ".xml");
    require_same_domain(text, xml);
    Sandbox box;
    const std::string again = (box.dir() / "again.xml").string();
    write_gismo_xml(text, again);
    require_same_domain(text, read_geometry_file(again));
  }
}

TEST_CASE("The L-shape cut along its C0 fold into two patches gives the one patch's solution", "[multipatch]") {
  // lshape_patch is bilinear with a C0 knot at u = 1/2: its control columns 0-1 and 1-2 are the
  // two quads. Degree 2 keeps the fold C0, so both spaces are the same.
  const NurbsPatch whole = lshape_patch();
  const std::string problem = "exact = \"sin(2*x)*cosh(y) + x*y\"\nneumann = [\"1\"]\n";
  Sandbox box;
  const Errors e1 = solve(box, one_patch(whole), "one", problem);
  for (int turns = 0; turns < 4; ++turns) {
    MultiPatch two;
    NurbsPatch second = columns(whole, 1, 3);
    for (int k = 0; k < turns; ++k) second = turned(second);
    two.patches = {columns(whole, 0, 2), second};
    glue(two);
    REQUIRE(two.interfaces.size() == 1);
    // Side 1 of the single patch (u = 0) is side 1 of the first piece.
    two.boundaries = {{"1", {{0, 1}}, ""}};
    const Errors e2 = solve(box, two, "two" + std::to_string(turns), problem);
    INFO("quarter turns of the second patch: " << turns);
    REQUIRE(std::abs(e1.l2 - e2.l2) <= same_space_tolerance(e1, e2));
    REQUIRE(std::abs(e1.h1 - e2.h1) <= same_space_tolerance(e1, e2));
  }
}

TEST_CASE("The quarter annulus cut into 2 x 2 NURBS patches gives the one patch's solution, however they are turned",
          "[multipatch]") {
  // Knots inserted at 1/2 to C0 in both directions (once in u, degree 1; twice in v, degree 2)
  // leave the same geometry; its single patch and its four pieces carry the same space.
  NurbsPatch p = quarter_annulus_patch(1, 2);
  auto insert = [](NurbsPatch& patch, bool along_u, double t) {
    const BSplineBasis1D& b = along_u ? patch.basis_u : patch.basis_v;
    const int nu = patch.basis_u.num_functions(), nv = patch.basis_v.num_functions();
    const int n = along_u ? nu : nv, m = along_u ? nv : nu;
    Eigen::MatrixXd c(n, 3 * m);  // homogeneous points of each line across, side by side
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < n; ++i) {
        const int k = along_u ? i + nu * j : j + nu * i;
        c(i, 3 * j) = patch.weights[k] * patch.control_points(k, 0);
        c(i, 3 * j + 1) = patch.weights[k] * patch.control_points(k, 1);
        c(i, 3 * j + 2) = patch.weights[k];
      }
    const BSplineBasis1D refined = insert_knot(b, c, t);
    (along_u ? patch.basis_u : patch.basis_v) = refined;
    const int n2 = refined.num_functions(), nu2 = along_u ? n2 : nu;
    patch.control_points.resize(n2 * m, 2);
    patch.weights.resize(n2 * m);
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < n2; ++i) {
        const int k = along_u ? i + nu2 * j : j + nu2 * i;
        patch.weights[k] = c(i, 3 * j + 2);
        patch.control_points(k, 0) = c(i, 3 * j) / c(i, 3 * j + 2);
        patch.control_points(k, 1) = c(i, 3 * j + 1) / c(i, 3 * j + 2);
      }
  };
  insert(p, true, 0.5);
  insert(p, false, 0.5);
  insert(p, false, 0.5);
  const std::string problem = "exact = \"exp(x/2)*sin(y) + x*y/4\"\nneumann = [\"2\"]\n";
  Sandbox box;
  const Errors e1 = solve(box, one_patch(p), "one", problem);
  // The pieces: u columns {0,1}, {1,2}; v rows {0..2}, {2..4}.
  auto piece = [&](int iu, int iv) {
    NurbsPatch q = columns(p, iu, iu + 2);
    NurbsPatch qt = columns(transposed(q), 2 * iv, 2 * iv + 3);  // rows of q as columns of its transpose
    return transposed(qt);
  };
  for (int variant = 0; variant < 3; ++variant) {
    MultiPatch four;
    for (int iv = 0; iv < 2; ++iv)
      for (int iu = 0; iu < 2; ++iu) {
        NurbsPatch q = piece(iu, iv);
        const int k = iu + 2 * iv;
        for (int t = 0; t < (variant == 0 ? 0 : variant == 1 ? k : 3 - k); ++t) q = turned(q);
        four.patches.push_back(q);
      }
    glue(four);
    REQUIRE(four.interfaces.size() == 4);
    // Side 2 of the whole (u = 1, the outer circle) is where the turned pieces have it: find it.
    NamedBoundary outer{"2", {}, ""};
    for (int k = 0; k < 4; ++k)
      for (int s = 1; s <= 4; ++s) {
        const NurbsPatch& q = four.patches[k];
        const double u = s == 1 ? 0 : s == 2 ? 1 : 0.5, v = s == 3 ? 0 : s == 4 ? 1 : 0.5;
        if (std::abs(patch_point(q, u, v).norm() - 2) < 1e-12) outer.sides.push_back({k, s});
      }
    REQUIRE(outer.sides.size() == 2);
    four.boundaries = {outer};
    const Errors e2 = solve(box, four, "four" + std::to_string(variant), problem);
    INFO("variant " << variant);
    REQUIRE(std::abs(e1.l2 - e2.l2) <= same_space_tolerance(e1, e2));
    REQUIRE(std::abs(e1.h1 - e2.h1) <= same_space_tolerance(e1, e2));
  }
}

TEST_CASE("Each shipped multipatch case converges at the optimal rates for p = 1..4", "[multipatch][rates]") {
  // Rates between the last two of 3 uniform levels: L2 like h^(p+1), H1 like h^p (smooth exact
  // solutions). Degree 1 is below the degree-2 NURBS and curved geometries: B-splines
  // (rational = false) on the exact geometry there, as the isoparametric space cannot be.
  for (const char* name : {"multipatch_lshape", "multipatch_lshape_geopdes", "multipatch_ring", "multipatch_plate_with_hole",
                           "multipatch_plus"}) {
    const std::string text = slurp(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
    for (int p = 1; p <= 4; ++p) {
      Sandbox box;
      std::string c = replace(text, "file = \"geometries/", "file = \"" + kGeometries);
      c = replace(c, "degree = 2", "degree = " + std::to_string(p) + (p == 1 ? "\nrational = false" : ""));
      box.file("case.toml", c);
      const Result r = box.run("converge --levels 3 --json case.toml");
      INFO(name << ", p = " << p << ": " << r.err);
      REQUIRE(r.code == 0);
      const auto last_rate = [&](const std::string& key) {
        const auto at = r.out.rfind("\"" + key + "\": ");
        REQUIRE(at != std::string::npos);
        return std::stod(r.out.substr(at + key.size() + 4));
      };
      CHECK(last_rate("l2_rate") > p + 1 - 0.15);
      CHECK(last_rate("h1_rate") > p - 0.1);
    }
  }
}

TEST_CASE("[space] boundary_quadrature_points: the default is the interior rule plus one, and it is read", "[quadrature]") {
  // The GeoPDEs convention (the interior rule's points on sides) changes the boundary
  // integrals, so the errors move; giving the default's number explicitly changes nothing.
  const std::string text = slurp(std::string(KNOTWORK_SOURCE_DIR) + "/cases/multipatch_plate_with_hole.toml");
  Sandbox box;
  auto errors = [&](const std::string& extra) {
    std::string c = replace(text, "file = \"geometries/", "file = \"" + kGeometries);
    c = replace(c, "elements = 4", "elements = 4\nquadrature_points = 3" + extra);
    box.file("case.toml", c);
    const Result r = box.run("run --json --no-output case.toml");
    INFO(r.err);
    REQUIRE(r.code == 0);
    return json_number_of(r.out, "h1_seminorm_error");
  };
  const double by_default = errors(""), explicit_default = errors("\nboundary_quadrature_points = 4");
  const double peers = errors("\nboundary_quadrature_points = 3");
  REQUIRE(by_default == explicit_default);
  REQUIRE(peers != by_default);
  REQUIRE(std::abs(peers - by_default) < 1e-2 * by_default);  // a quadrature change, not another problem
  box.file("bad.toml", replace(replace(text, "file = \"geometries/", "file = \"" + kGeometries), "elements = 4",
                               "elements = 4\nboundary_quadrature_points = 0"));
  const Result bad = box.run("run -q bad.toml");
  REQUIRE(bad.code == 2);
  REQUIRE(bad.err.find("[space] boundary_quadrature_points: must be in [1, 30], got 0") != std::string::npos);
}

TEST_CASE("A patch's parameter domain need not be [0, 1]: the same squares on other knot ranges solve the same",
          "[multipatch]") {
  // Two unit squares side by side; then the second patch's knots moved to [2, 5] x [1, 3]
  // (the same map, reparametrized affinely): the interface check and the gluing must map
  // parameters through each patch's own domain.
  auto squares = [](double u0, double u1, double v0, double v1) {
    MultiPatch d;
    for (int k = 0; k < 2; ++k) {
      NurbsPatch p;
      p.basis_u = BSplineBasis1D(1, k == 0 ? std::vector<double>{0, 0, 1, 1} : std::vector<double>{u0, u0, u1, u1});
      p.basis_v = BSplineBasis1D(1, k == 0 ? std::vector<double>{0, 0, 1, 1} : std::vector<double>{v0, v0, v1, v1});
      p.control_points.resize(4, 2);
      p.control_points << k, 0, k + 1, 0, k, 1, k + 1, 1;
      p.weights = Eigen::VectorXd::Ones(4);
      d.patches.push_back(p);
    }
    glue(d);
    return d;
  };
  Sandbox box;
  const std::string problem = "exact = \"sin(x)*exp(y)\"\n";
  const MultiPatch unit = squares(0, 1, 0, 1), moved = squares(2, 5, 1, 3);
  REQUIRE(moved.interfaces.size() == 1);
  REQUIRE_NOTHROW(check_multipatch(moved));
  const Errors a = solve(box, unit, "unit", problem), b = solve(box, moved, "moved", problem);
  REQUIRE(std::abs(a.l2 - b.l2) <= same_space_tolerance(a, b));
  REQUIRE(std::abs(a.h1 - b.h1) <= same_space_tolerance(a, b));
}

TEST_CASE("GeoPDEs' ring and iso-ring tests give the same errors from GeoPDEs' text file as from the built-in patch",
          "[multipatch][geopdes]") {
  // GeoPDEs' test_ring: the quarter annulus 1 <= r <= 2, u = -(r^2-1)(r^2-4) x y^2, degree 3,
  // C^2, 9 new knots per interval (10 elements), 4 Gauss points inside and on the boundary;
  // the ring with B-splines, the iso-ring with NURBS (rational), Dirichlet on every side or
  // Neumann on two. cases/geometries/quarter_ring.txt is the built-in quarter_annulus_patch
  // written in GeoPDEs' format (weighted control points); reading it back costs an ulp here
  // and there, so the errors agree to the rounding of the solve (same_space_tolerance).
  Sandbox box;
  const std::string space = "[space]\ndegree = 3\nelements = 10\nquadrature_points = 4\nboundary_quadrature_points = 4\n";
  for (const bool rational : {false, true})
    for (const std::string neumann : {"", "neumann = [\"2\", \"4\"]\n"}) {
      const std::string rest = space + "rational = " + (rational ? "true" : "false") +
                               "\n[problem]\nexact = \"-(x^2+y^2-1)*(x^2+y^2-4)*x*y^2\"\n" + neumann;
      box.file("built_in.toml", "[geometry]\ntype = \"quarter_annulus\"\n" + rest);
      box.file("from_file.toml", "[geometry]\nfile = \"" + kGeometries + "quarter_ring.txt\"\n" + rest);
      const Errors e[2] = {run_case(box, "built_in.toml"), run_case(box, "from_file.toml")};
      INFO((rational ? "iso-ring" : "ring") << (neumann.empty() ? ", Dirichlet" : ", mixed") << ": L2 " << e[0].l2 << " and "
                                           << e[1].l2 << ", H1 " << e[0].h1 << " and " << e[1].h1);
      CHECK(std::abs(e[0].l2 - e[1].l2) <= same_space_tolerance(e[0], e[1]));
      CHECK(std::abs(e[0].h1 - e[1].h1) <= same_space_tolerance(e[0], e[1]));
    }
}

TEST_CASE("A G+Smo problem file runs as the case it describes", "[multipatch][gismo]") {
  // cases/multipatch_lshape_problem.xml (written by scripts/write_multipatch_geometries.py) is
  // cases/multipatch_lshape.toml's problem in G+Smo's layout: Dirichlet on "outer" from a
  // function, Neumann on the two re-entrant sides as a flux vector and as a flux. The TOML case
  // below takes its Neumann data from the exact solution instead, with the same space and
  // rules: the two agree to the rounding of the solve.
  Sandbox box;
  const std::string problem = std::string(KNOTWORK_SOURCE_DIR) + "/cases/multipatch_lshape_problem.xml";
  for (int p : {2, 3}) {
    const std::string args = "--degree " + std::to_string(p) + " --elements 4 ";
    box.file("same.toml", "[geometry]\nfile = \"" + kGeometries + "lshape_3patches.xml\"\n[space]\ndegree = 2\nelements = 4\n"
                          "rational = false\nboundary_quadrature_points = \"interior\"\n[problem]\n"
                          "exact = \"sin(2*x)*cosh(y) + x*y\"\nneumann = [\"reentrant\"]\n");
    const Errors e[2] = {run_case(box, args + problem), run_case(box, args + "same.toml")};
    INFO("degree " << p << ": L2 " << e[0].l2 << " and " << e[1].l2);
    CHECK(std::abs(e[0].l2 - e[1].l2) <= same_space_tolerance(e[0], e[1]));
    CHECK(std::abs(e[0].h1 - e[1].h1) <= same_space_tolerance(e[0], e[1]));
  }
  // Without options, G+Smo's examples' space: the patches' degree (1 here), 32 elements per
  // knot span; three 33 x 33 grids of functions sharing two interfaces of 33.
  const Result r = box.run("run --json --no-output " + problem);
  REQUIRE(r.code == 0);
  CHECK(json_number_of(r.out, "dofs") == 3 * 33 * 33 - 2 * 33);
}

TEST_CASE("G1 on a geometry file of bilinear patches is G1 on the quad mesh they make, and curved patches are refused",
          "[multipatch][g1]") {
  // Each quad of a shipped OBJ mesh written as a bilinear patch (its corners turned by a
  // different number of quarter turns per patch), glued where sides coincide: the same quad
  // mesh, numbered and parametrized otherwise. The G1 space is the mesh's, so the errors agree
  // to the rounding of the solve.
  Sandbox box;
  const std::string meshes = std::string(KNOTWORK_SOURCE_DIR) + "/cases/meshes/";
  const std::string problem = "[problem]\noperator = \"laplace\"\nexact = \"cos(2*x)*exp(y) + x^2*y\"\n";
  for (const char* name : {"three_quads", "pentagon"}) {
    INFO(name);
    std::vector<Eigen::Vector3d> v;
    std::vector<std::array<int, 4>> faces;
    {
      std::ifstream in(meshes + name + ".obj");
      for (std::string line; std::getline(in, line);) {
        std::istringstream s(line);
        std::string tag;
        s >> tag;
        if (tag == "v") {
          Eigen::Vector3d x;
          s >> x[0] >> x[1] >> x[2];
          v.push_back(x);
        } else if (tag == "f") {
          std::array<int, 4> f;
          for (int& k : f) s >> k, --k;
          faces.push_back(f);
        }
      }
    }
    REQUIRE(!faces.empty());
    MultiPatch d;
    for (size_t k = 0; k < faces.size(); ++k) {
      std::array<int, 4> f;
      for (int j = 0; j < 4; ++j) f[j] = faces[k][(j + k) % 4];  // turned by k quarter turns
      NurbsPatch p = rectangle_patch(0, 0, 1, 1);
      const int corner[4] = {0, 1, 3, 2};  // (u, v) = (0,0), (1,0), (1,1), (0,1) in the net's order
      for (int j = 0; j < 4; ++j) p.control_points.row(corner[j]) << v[f[j]][0], v[f[j]][1];
      d.patches.push_back(p);
    }
    glue(d);
    write_gismo_xml(d, (box.dir() / "patches.xml").string());
    const std::string space = "[space]\nfamily = \"g1\"\ndegree = 4\nsplit_smoothness = 1\n";
    box.file("obj.toml", space + "mesh = \"" + meshes + name + ".obj\"\n" + problem);
    box.file("xml.toml", space + "[geometry]\nfile = \"patches.xml\"\n" + problem);
    const Errors e[2] = {run_case(box, "obj.toml"), run_case(box, "xml.toml")};
    INFO("L2 " << e[0].l2 << " and " << e[1].l2 << ", H1 " << e[0].h1 << " and " << e[1].h1);
    CHECK(std::abs(e[0].l2 - e[1].l2) <= same_space_tolerance(e[0], e[1]));
    CHECK(std::abs(e[0].h1 - e[1].h1) <= same_space_tolerance(e[0], e[1]));
  }
  // The ring's patches are quadratic along the angle: refused, naming the patch.
  box.file("curved.toml", "[space]\nfamily = \"g1\"\n[geometry]\nfile = \"" + kGeometries + "ring_4patches.txt\"\n" + problem);
  const Result r = box.run("run -q --no-output curved.toml");
  CHECK(r.code != 0);
  CHECK(r.err.find("curved.toml: [geometry] file: ") != std::string::npos);
  CHECK(r.err.find("patch 1 has degree 1x2") != std::string::npos);
}

TEST_CASE("The per-patch fast diagonalization solves multipatch cases to the direct solution, and auto takes multigrid",
          "[multipatch][solver]") {
  // CG stops at a backward error of 1e-15; the two solutions then differ by about kappa times
  // that, and so do their errors (same_space_tolerance, with the condition of the system).
  Sandbox box;
  for (const char* name : {"multipatch_ring", "multipatch_plus", "multipatch_lshape"}) {
    INFO(name);
    const std::string text = slurp(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
    std::string local = text;
    for (size_t at = local.find("geometries/"); at != std::string::npos; at = local.find("geometries/", at + kGeometries.size()))
      local.replace(at, std::string("geometries/").size(), kGeometries);
    box.file("direct.toml", local);
    box.file("fd.toml", local + "\n[solver]\nmethod = \"iterative\"\npreconditioner = \"fast_diagonalization\"\nmax_iterations = 5000\n");
    box.file("auto.toml", local + "\n[solver]\nmethod = \"iterative\"\n");
    const Errors e[2] = {run_case(box, "--elements 6 direct.toml"), run_case(box, "--elements 6 fd.toml")};
    const Result fd = box.run("run --json --no-output --elements 6 fd.toml");
    REQUIRE(fd.code == 0);
    CHECK(fd.out.find("\"preconditioner\": \"fast_diagonalization\"") != std::string::npos);
    CHECK(std::abs(e[0].l2 - e[1].l2) <= same_space_tolerance(e[0], e[1]));
    CHECK(std::abs(e[0].h1 - e[1].h1) <= same_space_tolerance(e[0], e[1]));
    const Result a = box.run("run --json --no-output --elements 6 auto.toml");
    REQUIRE(a.code == 0);
    CHECK(a.out.find("\"preconditioner\": \"multigrid\"") != std::string::npos);
  }
}

TEST_CASE("On several patches the memory guard follows the path the solve takes, and refuses before allocating",
          "[multipatch][solver]") {
  // 4096 elements per side on the plus: 2e8 cells. "auto" would take CG + multigrid, whose
  // estimate (calibrated on measured peaks, families/tensor/tensor_family.cpp) is named; the
  // direct solve's is larger.
  Sandbox box;
  std::string local = slurp(std::string(KNOTWORK_SOURCE_DIR) + "/cases/multipatch_plus.toml");
  for (size_t at = local.find("geometries/"); at != std::string::npos; at = local.find("geometries/", at + kGeometries.size()))
    local.replace(at, std::string("geometries/").size(), kGeometries);
  box.file("plus.toml", local);
  const Result cg = box.run("run -q --no-output --elements 4096 plus.toml");
  CHECK(cg.code != 0);
  CHECK(cg.err.find("plus.toml: [space] elements: about ") != std::string::npos);
  CHECK(cg.err.find(" with CG + multigrid, more than this machine's ") != std::string::npos);
  const Result direct = box.run("run -q --no-output --elements 4096 --solver direct plus.toml");
  CHECK(direct.code != 0);
  CHECK(direct.err.find("plus.toml: [space] elements: about ") != std::string::npos);
  CHECK(direct.err.find("CG") == std::string::npos);
}

TEST_CASE("Parts of a multipatch space hold whole patches and the halo their functions need, checked against the whole",
          "[multipatch][parts]") {
  // By brute force against the whole space: the owned cells of all ranks tile it (same patch,
  // box, functions by global number, extraction), the owned functions tile [0, N), and every
  // cell of the whole space that carries an owned function is in the rank's part.
  for (const char* name : {"plus_12patches.txt", "ring_4patches.txt", "lshape_3patches.xml"}) {
    const MultiPatch domain = read_geometry_file(kGeometries + name);
    TensorSpaceOptions o;
    o.degree = {2, 2};
    o.elements_per_span = {3, 3};
    o.rational = std::string(name).find("lshape") == std::string::npos;
    const MultiPatchTensorDiscretization whole = build_multipatch_tensor(domain, o);
    const BezierMesh& W = whole.mesh;
    for (int ranks : {2, 3}) {
      INFO(name << ", " << ranks << " ranks");
      std::vector<int> cell_owner(W.num_cells(), -1), function_owner(W.num_functions(), -1);
      for (int rank = 0; rank < ranks; ++rank) {
        const MultiPatchTensorPart p = build_multipatch_tensor_part(domain, o, rank, ranks);
        const BezierMesh& M = p.mesh;
        REQUIRE(p.part.global_functions == W.num_functions());
        REQUIRE(p.part.global_cells == W.num_cells());
        for (int g = p.part.first_owned_function; g < p.part.last_owned_function; ++g) {
          REQUIRE(function_owner[g] < 0);
          function_owner[g] = rank;
        }
        // Each part cell is the whole space's cell with the same patch and box.
        std::vector<int> whole_cell(M.num_cells(), -1);
        for (int c = 0; c < M.num_cells(); ++c) {
          const BezierCell& a = M.cell(c);
          for (int w = whole.first_cell[a.patch]; w < whole.first_cell[a.patch + 1]; ++w) {
            const BezierCell& b = W.cell(w);
            if (a.u0 == b.u0 && a.u1 == b.u1 && a.v0 == b.v0 && a.v1 == b.v1) whole_cell[c] = w;
          }
          REQUIRE(whole_cell[c] >= 0);
          const int w = whole_cell[c];
          CHECK(M.cell(c).boundary == W.cell(w).boundary);
          CHECK((M.extraction(c) - W.extraction(w)).cwiseAbs().maxCoeff() == 0);
          const auto fa = M.functions(c), fb = W.functions(w);
          REQUIRE(fa.size() == fb.size());
          for (size_t k = 0; k < fa.size(); ++k) CHECK(p.part.global(fa[k]) == fb[k]);
          if (c >= p.part.owned.first && c < p.part.owned.last) {
            REQUIRE(cell_owner[w] < 0);
            cell_owner[w] = rank;
          }
        }
        // The halo: every whole cell carrying an owned function is in the part.
        std::vector<char> held(W.num_cells(), 0);
        for (int w : whole_cell) held[w] = 1;
        for (int w = 0; w < W.num_cells(); ++w)
          for (int f : W.functions(w))
            if (f >= p.part.first_owned_function && f < p.part.last_owned_function) CHECK(held[w]);
        CHECK(M.num_cells() < W.num_cells());
      }
      CHECK(std::count(cell_owner.begin(), cell_owner.end(), -1) == 0);
      CHECK(std::count(function_owner.begin(), function_owner.end(), -1) == 0);
    }
  }
}
