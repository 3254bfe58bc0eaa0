// `knotwork basis` on T-mesh files and on collections given explicitly, solving on an
// explicit collection (refused when it is not semi-regular), and JSON input files.
#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <random>

#include "basis/g1/g1_space.hpp"
#include "basis/g1/quad_mesh.hpp"
#include "cases/json_input.hpp"
#include "tests/cli_sandbox.hpp"

using namespace cli_test;
using namespace knotwork;

namespace {

const std::string kSource = KNOTWORK_SOURCE_DIR;

bool has(const std::string& text, const std::string& what) { return text.find(what) != std::string::npos; }

}  // namespace

TEST_CASE("basis on a T-mesh file builds the semi-regular collection on it", "[cli][semi-regular]") {
  Sandbox box;
  // 8 x 8 biquadratic grid: (8+2)^2 = 100 functions. The ray x = 5/16, y in [0, 3/8] adds 3
  // interior edges of its own and splits 3 horizontal ones (+6 edges) at 2 crossings and a
  // T-node (+3 vertices): 3*6 - 5*3 = +3. The segment y = 11/16, x in [1/4, 3/4] adds 4 edges,
  // splits 5 vertical ones (+9) at 5 new vertices: 3*9 - 5*5 = +2. Weller's count: 105.
  const Result r = box.run("basis --json --export c.json " + kSource + "/cases/tmeshes/ray_and_segment.toml");
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* expected : {"\"functions\": 105", "\"cells\": 71", "\"input_cells\": 71", "\"partition_reached\": true",
                               "\"semi_regular\": true", "\"violations\": []", "\"rank\": 105",
                               "\"dimension_formula\": 105", "\"dimension_bruteforce\": 105", "\"extended_segments\": 0"})
    REQUIRE(has(r.out, expected));
  // The export reads back as the same collection.
  const Result back = box.run("basis --json c.json");
  INFO(back.err);
  REQUIRE(back.code == 0);
  for (const char* expected : {"\"functions\": 105", "\"cells\": 71", "\"semi_regular\": true", "\"rank\": 105"})
    REQUIRE(has(back.out, expected));
}

TEST_CASE("basis on a T-mesh without a semi-regular collection says why", "[cli][semi-regular]") {
  Sandbox box;
  // The hierarchical bicubic mesh fails Lemma 3.4 at the four crossings inside the refined
  // block, so no semi-regular collection lives on it; the construction extends instead.
  const Result r = box.run("basis --json " + kSource + "/cases/tmeshes/hierarchical.toml");
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* expected : {"\"partition_reached\": false", "\"semi_regular\": true", "Lemma 3.4", "extended to"})
    REQUIRE(has(r.out, expected));
  const Result text = box.run("basis " + kSource + "/cases/tmeshes/hierarchical.toml");
  REQUIRE(has(text.out, "NOT reached"));
  // Smoothness other than C^(d-1) has no knot-segment collection: refused with the field named.
  box.file("c1.toml", "degree = 3\nsmoothness = [1, 1]\ncells = [[0, 0, 1, 1]]\n");
  const Result s = box.run("basis c1.toml");
  REQUIRE(s.code != 0);
  REQUIRE(has(s.err, "c1.toml: smoothness"));
}

TEST_CASE("basis on a collection that is not semi-regular names the cells", "[cli][semi-regular]") {
  Sandbox box;
  const Result r = box.run("basis --json " + kSource + "/cases/collections/not_semi_regular.json");
  INFO(r.err);
  REQUIRE(r.code == 0);
  REQUIRE(has(r.out, "\"semi_regular\": false"));
  REQUIRE(has(r.out, "cell [0.375,0.5]x[0.375,0.5]: 8 B-splines are alive, not 9"));
  REQUIRE(has(r.out, "\"functions\": 104"));
}

