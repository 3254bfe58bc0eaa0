// Volumes read from G+Smo XML and GeoPDEs text (cases/geometry_file.hpp): the files that
// scripts/write_volume_geometries.py writes from mathematics are read back as the volumes they
// describe, checked against that mathematics (the built-in thick quarter annulus; the map F of
// the distorted block, evaluated here); their labels name the right faces; a case on a file
// solves as on the built-in volume, and the patch test holds on the distorted block.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "basis/core/input_error.hpp"
#include "cases/boundary_labels.hpp"
#include "cases/case_file.hpp"
#include "cases/geometries.hpp"
#include "cases/geometry_file.hpp"
#include "cases/spline_space.hpp"
#include "rounding_bounds.hpp"
#include "cli_sandbox.hpp"
#include "solver/poisson_solver.hpp"
#include "studies/pipeline.hpp"

using namespace knotwork;

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

std::string geometry(const std::string& name) { return std::string(KNOTWORK_SOURCE_DIR) + "/cases/geometries/" + name; }

// A case on the volume file `file` (absolute path), with the given [space] and [problem].
CaseDescription file_case(const std::string& file, const std::string& space, const std::string& problem) {
  return load_case_text("[geometry]\nfile = \"" + file + "\"\n[space]\n" + space + "\n[problem]\n" + problem, "volume.toml");
}

}  // namespace

TEST_CASE("The thick quarter ring's files are the built-in thick quarter annulus", "[volume][files]") {
  // The script computes the control points from cos(pi/4) in Python, the built-in volume from
  // 1/sqrt(2) in C++: each of the few coordinates agrees to an ulp or two of its size (<= 2).
  const NurbsVolume built = thick_quarter_annulus_volume(1, 2, 1);
  for (const char* name : {"thick_quarter_ring.xml", "thick_quarter_ring.txt"}) {
    INFO(name);
    REQUIRE(geometry_file_dimension(geometry(name)) == 3);
    const VolumeFile f = read_volume_file(geometry(name));
    for (int k = 0; k < 3; ++k) {
      CHECK(f.volume.bases[k].degree() == built.bases[k].degree());
      CHECK(f.volume.bases[k].knots() == built.bases[k].knots());
    }
    REQUIRE(f.volume.control_points.rows() == built.control_points.rows());
    CHECK((f.volume.control_points - built.control_points).cwiseAbs().maxCoeff() <= 4 * kEps);
    CHECK((f.volume.weights - built.weights).cwiseAbs().maxCoeff() <= 2 * kEps);
    // The labels by where the faces lie: inner r = 1 is u = 0 (face 1), outer u = 1 (2), the
    // symmetry planes v = 0 and v = 1 (3, 4), the base w = 0 (5) and the lid w = 1 (6).
    REQUIRE(f.boundaries.size() == 5);
    const std::array<std::pair<const char*, std::vector<int>>, 5> expected{
        {{"inner", {1}}, {"outer", {2}}, {"symmetry", {3, 4}}, {"base", {5}}, {"lid", {6}}}};
    for (size_t b = 0; b < expected.size(); ++b) {
      CHECK(f.boundaries[b].name == expected[b].first);
      std::vector<int> sides;
      for (const PatchSideRef& s : f.boundaries[b].sides) sides.push_back(s.side);
      CHECK(sides == expected[b].second);
    }
  }
}

TEST_CASE("The distorted block's files evaluate to the map they were written from", "[volume][files]") {
  // F(u, v, w) = (u + v w / 5, v + u^2 / 4, w + u v / 10) and its Jacobian, against de Boor's
  // evaluation of the read volume: sums of at most 3 x 2 x 2 terms of size <= 1.25, so rounding
  // stays below 64 eps. A wrong numbering of the control points (u fastest) moves points by
  // far more: the interior knots make every direction's count different.
  for (const char* name : {"distorted_block.xml", "distorted_block.txt"}) {
    INFO(name);
    const VolumeFile f = read_volume_file(geometry(name));
    CHECK(f.boundaries.empty());
    for (double u : {0.0, 0.3, 0.5, 0.77, 1.0})
      for (double v : {0.0, 0.2, 1.0 / 3, 0.9})
        for (double w : {0.0, 0.45, 1.0}) {
          const VolumePointDerivatives p = volume_point_derivatives(f.volume, {u, v, w});
          const Eigen::Vector3d x(u + v * w / 5, v + u * u / 4, w + u * v / 10);
          Eigen::Matrix3d j;
          j << 1, w / 5, v / 5, u / 2, 1, 0, v / 10, u / 10, 1;
          CHECK((p.x - x).cwiseAbs().maxCoeff() <= 64 * kEps);
          CHECK((p.jacobian - j).cwiseAbs().maxCoeff() <= 64 * kEps);
        }
  }
}

