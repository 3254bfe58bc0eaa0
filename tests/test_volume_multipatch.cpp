// Several volumes glued face to face (basis/core/multivolume, glue_volumes; family tensor): the
// Fichera corner as seven cubes, three of them turned, read from both peer formats that
// scripts/write_volume_geometries.py writes. The orientations the files declare are the ones
// the geometry shows; the glued space has the dimension counted by hand, is the same space as
// the THB Fichera corner (one box less its octant: another construction), reproduces
// triquadratics, converges at the optimal rates, and its estimator sees the turned faces.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "basis/core/multivolume.hpp"
#include "cases/case_file.hpp"
#include "cases/geometry_file.hpp"
#include "cases/spline_space.hpp"
#include "rounding_bounds.hpp"
#include "solver/residual_estimator.hpp"
#include "studies/pipeline.hpp"
#include "studies/studies.hpp"

using namespace knotwork;

namespace {

std::string geometry(const std::string& name) { return std::string(KNOTWORK_SOURCE_DIR) + "/cases/geometries/" + name; }

CaseDescription patches_case(const std::string& file, const std::string& space, const std::string& problem) {
  return load_case_text("[geometry]\nfile = \"" + geometry(file) + "\"\n[space]\n" + space + "\n[problem]\n" + problem, "volumes.toml");
}

}  // namespace

TEST_CASE("Both files of the seven-cube Fichera corner declare the orientations the geometry shows", "[volume][multipatch]") {
  for (const char* name : {"fichera_7patches.txt", "fichera_7patches.xml"}) {
    INFO(name);
    const VolumeFile f = read_volume_file(geometry(name));
    const MultiVolume& d = f.domain;
    REQUIRE(d.num_patches() == 7);
    // Eight cubes of the 2 x 2 x 2 grid share 12 faces; the missing octant takes 3 of them.
    REQUIRE(d.interfaces.size() == 9);
    const std::vector<VolumeInterface> found = find_face_interfaces(d);
    REQUIRE(found.size() == 9);
    int turned = 0;
    for (const VolumeInterface& i : d.interfaces) {
      VolumeInterface g;
      REQUIRE(match_faces(d, i.a, i.b, 1e-12, g));
      CHECK(g.same_order == i.same_order);
      CHECK(g.reverse_first == i.reverse_first);
      CHECK(g.reverse_second == i.reverse_second);
      turned += !i.same_order || i.reverse_first || i.reverse_second;
    }
    CHECK(turned >= 3);  // the turned cubes' faces exchange or reverse coordinates
    CHECK(exterior_faces(d).size() == 7 * 6 - 2 * 9);
    REQUIRE(d.boundaries.size() == 2);
    CHECK(d.boundaries[0].name == "reentrant");
    CHECK(d.boundaries[0].sides.size() == 3);
  }
}

TEST_CASE("The glued space on seven cubes: its dimension, and the same space as the box less its octant", "[volume][multipatch]") {
  // Per cube and direction e + p B-splines (e elements, C^(p-1)); glued C0 across the planes
  // through the origin, 2 (e + p) - 1 along each axis of the box, less the (e + p - 1)^3 that
  // live inside the octant only.
  const std::string problem = "exact = \"sin(x)*exp(y/2)*cos(z)\"\nneumann = [\"reentrant\"]";
  for (const auto& [p, e] : {std::pair{1, 2}, std::pair{2, 2}, std::pair{3, 1}}) {
    const std::string space = "degree = " + std::to_string(p) + "\nelements = " + std::to_string(e);
    const CaseDescription glued = patches_case("fichera_7patches.xml", space, problem);
    const auto s = build_space(glued);
    const int n = 2 * (e + p) - 1, inside = e + p - 1;
    INFO("p = " << p << ", " << e << " elements per cube");
    CHECK(s->mesh().num_functions() == n * n * n - inside * inside * inside);
    CHECK(s->mesh().num_cells() == 7 * e * e * e);
    // The THB Fichera corner on the box (-1,1)^3 less its octant is the same space (C0 knot
    // planes through the origin): the two Galerkin solutions differ by rounding only.
    const CaseDescription box = load_case_text("[geometry]\ntype = \"fichera\"\n[space]\nfamily = \"thb\"\n" + space +
                                                   "\n[problem]\nexact = \"sin(x)*exp(y/2)*cos(z)\"\nneumann = [\"hole\"]",
                                               "box.toml");
    const auto t = build_space(box);
    REQUIRE(t->mesh().num_functions() == s->mesh().num_functions());
    PoissonSolveOptions options;
    const rounding_test::Reproduction a = rounding_test::solve_reproducing(s->mesh(), s->geometry(), glued.problem, options);
    const rounding_test::Reproduction b = rounding_test::solve_reproducing(t->mesh(), t->geometry(), box.problem, options);
    INFO("H1 errors " << a.errors.h1_semi << " and " << b.errors.h1_semi << ", bounds " << a.h1_bound() << " + " << b.h1_bound());
    CHECK(std::abs(a.errors.h1_semi - b.errors.h1_semi) <= a.h1_bound() + b.h1_bound());
    CHECK(std::abs(a.errors.l2 - b.errors.l2) <= a.l2_bound() + b.l2_bound());
    // The estimator runs across the turned faces as across the box's planes: the same value
    // up to what the two rounding errors of u_h can move it (an inverse inequality, 1e3 / h, as
    // in tests/test_volume_estimator.cpp).
    const ErrorIndicators ia = residual_indicators(s->mesh(), s->geometry(), a.coefficients, glued.problem);
    const ErrorIndicators ib = residual_indicators(t->mesh(), t->geometry(), b.coefficients, box.problem);
    const double h = 1.0 / e;
    CHECK(std::abs(std::sqrt(ia.total()) - std::sqrt(ib.total())) <= 1e3 / h * (a.h1_bound() + b.h1_bound()));
    CHECK(ia.jump_part > 0);
  }
}

TEST_CASE("Seven glued cubes, three turned, reproduce a triquadratic u and converge at the optimal rates", "[volume][multipatch]") {
  for (const char* name : {"fichera_7patches.txt", "fichera_7patches.xml"}) {
    INFO(name);
    const CaseDescription c = patches_case(name, "degree = 2\nelements = 2", "exact = \"x^2*y - z^2 + 3*x*y*z\"\nneumann = [\"reentrant\"]");
    const auto s = build_space(c);
    PoissonSolveOptions options;
    const rounding_test::Reproduction r = rounding_test::solve_reproducing(s->mesh(), s->geometry(), c.problem, options);
    REQUIRE_REPRODUCED(r);
  }
  for (int p : {1, 2}) {
    CaseDescription c = patches_case("fichera_7patches.txt", "degree = " + std::to_string(p) + "\nelements = 1",
                                     "exact = \"sin(x)*exp(y/2)*cos(z)\"\nneumann = [\"reentrant\"]");
    const ConvergeOutcome o = converge_study(c, 4, Ordering::kCholmodDefault, nullptr, {});
    const ConvergeLevel& last = o.levels.back();
    INFO("p = " << p << ": L2 rate " << last.l2_rate << ", H1 rate " << last.h1_rate);
    CHECK(last.l2_rate >= p + 1 - 0.2);
    CHECK(last.h1_rate >= p - 0.2);
  }
}