TEST_CASE("run on an explicit collection, refused unless --allow-non-semi-regular", "[cli][semi-regular]") {
  Sandbox box;
  const Result good = box.run("run -q --no-output --json " + kSource + "/cases/square_collection.toml");
  INFO(good.err);
  REQUIRE(good.code == 0);
  REQUIRE(has(good.out, "\"dofs\": 105"));

  const std::string bad_case = "[geometry]\ntype = \"rectangle\"\n[space]\nfamily = \"knot_segments\"\ncollection = \"" +
                               kSource + "/cases/collections/not_semi_regular.json\"\n[problem]\nexact = \"x*y\"\n";
  expect_rejected(box, bad_case, {"bad.toml", "[space] collection", "not semi-regular", "cell [0.375,0.5]x[0.375,0.5]",
                                  "--allow-non-semi-regular"});
  box.file("bad.toml", bad_case);
  const Result forced = box.run("run -q --no-output bad.toml --allow-non-semi-regular");
  INFO(forced.err);
  REQUIRE(forced.code == 0);
  REQUIRE(has(forced.err, "may be linearly dependent"));
  // Adaptive refinement needs a semi-regular start, whatever the flags.
  expect_rejected(box, bad_case, {"bad.toml", "semi-regular"}, "", "adapt");
}

TEST_CASE("an explicit collection on the L-shape: cells must not straddle the geometry's fold", "[cli][semi-regular][geometry]") {
  // The one-patch L-shape is bilinear on each side of its C0 fold u = 1/2, so a linear u is
  // in the degree-1 space whose cells end at the fold: reproduced to rounding. Cells across
  // the fold would be mapped by one side's polynomial: refused, naming the cell and the knot.
  Sandbox box;
  auto lshape_case = [&](const std::string& breaks) {
    box.file("coll.json", R"({"degree": [1, 1], "functions": [)"
                          R"({"x": [0, 0, )" + breaks + R"(], "y": [0, 0, 1]}, {"x": [0, 0, )" + breaks +
                          R"(], "y": [0, 1, 1]}, {"x": [0, )" + breaks + R"(, 1], "y": [0, 0, 1]}, {"x": [0, )" +
                          breaks + R"(, 1], "y": [0, 1, 1]}, {"x": [)" + breaks + R"(, 1, 1], "y": [0, 0, 1]}, {"x": [)" +
                          breaks + R"(, 1, 1], "y": [0, 1, 1]}]})");
    return std::string("[geometry]\ntype = \"lshape\"\n[space]\nfamily = \"knot_segments\"\ncollection = \"coll.json\"\n"
                       "[problem]\nexact = \"1 + 2*x - 3*y\"\n");
  };
  box.file("fold.toml", lshape_case("0.5"));
  const Result fold = box.run("run -q --no-output --json fold.toml");
  INFO(fold.err);
  REQUIRE(fold.code == 0);
  REQUIRE(json_number_of(fold.out, "l2_error") < 1e-12);
  expect_rejected(box, lshape_case("0.4"),
                  {"bad.toml", "[space] collection", "coll.json", "straddles the geometry's knot u = 0.5"});
}

TEST_CASE("bad input: collection files", "[cli][bad-input][semi-regular]") {
  Sandbox box;
  auto collection_case = [&](const std::string& json) {
    box.file("coll.json", json);
    return std::string("[geometry]\ntype = \"rectangle\"\n[space]\nfamily = \"knot_segments\"\ncollection = \"coll.json\"\n"
                       "[problem]\nexact = \"x\"\n");
  };
  const std::string one = R"({"degree": [1, 1], "functions": [)";
  expect_rejected(box, collection_case(one + R"({"x": [0, 1], "y": [0, 0, 1]}]})"),
                  {"coll.json", "functions[0] x", "degree+2 = 3"});
  expect_rejected(box, collection_case(one + R"({"x": [0, 1, 0.5], "y": [0, 0, 1]}]})"),
                  {"coll.json", "functions[0] x", "non-decreasing"});
  expect_rejected(box, collection_case(one + R"({"x": [0, 0, 1], "y": [0, 0, 1]}, {"x": [0, 0, 1], "y": [0, 0, 1]}]})"),
                  {"bad.toml", "collection", "twice"});
  expect_rejected(box, collection_case(one + R"({"x": [0, 0, 2], "y": [0, 0, 1]}]})"),
                  {"bad.toml", "collection", "parameter domain"});
  expect_rejected(box, collection_case(one + R"({"x": [0, 0, 1], "y": [0, 0, 1]}, ]})"),
                  {"coll.json:1:", "JSON syntax error"});
  expect_rejected(box, collection_case(R"({"degree": null, "functions": []})"), {"coll.json", "degree", "null"});
  expect_rejected(box, collection_case(R"({"degre": [1, 1], "functions": []})"), {"coll.json", "did you mean 'degree'"});
  const std::string with_elements =
      replace(collection_case(one + R"({"x": [0, 0, 1], "y": [0, 0, 1]}]})"), "collection =", "elements = 4\ncollection =");
  expect_rejected(box, with_elements, {"bad.toml", "[space] elements", "explicit collection"});
  expect_rejected(box, replace(kGood, "degree = 2", "degree = 2\ncollection = \"coll.json\""),
                  {"bad.toml", "[space] collection", "knot_segments"});
  expect_rejected(box, collection_case(one + R"({"x": [0, 0, 1], "y": [0, 0, 1]}]})"), {"--degree"}, "--degree 3");
  expect_rejected(box, collection_case(one + R"({"x": [0, 0, 1], "y": [0, 0, 1]}]})"),
                  {"bad.toml", "[space] collection", "convergence"}, "", "converge");
}