TEST_CASE("A case on a volume file solves as on the built-in volume, its labels naming the faces", "[volume][files]") {
  // The same problem as cases/thick_quarter_annulus.toml, Neumann data on the file's "outer"
  // and "lid" (the built-in "right" and "back"). The volumes agree to a few ulps (above), a
  // perturbation within the solve's backward error, so the two solutions differ by at most
  // twice the rounding bound of one (tests/rounding_bounds.hpp).
  const std::string space = "degree = 2\nelements = 3\n";
  const std::string u = "exact = \"sin(x) * exp(y / 2) * (1 + z * z / 3)\"\n";
  const CaseDescription built = load_case_text("[geometry]\ntype = \"thick_quarter_annulus\"\n[space]\n" + space +
                                                   "[problem]\n" + u + "neumann = [\"right\", \"back\"]\n",
                                               "built.toml");
  const auto a = build_space(built);
  const rounding_test::Reproduction ra = rounding_test::solve_reproducing(a->mesh(), a->geometry(), built.problem);
  for (const char* name : {"thick_quarter_ring.xml", "thick_quarter_ring.txt"}) {
    INFO(name);
    const CaseDescription c = file_case(geometry(name), space, u + "neumann = [\"outer\", \"lid\"]\n");
    REQUIRE(c.is_volume());
    const BoundaryLabels labels = boundary_labels(c);
    CHECK(labels.resolve("symmetry") == std::vector<int>{2, 3});
    CHECK(labels.resolve("lid") == labels.resolve("back"));
    const auto b = build_space(c);
    REQUIRE(b->mesh().num_functions() == a->mesh().num_functions());
    const PoissonSolution sb = solve_poisson(b->mesh(), b->geometry(), c.problem, PoissonSolveOptions{});
    const double bound = 2 * ra.h1_bound();
    INFO("H1 errors " << ra.errors.h1_semi << " and " << sb.errors->h1_semi << ", bound on the difference " << bound);
    CHECK(std::abs(ra.errors.h1_semi - sb.errors->h1_semi) <= bound);
  }
}

TEST_CASE("The patch test on the distorted block read from a file", "[volume][files]") {
  // u = 1 + x - 2y + 3z is harmonic, and u o F is a polynomial of degree (2, 1, 1): it lies in
  // the B-spline space of degree 2 on the block's knots, so the Galerkin solution is u up to
  // the quadrature of the rational integrands (the inverse Jacobian) and rounding; 12 points
  // take the first below the second (as on the thick annulus, tests/test_volume_cases.cpp).
  for (const char* name : {"distorted_block.xml", "distorted_block.txt"}) {
    INFO(name);
    const CaseDescription c = file_case(geometry(name), "degree = 2\nelements = 2\nquadrature_points = 12\n",
                                        "exact = \"1 + x - 2*y + 3*z\"\n");
    const auto space = build_space(c);
    PoissonSolveOptions options;
    options.quadrature = c.quadrature;
    const rounding_test::Reproduction r = rounding_test::solve_reproducing(space->mesh(), space->geometry(), c.problem, options);
    INFO("L2 " << r.errors.l2 << " (bound " << r.l2_bound() << "), H1 " << r.errors.h1_semi << " (bound " << r.h1_bound() << ")");
    CHECK(r.reproduced());
  }
}

TEST_CASE("Volume files: what is refused, in one line", "[volume][files]") {
  const cli_test::Sandbox box;
  const auto write = [&](const std::string& name, const std::string& text) { return box.file(name, text).string(); };
  const std::string cube = "2 2 2\n0 0 1 1\n0 0 1 1\n0 0 1 1\n0 1 0 1 0 1 0 1\n0 0 1 1 0 0 1 1\n0 0 0 0 1 1 1 1\n1 1 1 1 1 1 1 1\n";
  const auto refused = [](const std::string& path, const std::string& what) {
    try {
      read_volume_file(path);
      FAIL("accepted " << path);
    } catch (const InputError& e) {
      INFO(e.what());
      CHECK(std::string(e.what()).find(what) != std::string::npos);
    }
  };
  // A side beyond the six faces; a second patch announced and missing; a planar patch where a volume is read.
  refused(write("side.txt", "3 3 1\nPATCH 1\n1 1 1\n" + cube + "BOUNDARY walls\n1\n1 7\n"),
          "side.txt: line 14: boundary walls (patch side): side 7 does not exist (sides are 1 to 6)");
  refused(write("two.txt", "3 3 2 1 0\nPATCH 1\n1 1 1\n" + cube), "two.txt: the file ends where patch 2 degrees should be");
  refused(write("planar.txt", "3 3 1\nPATCH 1\n1 1\n2 2\n"), "planar.txt: line 3: patch 1 degrees: expected 3 integers, found 2");
  refused(write("planar.xml", "<xml>\n<Geometry type=\"TensorBSpline2\" id=\"0\"/>\n<MultiPatch parDim=\"3\">"
                              "<patches type=\"id_range\">0 0</patches></MultiPatch>\n</xml>\n"),
          "planar.xml: line 2: Geometry id 0 has type \"TensorBSpline2\" where a volume (TensorBSpline3 or TensorNurbs3) "
          "is read: a planar patch");
  CHECK(geometry_file_dimension(write("plain.txt", "2 2 1\n")) == 2);
  // A planar reader given a volume says so.
  try {
    read_geometry_file(geometry("distorted_block.txt"));
    FAIL("a volume read as planar patches");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("a 3D (volume) geometry where a planar one (ndim = 2) is read") != std::string::npos);
  }
}