TEST_CASE("a case written as JSON solves exactly like its TOML twin", "[cli][json]") {
  Sandbox box;
  box.file("sq.toml", kGood);
  box.file("sq.json", R"J({
    "geometry": {"type": "rectangle"},
    "space": {"degree": 2, "elements": 4},
    "problem": {"exact": "sin(pi*x)*sin(pi*y)"}
  })J");
  const Result t = box.run("run -q --no-output --json sq.toml");
  const Result j = box.run("run -q --no-output --json sq.json");
  INFO(t.err << j.err);
  REQUIRE(t.code == 0);
  REQUIRE(j.code == 0);
  auto l2 = [](const std::string& out) {
    const auto at = out.find("\"l2_error\": ");
    REQUIRE(at != std::string::npos);
    return std::stod(out.substr(at + 12));
  };
  // The same problem; only the threads' summation order may differ in the last bits.
  REQUIRE(l2(t.out) > 0);
  REQUIRE(std::abs(l2(t.out) - l2(j.out)) <= 1e-12 * l2(t.out));
  // JSON syntax errors carry line and column.
  box.file("broken.json", "{\n  \"geometry\": {\"type\": \"rectangle\"},\n  \"space\": {\"degree\": 2 \"elements\": 4}\n}\n");
  const Result b = box.run("run -q broken.json");
  REQUIRE(b.code != 0);
  REQUIRE(has(b.err, "broken.json:3:"));
  REQUIRE(has(b.err, "JSON syntax error"));
  box.file("dup.json", R"({"geometry": {"type": "rectangle"}, "geometry": {}})");
  REQUIRE(has(box.run("run -q dup.json").err, "duplicate key \"geometry\""));
}

TEST_CASE("nothing typed into a JSON collection or T-mesh file crashes knotwork", "[cli][bad-input][fuzz]") {
  // Random edits of valid JSON inputs: exit 0 or a one-line error, never a signal.
  Sandbox box;
  std::mt19937 rng(2027);
  const std::string alphabet = "[]{}:,\"\\.-+0123456789eEnulltrufas \n/";
  const std::vector<std::string> seeds = {
      R"({"degree": [1, 1], "functions": [{"x": [0, 0, 0.5], "y": [0, 0, 1]}, {"x": [0, 0.5, 1], "y": [0, 0, 1]},)"
      R"( {"x": [0.5, 1, 1], "y": [0, 0, 1]}, {"x": [0, 0, 0.5], "y": [0, 1, 1]}, {"x": [0, 0.5, 1], "y": [0, 1, 1]},)"
      R"( {"x": [0.5, 1, 1], "y": [0, 1, 1]}]})",
      R"({"degree": [2, 2], "cells": [[0, 0, 1, 1], [1, 0, 2, 1], [0, 1, 2, "3/2"], [0, "3/2", 2, 2]]})"};
  fuzz(box, 120, [&](int trial) {
    std::string text = seeds[trial % seeds.size()];
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int e = 0; e < edits; ++e) random_edit(text, rng, alphabet);
    box.file("fuzz.json", text);
    return std::pair{std::string("basis --json fuzz.json"), text};
  });
}

TEST_CASE("basis --g1: dimensions of the shipped meshes, and bad input", "[cli][g1]") {
  Sandbox box;
  const std::string three = kSource + "/cases/meshes/three_quads.obj";
  const Result r = box.run("basis --json --g1 " + three + " --degree 4 --split-smoothness 1");
  INFO(r.err);
  REQUIRE(r.code == 0);
  REQUIRE(has(r.out, "\"dimension\": 141"));
  REQUIRE(has(r.out, "\"faces\": 3"));
  const Result lin = box.run("basis --json --g1 " + three + " --degree 3 --split-smoothness 1 --gluing " + kSource +
                             "/cases/meshes/three_quads_linear.json");
  INFO(lin.err);
  REQUIRE(has(lin.out, "\"dimension\": 72"));
  // The split pentagonal prism: the analysis-suitable data skew its 10 failing crossings, and
  // both outputs say so; the paper's data need none.
  const std::string prism = kSource + "/cases/meshes/pentagonal_prism.obj";
  const Result skew = box.run("basis --g1 " + prism + " --gluing analysis_suitable");
  INFO(skew.err);
  REQUIRE(skew.code == 0);
  REQUIRE(has(skew.out, "10 crossings given a skewed fan (12, 13, 14, 15, 16, 18, 19, 20, 21, 22)"));
  REQUIRE(has(box.run("basis --json --g1 " + prism + " --gluing analysis_suitable").out, "\"skewed_fans\": 10"));
  REQUIRE(has(box.run("basis --json --g1 " + prism).out, "\"skewed_fans\": 0"));
  // Floating-point data (geometric data of decimal coordinates): local SVDs, and the margin
  // between the singular values kept and dropped, in both outputs.
  const std::string decimals = kSource + "/tests/bad_inputs/uses_pentagon_decimals.obj";
  const Result floating = box.run("basis --json --g1 " + decimals + " --gluing geometric --degree 5");
  INFO(floating.err);
  REQUIRE(floating.code == 0);
  REQUIRE(has(floating.out, "\"rank_method\": \"floating point, local SVDs\""));
  REQUIRE(json_number_of(floating.out, "svd_smallest_kept") > 10 * json_number_of(floating.out, "svd_largest_dropped"));
  REQUIRE(json_number_of(floating.out, "functions") == json_number_of(floating.out, "dimension"));
  REQUIRE(has(box.run("basis --g1 " + decimals + " --gluing geometric --degree 5").out, "singular values kept down to"));

  auto rejected = [&](const std::string& args, const std::vector<std::string>& mentions) {
    INFO("basis " << args);
    expect_one_line_error(box.run("basis " + args), mentions);
  };
  rejected("--g1 " + three + " --degree 1", {"--degree"});
  rejected("--g1 " + three + " --degree 3 --split-smoothness 3", {"--split-smoothness"});
  rejected("--g1 " + three + " --split-smoothness -1", {"--split-smoothness"});
  box.file("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  rejected("--g1 tri.obj", {"tri.obj:4", "only quadrilaterals"});
  box.file("g.json", R"({"gluing": [{"edge": [1, 7], "a": 0, "b": -1, "c": 1}]})");
  rejected("--g1 " + three + " --gluing g.json", {"g.json", "gluing[0].edge", "[1, 7] is not an edge"});
  box.file("g.json", R"({"gluing": [{"edge": [1, 2], "a": "-1/3", "b": -1, "c": 1}]})");
  rejected("--g1 " + three + " --gluing g.json", {"g.json", "no data for the interior edge"});
  box.file("g.json", R"({"gluing": [{"edge": [1, 2], "a": 0, "b": -1, "c": [[0], [1]]},
                                    {"edge": [1, 3], "a": 0, "b": -1, "c": 1}, {"edge": [1, 4], "a": 0, "b": -1, "c": 1}]})");
  rejected("--g1 " + three + " --gluing g.json", {"g.json", "c is identically 0 on [0, 1/2]"});
  // a = 0 on all three edges at a valence-3 vertex: the jets do not close up.
  box.file("g.json", R"({"gluing": [{"edge": [1, 2], "a": 0, "b": -1, "c": 1},
                                    {"edge": [1, 3], "a": 0, "b": -1, "c": 1}, {"edge": [1, 4], "a": 0, "b": -1, "c": 1}]})");
  rejected("--g1 " + three + " --gluing g.json", {"g.json", "vertex 1 (valence 3): Condition 3.1 fails"});
  box.file("g.json", R"({"gluing": [{"edge": [2, 5], "a": 0, "b": -1, "c": 1}]})");
  rejected("--g1 " + three + " --gluing g.json", {"boundary edge"});
  rejected("--g1 " + three + " " + three, {"one input"});
}

TEST_CASE("basis --g1: the basis in JSON, --export per-face coefficients, --vtk surface and functions", "[cli][g1]") {
  Sandbox box;
  const std::string three = kSource + "/cases/meshes/three_quads.obj";
  const Result r = box.run("basis --json --g1 " + three + " --degree 4 --split-smoothness 1 --export basis.json "
                           "--vtk basis.vtu --show vertex:1");
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* field : {"\"functions\": 141", "\"rank\": 141", "\"vertex\": 30", "\"edge\": 63", "\"face\": 48",
                            "\"coupled\": 0", "\"dimension_formula\": null", "\"vtk_functions\": 6"})
    REQUIRE(has(r.out, field));
  REQUIRE(has(r.out, "\"g1_residual_max\": "));

  // The export: every function as per-face arrays of (2k - r + 1)^2 = 64 coefficients,
  // and each one satisfies the G1 conditions of the mesh read independently here.
  const JsonValue root = read_json_file((box.dir() / "basis.json").string());
  const JsonValue* functions = nullptr;
  for (const auto& [key, value] : root.members)
    if (key == "functions") functions = &value;
  REQUIRE(functions);
  REQUIRE(functions->items.size() == 141);
  const QuadMesh mesh = QuadMesh::read_obj(three);
  const auto rows = g1_condition_rows(mesh, symmetric_gluing(mesh), 4, 1);
  std::map<std::string, int> kinds;
  for (const auto& f : functions->items) {
    std::map<long, double> x;
    double scale = 0;
    for (const auto& [key, value] : f.members) {
      if (key == "kind") ++kinds[value.text];
      if (key != "faces") continue;
      for (const auto& face : value.items) {
        REQUIRE(face.members.size() == 2);
        const int index = static_cast<int>(face.members[0].value.number) - 1;
        REQUIRE(index >= 0);
        REQUIRE(index < 3);
        const auto& c = face.members[1].value.items;
        REQUIRE(c.size() == 64);
        for (int i = 0; i < 64; ++i) {
          x[index * 64L + i] = c[i].number;
          scale = std::max(scale, std::abs(c[i].number));
        }
      }
    }
    REQUIRE(scale > 0);
    for (const auto& row : rows) {
      double s = 0, size = 0;
      for (const auto& [col, a] : row) {
        size += std::abs(a);
        if (x.count(col)) s += a * x[col];
      }
      REQUIRE(std::abs(s) <= 1e-11 * size * scale);
    }
  }
  REQUIRE(kinds["vertex"] == 30);
  REQUIRE(kinds["edge"] == 63);
  REQUIRE(kinds["face"] == 48);

  const std::string vtu = slurp(box.dir() / "basis.vtu");
  REQUIRE(has(vtu, "HigherOrderDegrees"));
  for (int i = 1; i <= 6; ++i) REQUIRE(has(vtu, "vertex1_" + std::to_string(i)));
  REQUIRE(!has(vtu, "vertex1_7"));

  // Closed surface: Theorem 7.1 applies and agrees with the null space.
  const Result cube = box.run("basis --json --g1 " + kSource + "/cases/meshes/cube.obj --degree 4 --split-smoothness 1");
  REQUIRE(has(cube.out, "\"dimension\": 192"));
  REQUIRE(has(cube.out, "\"dimension_formula\": 192"));

  auto rejected = [&](const std::string& args, const std::vector<std::string>& mentions) {
    INFO("basis " << args);
    expect_one_line_error(box.run("basis " + args), mentions);
  };
  rejected("--g1 " + three + " --vtk out.txt", {"out.txt", "--vtk", ".vtu"});
  rejected("--g1 " + three + " --vtk bad.vtu --show vertex:99", {"--show vertex:99", "vertices 1..7"});
  rejected("--g1 " + three + " --vtk bad.vtu --show edge:2-3", {"no edge between vertices 2 and 3"});
  rejected("--g1 " + three + " --vtk bad.vtu --show corner", {"--show corner", "expected"});
  rejected("--g1 " + three + " --export no/such/dir/basis.json", {"no/such/dir/basis.json", "--export", "does not exist"});
  rejected("--g1 " + three + " --vtk no/such/dir/s.vtu", {"no/such/dir/s.vtu", "--vtk", "does not exist"});
  rejected("--g1 " + three + " --show vertex:2", {"--show vertex:2", "needs --vtk"});
  // Floating-point data whose numerical rank is not clear-cut (geometric data on a torus of
  // 240 faces: its crossings hold Condition 3.2 only to rounding): refused, with the margin.
  std::string torus;
  for (int j = 0; j < 12; ++j)
    for (int i = 0; i < 20; ++i) {
      const double a = 2 * M_PI * i / 20, b = 2 * M_PI * j / 12;
      torus += "v " + std::to_string((3 + std::cos(b)) * std::cos(a)) + " " + std::to_string((3 + std::cos(b)) * std::sin(a)) +
               " " + std::to_string(std::sin(b)) + "\n";
    }
  for (int j = 0; j < 12; ++j)
    for (int i = 0; i < 20; ++i) {
      const int i1 = (i + 1) % 20, j1 = (j + 1) % 12;
      torus += "f " + std::to_string(j * 20 + i + 1) + " " + std::to_string(j * 20 + i1 + 1) + " " +
               std::to_string(j1 * 20 + i1 + 1) + " " + std::to_string(j1 * 20 + i + 1) + "\n";
    }
  box.file("torus.obj", torus);
  rejected("--g1 torus.obj --gluing geometric", {"torus.obj", "--gluing geometric", "not clear-cut", "a factor 10 apart"});
  REQUIRE(!fs::exists(box.dir() / "bad.vtu"));
  for (const auto& entry : fs::directory_iterator(box.dir())) REQUIRE(!has(entry.path().filename().string(), "partial"));
}

TEST_CASE("nothing typed into a quad mesh or gluing file crashes knotwork basis --g1", "[cli][g1][bad-input][fuzz]") {
  // Random edits of the shipped OBJ and gluing files: exit 0 or a one-line error, never a signal.
  Sandbox box;
  std::mt19937 rng(2028);
  const std::string obj = slurp(kSource + "/cases/meshes/three_quads.obj");
  const std::string gluing = slurp(kSource + "/cases/meshes/three_quads_linear.json");
  fuzz(box, 120, [&](int trial) {
    const bool edit_mesh = trial % 2 == 0;
    std::string text = edit_mesh ? obj : gluing;
    const std::string alphabet = edit_mesh ? "vf 0123456789.-e\n/#" : "[]{}:,\"\\.-+0123456789eEnulltrufas \n/";
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int e = 0; e < edits; ++e) random_edit(text, rng, alphabet);
    box.file("fuzz.obj", edit_mesh ? text : obj);
    box.file("fuzz.json", edit_mesh ? gluing : text);
    return std::pair{std::string("basis --json --g1 fuzz.obj --degree 3 --split-smoothness 1 --gluing fuzz.json"), text};
  });
}

// A number printed in the JSON object by `key`.

TEST_CASE("basis --pt: the PT-spline basis of a T-mesh, checked, exported, and bad input", "[cli][pt]") {
  Sandbox box;
  const Result r = box.run("basis --pt --json --export pt.json " + kSource + "/cases/tmeshes/hierarchical.toml");
  INFO(r.err);
  REQUIRE(r.code == 0);
  // The hierarchical bicubic mesh: 61 functions (the brute-force count, an independent algorithm).
  REQUIRE(json_number_of(r.out, "functions") == 61);
  REQUIRE(json_number_of(r.out, "dimension_bruteforce") == 61);
  REQUIRE(json_number_of(r.out, "rank") == 61);
  REQUIRE(json_number_of(r.out, "max_smoothness_residual") <= 1e-11);
  REQUIRE(json_number_of(r.out, "min_bernstein_coefficient") >= 0);  // Prop. 1
  // The minimal extension: T itself is an LR-mesh (every l-edge of the hierarchical mesh
  // splits a B-spline when inserted), so nothing is extended and the LR B-splines are the basis.
  REQUIRE(has(r.out, "\"extension\": \"minimal\""));
  REQUIRE(json_number_of(r.out, "extended_edges") == 0);
  // The full extension reaches the same dimension through extended edges.
  const Result full = box.run("basis --pt --json --extension horizontal " + kSource + "/cases/tmeshes/hierarchical.toml");
  REQUIRE(json_number_of(full.out, "functions") == 61);
  REQUIRE(json_number_of(full.out, "rank") == 61);
  REQUIRE(json_number_of(full.out, "extended_edges") > 0);
  // Diagonalizable (an ordering of its T l-edges keeps 4 vertices on each), so the formula
  // applies and must agree with the brute force.
  REQUIRE(has(r.out, "\"diagonalizable\": true"));
  REQUIRE(json_number_of(r.out, "dimension_formula") == 61);
  const std::string exported = slurp(box.dir() / "pt.json");
  size_t exported_functions = 0;  // one "bernstein" list per function
  for (size_t at = exported.find("\"bernstein\""); at != std::string::npos; at = exported.find("\"bernstein\"", at + 1))
    ++exported_functions;
  REQUIRE(exported_functions == 61);
  // Nothing extended: the functions are the LR B-splines with their weights, a partition of
  // unity (as evaluated by the command, at sample points of every cell).
  const Result weighted = box.run("basis --pt --json --no-prop1 " + kSource + "/cases/tmeshes/hierarchical.toml");
  REQUIRE(json_number_of(weighted.out, "partition_of_unity_error") < 1e-12);
  // Without Prop. 1 the EEE combinations of the full extension change sign.
  const Result raw = box.run("basis --pt --json --no-prop1 --extension horizontal " + kSource + "/cases/tmeshes/hierarchical.toml");
  REQUIRE(json_number_of(raw.out, "min_bernstein_coefficient") < 0);
  // The pinwheel T-cycle is not diagonalizable; the full extension is, by the paper's Lemma 2
  // argument (its vertical T l-edges no longer meet one another), and so is the minimal one here.
  for (const std::string extension : {"auto", "horizontal", "diagonalizable"}) {
    const Result pw = box.run("basis --pt --json --extension " + extension + " " + kSource + "/cases/tmeshes/pinwheel_special.toml");
    INFO(extension << ": " << pw.err);
    REQUIRE(has(pw.out, "\"diagonalizable\": false"));
    REQUIRE(has(pw.out, "\"extension_diagonalizable\": true"));
    REQUIRE(json_number_of(pw.out, "functions") == 30);
  }
  // Dokken-Lyche-Pettersen's LR-mesh: 82 LR B-splines for dimension 81 (test_lr_and_hb);
  // one is dropped as dependent, nothing is extended (the paper's Example 9).
  const Result dlp = box.run("basis --pt --json " + kSource + "/cases/tmeshes/lr_dependent_dlp.toml");
  REQUIRE(json_number_of(dlp.out, "functions") == 81);
  REQUIRE(json_number_of(dlp.out, "rank") == 81);
  REQUIRE(json_number_of(dlp.out, "local_bsplines") == 82);
  REQUIRE(json_number_of(dlp.out, "dropped_dependent") == 1);
  REQUIRE(json_number_of(dlp.out, "extended_edges") == 0);
  // Bad input: one line naming what is wrong, nothing written.
  expect_one_line_error(box.run("basis --pt --extension diagonal " + kSource + "/cases/tmeshes/hierarchical.toml"),
                        {"--extension", "diagonal"});
  box.file("overlap.toml", "degree = [2, 2]\ncells = [[0, 0, 1, 1], [\"1/2\", 0, 2, 1]]\n");
  expect_one_line_error(box.run("basis --pt --export never.json overlap.toml"), {"overlap.toml", "overlap"});
  REQUIRE(!fs::exists(box.dir() / "never.json"));
  // ParaView output: the T-mesh with the chosen functions as exact Bezier fields.
  const Result v = box.run("basis --pt --json --vtk f.vtu --show 0,7 " + kSource + "/cases/tmeshes/ray_and_segment.toml");
  REQUIRE(v.code == 0);
  const std::string vtu = slurp(box.dir() / "f.vtu");
  REQUIRE(has(vtu, "function_0"));
  REQUIRE(has(vtu, "function_7"));
  REQUIRE(has(vtu, "HigherOrderDegrees"));
  expect_one_line_error(box.run("basis --pt --vtk g.vtu --show 3,x " + kSource + "/cases/tmeshes/ray_and_segment.toml"),
                        {"--show", "'x'"});
  REQUIRE(!fs::exists(box.dir() / "g.vtu"));
  box.file("degree0.toml", "degree = [0, 2]\ncells = [[0, 0, 1, 1]]\n");
  expect_one_line_error(box.run("basis --pt degree0.toml"), {"degree0.toml", "degree"});
}

TEST_CASE("family pt: run and converge on a T-mesh given as a grid plus segments", "[cli][pt]") {
  Sandbox box;
  // The T-mesh file format with a base grid and inserted segments, read by basis --pt too.
  box.file("tmesh.toml",
           "grid = { x = [0, \"1/4\", \"1/2\", \"3/4\", 1], y = [0, \"1/4\", \"1/2\", \"3/4\", 1] }\n"
           "segments = [ { direction = \"vertical\", position = \"3/8\", from = 0, to = \"1/2\" },\n"
           "             { direction = \"horizontal\", position = \"3/8\", from = \"1/4\", to = 1 } ]\n");
  box.file("pt.toml",
           "[geometry]\ntype = \"rectangle\"\n[space]\nfamily = \"pt\"\ndegree = 2\ntmesh = \"tmesh.toml\"\n"
           "[problem]\nexact = \"x^2*y^2 - 3*x*y + y\"\n");
  const Result r = box.run("run pt.toml --json -q");
  INFO(r.err);
  REQUIRE(r.code == 0);
  // A biquadratic solution lies in the space: reproduced to rounding. 22 cells, and the
  // brute-force dimension of this T-mesh at degree 2 is 42 (knotwork dimension, an
  // independent count).
  REQUIRE(json_number_of(r.out, "cells") == 22);
  REQUIRE(json_number_of(r.out, "dofs") == 42);
  REQUIRE(json_number_of(r.out, "l2_error") < 1e-12);
  REQUIRE(fs::exists(box.dir() / "results/pt/solution.vtu"));
  const Result b = box.run("basis tmesh.toml --pt --json");
  REQUIRE(b.code == 2);  // the T-mesh file has no degree: basis needs one
  box.file("tmesh2.toml", "degree = 2\n" + slurp(box.dir() / "tmesh.toml"));
  const Result b2 = box.run("basis tmesh2.toml --pt --json");
  REQUIRE(b2.code == 0);
  REQUIRE(json_number_of(b2.out, "functions") == 42);
  REQUIRE(json_number_of(b2.out, "dimension_bruteforce") == 42);
  // A segment that ends inside a cell: one line naming the file and the segment.
  box.file("bad.toml", "degree = 2\ngrid = { x = [0, 1, 2], y = [0, 1, 2] }\n"
                       "segments = [ { direction = \"vertical\", position = \"1/2\", from = 0, to = \"3/2\" } ]\n");
  expect_one_line_error(box.run("basis bad.toml --pt"), {"bad.toml", "segments", "ends inside cell"});
  // Convergence on the T-mesh, every cell halved per level: optimal rates.
  box.file("ptsin.toml",
           "[geometry]\ntype = \"rectangle\"\n[space]\nfamily = \"pt\"\ndegree = 2\ntmesh = \"tmesh.toml\"\n"
           "[problem]\nexact = \"sin(pi*x)*sin(pi*y)\"\n");
  const Result c = box.run("converge ptsin.toml --levels 3 --json -q");
  INFO(c.err << c.out);
  REQUIRE(c.code == 0);
  // The last level's rates (h^2 in H1, h^3 in L2 for degree 2) are the last ones printed.
  const size_t h1 = c.out.rfind("\"h1_rate\""), l2 = c.out.rfind("\"l2_rate\"");
  REQUIRE(h1 != std::string::npos);
  REQUIRE(l2 != std::string::npos);
  REQUIRE(std::stod(c.out.substr(c.out.find(':', h1) + 1)) == Approx(2.0).margin(0.1));
  REQUIRE(std::stod(c.out.substr(c.out.find(':', l2) + 1)) == Approx(3.0).margin(0.2));
}
