// Runs the real `knotwork` binary: good runs produce what they promise, bad input gets
// one line on stderr naming the file and the field, a non-zero exit code and no files.
#include <catch2/catch.hpp>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <set>
#include <sstream>

#include "tests/cli_sandbox.hpp"

using namespace cli_test;
namespace fs = std::filesystem;

TEST_CASE("run --json reports errors, timings and the files it wrote", "[cli]") {
  Sandbox box;
  box.file("good.toml", kGood);
  const Result r = box.run("run good.toml --json -q --out res");
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* key : {"\"dofs\"", "\"cells\"", "\"l2_error\"", "\"h1_seminorm_error\"", "\"h1_error\"",
                          "\"timings\"", "\"assembly\"", "\"factorization\"", "\"outputs\""})
    REQUIRE(r.out.find(key) != std::string::npos);
  REQUIRE(r.out.find("\"dofs\": 36") != std::string::npos);  // (4 + 2)^2
  // How the matrix was made: the square is one affine map (its Kronecker form), the quarter
  // annulus is curved (sum factorization), a variable coefficient needs the element loop.
  REQUIRE(r.out.find("\"assembly_method\": \"kronecker_form\"") != std::string::npos);
  const Result curved = box.run(std::string("run -q --no-output --json --solver direct ") + KNOTWORK_SOURCE_DIR +
                                "/cases/quarter_annulus.toml");
  REQUIRE(curved.code == 0);
  REQUIRE(curved.out.find("\"assembly_method\": \"sum_factorization\"") != std::string::npos);
  const Result variable = box.run(std::string("run -q --no-output --json --solver direct ") + KNOTWORK_SOURCE_DIR +
                                  "/cases/square_variable_coefficient.toml");
  REQUIRE(variable.code == 0);
  REQUIRE(variable.out.find("\"assembly_method\": \"element_loop\"") != std::string::npos);
  REQUIRE(fs::exists(box.dir() / "res/solution.vtu"));
  REQUIRE(fs::exists(box.dir() / "res/solution_sampled.vtu"));
  REQUIRE(r.err.empty());  // --quiet
  // Nothing is left of the staging folder.
  for (const auto& e : fs::directory_iterator(box.dir() / "res"))
    REQUIRE(e.path().filename().string().rfind(".knotwork", 0) != 0);
}

TEST_CASE("results are the same bits in every process", "[cli][reproducible]") {
  // GiNaC orders the terms of the derived source and gradient by address-seeded hashes:
  // printed in GiNaC's order, they changed from one process to the next (address-space
  // randomization), and so did the last bits of the errors (3 outcomes in 6 runs here).
  Sandbox box;
  box.file("u.toml", replace(kGood, "sin(pi*x)*sin(pi*y)", "sin(3*x)*cos(2*y) + x^2*y - exp(x*y) + y^3*x/7"));
  std::string first;
  for (const char* solver : {"direct", "iterative"})
    for (int run = 0; run < 5; ++run) {
      const Result r = box.run(std::string("run -q --no-output --json --degree 3 --elements 8 --solver ") + solver + " u.toml");
      REQUIRE(r.code == 0);
      const auto at = r.out.find("\"l2_error\"");
      REQUIRE(at != std::string::npos);
      const std::string errors = r.out.substr(at, r.out.find("\"solver\"") - at);  // L2, H1-semi, H1 as printed
      if (run == 0) first = errors;
      INFO(solver << " run " << run);
      REQUIRE(errors == first);
    }
}

TEST_CASE("a staging folder left by a killed run is removed by the next run", "[cli]") {
  Sandbox box;
  box.file("good.toml", kGood);
  // pid 2^22 + 7 is above the largest pid_max Linux allows (2^22): no such process exists.
  fs::create_directories(box.dir() / "res/.knotwork-staging-4194311");
  box.file("res/.knotwork-staging-4194311/solution.vtu", "partial");
  REQUIRE(box.run("run -q good.toml --out res").code == 0);
  REQUIRE(!fs::exists(box.dir() / "res/.knotwork-staging-4194311"));
  REQUIRE(fs::exists(box.dir() / "res/solution.vtu"));
}

TEST_CASE("run and converge with --condition report the Jacobi-scaled condition numbers, refused with petsc", "[cli][condition]") {
  Sandbox box;
  box.file("good.toml", kGood);
  Result r = box.run("run good.toml --condition --json -q --no-output");
  INFO(r.err);
  REQUIRE(r.code == 0);
  REQUIRE(r.out.find("\"condition\": {") != std::string::npos);
  REQUIRE(r.out.find("\"stiffness\": ") != std::string::npos);
  REQUIRE(r.out.find("\"mass\": ") != std::string::npos);
  r = box.run("run good.toml --condition -q --no-output");
  REQUIRE(r.code == 0);
  REQUIRE(r.out.find("kappa    stiffness ") != std::string::npos);
  r = box.run("converge good.toml --levels 2 --condition -q --out conv");
  REQUIRE(r.code == 0);
  REQUIRE(r.out.find("condition.stiffness") != std::string::npos);
  // Without it, nothing is estimated (the estimate costs a factorization and two Lanczos runs).
  r = box.run("run good.toml --json -q --no-output");
  REQUIRE(r.out.find("\"condition\"") == std::string::npos);
  r = box.run("run good.toml --condition --solver petsc -q --no-output");
  REQUIRE(r.code != 0);
  REQUIRE(r.err.find("--condition") != std::string::npos);
  REQUIRE(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}

TEST_CASE("converge writes table, JSON, plot and collection", "[cli]") {
  Sandbox box;
  box.file("good.toml", kGood);
  const Result r = box.run("converge good.toml --levels 3 --out conv --json -q");
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* f : {"convergence.csv", "convergence.json", "convergence.svg", "convergence.pvd", "level_2.vtu"})
    REQUIRE(fs::exists(box.dir() / "conv" / f));
  REQUIRE(r.out.find("\"l2_rate\"") != std::string::npos);
  REQUIRE(r.out.find("\"h1_rate\"") != std::string::npos);
  const std::string csv = slurp(box.dir() / "conv/convergence.csv");
  REQUIRE(std::count(csv.begin(), csv.end(), '\n') == 4);
}

// The CPU's features as the kernel reports them, independently of the compiler's view of them.
bool cpu_has_flags(std::initializer_list<const char*> flags) {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("flags", 0) == 0) {
      std::istringstream words(line.substr(line.find(':') + 1));
      std::set<std::string> have{std::istream_iterator<std::string>(words), std::istream_iterator<std::string>()};
      for (const char* f : flags)
        if (!have.count(f)) return false;
      return true;
    }
  return false;
}

TEST_CASE("bench names the OpenBLAS kernel: not the generic one where the CPU has AVX2, unless the user says so",
          "[cli][bench]") {
  // Debian 12's OpenBLAS runs its generic "Prescott" kernels on CPU models newer than it knows.
  Sandbox box;
  const Result own = box.run("bench --json --config 1:4", "env -u OPENBLAS_CORETYPE");
  INFO(own.err);
  REQUIRE(own.code == 0);
  const auto kernel_of = [](const std::string& out) {
    const std::string key = "\"blas_kernel\": \"";
    const auto at = out.find(key);
    REQUIRE(at != std::string::npos);
    return out.substr(at + key.size(), out.find('"', at + key.size()) - at - key.size());
  };
  const std::string kernel = kernel_of(own.out);
  INFO("kernel " << kernel);
  REQUIRE(!kernel.empty());  // the project links OpenBLAS
  if (cpu_has_flags({"avx2", "fma"})) REQUIRE(kernel != "Prescott");
  // A user's choice stands, and the text table names it too.
  const Result told = box.run("bench --config 1:4", "OPENBLAS_CORETYPE=Prescott");
  REQUIRE(told.code == 0);
  REQUIRE(told.out.find("OpenBLAS kernel Prescott") != std::string::npos);
}

TEST_CASE("bench runs both solvers with and without the error norms", "[cli][bench]") {
  // --no-errors once dropped the exact solution the iterative path's boundary data came from.
  Sandbox box;
  for (const char* solver : {"direct", "iterative"})
    for (const bool errors : {true, false}) {
      const Result r = box.run(std::string("bench --json --config 2:16 --solver ") + solver + (errors ? "" : " --no-errors"));
      INFO(solver << (errors ? "" : " --no-errors") << ": " << r.err);
      REQUIRE(r.code == 0);
      REQUIRE((r.out.find("\"l2_error\": null") == std::string::npos) == errors);
      REQUIRE(r.out.find("\"free_dofs\": 256") != std::string::npos);  // 16^2 interior functions of 18^2
      // The preconditioner "auto" chose is named (the space's first, below 2M functions).
      if (std::string(solver) == "iterative")
        REQUIRE(r.out.find("\"preconditioner\": \"fast_diagonalization\"") != std::string::npos);
    }
  const Result text = box.run("bench --config 2:16 --solver iterative");
  REQUIRE(text.code == 0);
  REQUIRE(text.out.find("preconditioner (auto): 2:16 fast_diagonalization") != std::string::npos);
  // --matrix as run takes it: the square's affine elements run without one unless told.
  for (const std::string matrix : {"auto", "matrix_free", "assembled"}) {
    const Result r = box.run("bench --json --config 2:16 --solver iterative --matrix " + matrix);
    INFO(matrix << ": " << r.err);
    REQUIRE(r.code == 0);
    const bool none = matrix != "assembled";
    REQUIRE(r.out.find(none ? "\"matrix\": \"matrix_free\"" : "\"matrix\": \"assembled\"") != std::string::npos);
    REQUIRE((r.out.find("\"matrix_nonzeros\": 0,") != std::string::npos) == none);
    // The unit square is one affine map: its matrix, when there is one, is the Kronecker form's.
    REQUIRE(r.out.find(none ? "\"assembly_method\": \"none\"" : "\"assembly_method\": \"kronecker_form\"") !=
            std::string::npos);
  }
  const Result bad = box.run("bench --config 2:16 --solver iterative --matrix sparse");
  REQUIRE(bad.code != 0);
  REQUIRE(bad.err.find("--matrix") != std::string::npos);
  const Result direct = box.run("bench --config 2:16 --matrix assembled");
  REQUIRE(direct.code != 0);
  REQUIRE(direct.err.find("--matrix: used with --solver iterative only") != std::string::npos);
}

TEST_CASE("bench on the unit cube: both solvers, the configurations' limit", "[cli][bench]") {
  Sandbox box;
  for (const char* solver : {"direct", "iterative"}) {
    const Result r = box.run(std::string("bench --json --domain cube --config 2:6 --solver ") + solver);
    INFO(solver << ": " << r.err);
    REQUIRE(r.code == 0);
    REQUIRE(r.out.find("\"domain\": \"cube\"") != std::string::npos);
    REQUIRE(r.out.find("\"free_dofs\": 216") != std::string::npos);  // 6^3 interior functions of 8^3
    if (std::string(solver) == "iterative")
      REQUIRE(r.out.find("\"preconditioner\": \"fast_diagonalization\"") != std::string::npos);
  }
  const Result big = box.run("bench --domain cube --config 2:407");
  REQUIRE(big.code != 0);
  REQUIRE(big.err.find("elements 1..406 per direction on the cube") != std::string::npos);
  const Result unknown = box.run("bench --domain sphere");
  REQUIRE(unknown.code != 0);
}

TEST_CASE("every subcommand has --help", "[cli]") {
  Sandbox box;
  for (const char* c : {"--help", "run --help", "converge --help", "bench --help", "adapt --help", "basis --help",
                        "dimension --help"}) {
    const Result r = box.run(c);
    REQUIRE(r.code == 0);
    REQUIRE(r.out.find("Usage") != std::string::npos);
  }
  for (const char* bad : {"", "frobnicate", "run", "run x.toml --degree abc", "run x.toml --bogus"}) {
    const Result r = box.run(bad);
    INFO(bad << ": " << r.err);
    REQUIRE(r.code != 0);
    REQUIRE(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
}

TEST_CASE("bad input: files and TOML", "[cli][bad-input]") {
  Sandbox box;
  {
    const Result r = box.run("run -q missing.toml --out o");
    REQUIRE(r.code != 0);
    REQUIRE(r.err.find("missing.toml") != std::string::npos);
    REQUIRE(r.err.find("no such file") != std::string::npos);
    REQUIRE(!fs::exists(box.dir() / "o"));
  }
  expect_rejected(box, "[geometry]\ntype = \"rectangle\"\n[space\ndegree = 2\n", {"bad.toml:3:", "TOML syntax error"});
  expect_rejected(box, replace(kGood, "degree = 2", "degre = 2"), {"bad.toml", "[space] degre", "did you mean 'degree'"});
  expect_rejected(box, replace(kGood, "degree = 2\n", ""), {"bad.toml", "[space] degree", "missing"});
}

TEST_CASE("bad input: degrees, elements, numbers", "[cli][bad-input]") {
  Sandbox box;
  expect_rejected(box, replace(kGood, "degree = 2", "degree = 0"), {"bad.toml", "[space] degree", "[1, 10]"});
  expect_rejected(box, replace(kGood, "degree = 2", "degree = 11"), {"bad.toml", "[space] degree"});
  expect_rejected(box, replace(kGood, "elements = 4", "elements = 0"), {"bad.toml", "[space] elements", ">= 1"});
  expect_rejected(box, replace(kGood, "type = \"rectangle\"", "type = \"rectangle\"\ncorners = [[0, 0], [nan, 1]]"),
                  {"bad.toml", "[geometry] corners", "finite"});
  expect_rejected(box, kGood, {"--degree", "[1, 10]"}, "--degree 12");
  expect_rejected(box, kGood, {"--elements"}, "--elements -3");
}

TEST_CASE("bad input: NURBS data", "[cli][bad-input]") {
  Sandbox box;
  expect_rejected(box, replace(kNurbs, "knots_u = [0, 0, 1, 1]", "knots_u = [0, 0, 0.7, 0.5, 1, 1]"),
                  {"bad.toml", "knots_u", "not non-decreasing"});
  expect_rejected(box, replace(kNurbs, "knots_u = [0, 0, 1, 1]", "knots_u = [0, 0, 0.5, 0.5, 0.5, 1, 1]"),
                  {"bad.toml", "knots_u", "multiplicity 3"});
  expect_rejected(box, replace(kNurbs, "[0, 1], [1, 1]]", "[0, 1]]"), {"bad.toml", "control_points", "need 2 x 2"});
  expect_rejected(box, replace(kNurbs, "weights = [1, 1, 1, 1]", "weights = [1, 1, 0, 1]"),
                  {"bad.toml", "weights", "positive"});
  expect_rejected(box, replace(kNurbs, "weights = [1, 1, 1, 1]", "weights = [1, inf, 1, 1]"),
                  {"bad.toml", "weights", "finite"});
  // Control points swapped: the map is oriented clockwise.
  expect_rejected(box, replace(kNurbs, "[[0, 0], [1, 0], [0, 1], [1, 1]]", "[[0, 0], [0, 1], [1, 0], [1, 1]]"),
                  {"bad.toml", "[geometry]", "non-positive Jacobian", "cell 0"});
}

TEST_CASE("bad input: a discretization too large for the machine is refused up front", "[cli][bad-input]") {
  Sandbox box;
  expect_rejected(box, kGood, {"bad.toml", "[space] elements", "GB"}, "--degree 10 --elements 8000");
}

TEST_CASE("nothing typed into a case file crashes knotwork", "[cli][bad-input][fuzz]") {
  // Random edits of a valid case (characters deleted, inserted, replaced, numbers made
  // huge, negative or fractional): every run must end with exit 0 or a one-line error,
  // never a signal, and a rejected run writes nothing.
  Sandbox box;
  std::mt19937 rng(2026);
  const std::string alphabet = "[]{}=\"',.-+0123456789eEnaxyzpi*/^() \n#";
  const std::vector<std::string> numbers = {"0", "-1", "1e308", "2.5", "99999", "-0", "1e-300", "\"1/3\"", "nan", "inf"};
  fuzz(box, 150, [&](int) {
    std::string text = kGood;
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int e = 0; e < edits; ++e) {
      const size_t at = rng() % text.size();
      if (rng() % 4 == 0) {  // a number made huge, negative, fractional, nan, ...
        const size_t digit = text.find_first_of("0123456789", at);
        if (digit != std::string::npos) text.replace(digit, 1, numbers[rng() % numbers.size()]);
      } else {
        random_edit(text, rng, alphabet);
      }
    }
    box.file("fuzz.toml", text);
    return std::pair{std::string("run -q --no-output fuzz.toml --elements 3"), text};
  });
}

TEST_CASE("basis: checks of a knot-segment space, and the export", "[cli][semi-regular]") {
  Sandbox box;
  const std::string file = std::string(KNOTWORK_SOURCE_DIR) + "/cases/square_knot_segments.toml";
  const Result r = box.run("basis --json --export knots.json " + file);
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* expected : {"\"functions\": 46", "\"cells\": 24", "\"semi_regular\": true", "\"violations\": []",
                               "\"rank\": 46", "\"dimension_formula\": 46", "\"dimension_bruteforce\": 46",
                               "\"extended_segments\": 1", "\"partition_of_unity_error\""})
    REQUIRE(r.out.find(expected) != std::string::npos);
  const std::string exported = slurp(box.dir() / "knots.json");
  size_t functions = 0;
  for (size_t at = exported.find("\"x\""); at != std::string::npos; at = exported.find("\"x\"", at + 1)) ++functions;
  REQUIRE(functions == 46);
  REQUIRE(!fs::exists(box.dir() / "knots.json.partial"));
}

TEST_CASE("bad input: knot segments", "[cli][bad-input]") {
  Sandbox box;
  const std::string base = replace(kGood, "degree = 2", "family = \"knot_segments\"\ndegree = 2");
  auto with = [&](const std::string& segment) {
    return replace(base, "elements = 4", "elements = 4\nsegments = [ " + segment + " ]");
  };
  expect_rejected(box, with("{ direction = \"vertical\", position = 1.5, from = 0, to = 1 }"),
                  {"bad.toml", "[space] segments[0]", "not inside the domain"});
  expect_rejected(box, with("{ direction = \"vertical\", position = 0.3, from = 0.5, to = 0.5 }"),
                  {"bad.toml", "[space] segments[0]", "zero length"});
  expect_rejected(box, with("{ direction = \"vertical\", position = 0.3, from = 0, to = 1, multiplicity = 4 }"),
                  {"bad.toml", "[space] segments[0]", "multiplicity 4"});
  expect_rejected(box, with("{ direction = \"vertical\", position = 0.3, from = 0, to = 1, multiplicity = 0 }"),
                  {"bad.toml", "[space] segments[0]", "multiplicity 0"});
  expect_rejected(box, with("{ direction = \"vertical\", position = 0.3, from = 0, to = 1, multiplicity = 2 }, "
                            "{ direction = \"vertical\", position = 0.3, from = 0.25, to = 0.5 }"),
                  {"bad.toml", "[space] segments[1]", "multiplicity 2"});
  expect_rejected(box, with("{ direction = \"diagonal\", position = 0.3, from = 0, to = 1 }"),
                  {"bad.toml", "[space] segments[0] direction"});
  expect_rejected(box, with("{ direction = \"vertical\", position = 0.3, from = 0, to = 1, multiplicty = 2 }"),
                  {"bad.toml", "mult", "did you mean 'multiplicity'"});
  expect_rejected(box, replace(base, "elements = 4", "elements = 4\ncontinuity = 1"), {"bad.toml", "[space] continuity"});
}

TEST_CASE("bad input: expressions and output directory", "[cli][bad-input]") {
  Sandbox box;
  expect_rejected(box, replace(kGood, "sin(pi*x)*sin(pi*y)", "sin(pi*x)*sin(pi*y"),
                  {"bad.toml", "[problem] exact", "')' is missing at character 19"});
  expect_rejected(box, replace(kGood, "exact = \"sin(pi*x)*sin(pi*y)\"", "source = \"1\"\ndirichlet = \"x + q\""),
                  {"bad.toml", "[problem] dirichlet", "unknown name 'q'", "character 5"});
  expect_rejected(box, replace(kGood, "exact = \"sin(pi*x)*sin(pi*y)\"", "source = \"log(x - 2)\"\ndirichlet = \"0\""),
                  {"bad.toml", "[problem] source", "not a finite number"});
  expect_rejected(box, replace(kGood, "[problem]", "[problem]\nneumann = [\"left\", \"right\", \"top\", \"bottom\"]"),
                  {"bad.toml", "[problem] neumann", "Dirichlet"});
  // An output "directory" that is a regular file cannot be written, even by root.
  box.file("good.toml", kGood);
  box.file("occupied", "not a directory");
  const Result r = box.run("run -q good.toml --out occupied");
  REQUIRE(r.code != 0);
  REQUIRE(r.err.find("occupied") != std::string::npos);
  REQUIRE(r.err.find("not writable") != std::string::npos);
  REQUIRE(slurp(box.dir() / "occupied") == "not a directory");
}

TEST_CASE("dimension: T-mesh files, results and bad input", "[cli][dimension]") {
  Sandbox box;
  // The shipped hierarchical mesh: bicubic C2 on 4 x 4 with the lower-left 2 x 2 block halved.
  // Hierarchical count: 49 level-0 functions, minus the 2 x 2 whose support lies in the
  // refined block [0,2]^2, plus the 4 x 4 level-1 functions supported there: 61.
  const Result r = box.run(std::string("dimension --json ") + KNOTWORK_SOURCE_DIR + "/cases/tmeshes/hierarchical.toml");
  INFO(r.err);
  REQUIRE(r.code == 0);
  REQUIRE(r.out.find("\"dimension_bruteforce\": 61") != std::string::npos);
  const Result e = box.run(std::string("dimension --exact ") + KNOTWORK_SOURCE_DIR + "/cases/tmeshes/hierarchical.toml");
  REQUIRE(e.out.find("dimension  61") != std::string::npos);

  // The dimensional-instability pair (the ratio argument in the files): 30 and 29, by the
  // brute force and by smoothing cofactors, and no topological formula for either.
  for (const auto& [name, dim] : std::vector<std::pair<std::string, int>>{{"special", 30}, {"generic", 29}}) {
    const Result pw =
        box.run(std::string("dimension --json ") + KNOTWORK_SOURCE_DIR + "/cases/tmeshes/pinwheel_" + name + ".toml");
    INFO(name << ": " << pw.err);
    REQUIRE(pw.code == 0);
    for (const std::string key : {"dimension_bruteforce", "dimension_cofactor"})
      REQUIRE(pw.out.find("\"" + key + "\": " + std::to_string(dim)) != std::string::npos);
    REQUIRE(pw.out.find("\"diagonalizable\": false") != std::string::npos);
    REQUIRE(pw.out.find("\"dimension_formula\": null") != std::string::npos);
  }

  // The generic twin with its ray moved off 5/2 by (2^61 - 1) / 2^71: special modulo the
  // first prime only, so the modular ranks disagree. Both commands used to stop with "modular
  // ranks disagree"; they must answer over Q.
  box.file("unlucky.toml",
           "degree = [2, 2]\ngrid = { x = [0, 1, 5, 6], y = [0, 1, 5, 6] }\nsegments = [\n"
           "  { direction = \"horizontal\", position = 2, from = 2, to = 5 },\n"
           "  { direction = \"vertical\", position = 4, from = 2, to = 5 },\n"
           "  { direction = \"horizontal\", position = 4, from = 1, to = 4 },\n"
           "  { direction = \"vertical\", position = 2, from = 1, to = 4 },\n"
           "  { direction = \"vertical\", position = \"5905263946596270211071/2361183241434822606848\", from = 0, to = 2 },\n"
           "  { direction = \"horizontal\", position = \"5/2\", from = 4, to = 6 },\n"
           "  { direction = \"vertical\", position = \"7/2\", from = 4, to = 6 },\n"
           "  { direction = \"horizontal\", position = \"7/2\", from = 0, to = 2 },\n]\n");
  const Result unlucky = box.run("dimension --json unlucky.toml");
  INFO(unlucky.err);
  REQUIRE(unlucky.code == 0);
  REQUIRE(unlucky.out.find("\"dimension_bruteforce\": 29") != std::string::npos);
  REQUIRE(unlucky.out.find("\"exact\": \"rational\"") != std::string::npos);
  const Result unlucky_pt = box.run("basis --pt --json unlucky.toml");
  INFO(unlucky_pt.err);
  REQUIRE(unlucky_pt.code == 0);
  REQUIRE(unlucky_pt.out.find("\"functions\": 29") != std::string::npos);
  REQUIRE(unlucky_pt.out.find("\"rank\": 29") != std::string::npos);

  auto rejected = [&](const std::string& text, const std::vector<std::string>& mentions) {
    box.file("mesh.toml", text);
    expect_one_line_error(box.run("dimension mesh.toml"), mentions);
  };
  rejected("degree = 2\ncells = [[0, 0, 1, 1], [\"1/2\", 0, 2, 1]]\n", {"mesh.toml", "cells", "cells 0", "overlap"});
  rejected("degree = 2\ncells = [[0, 0, 1, 1], [1, 0, 2, \"1/2\"]]\n", {"mesh.toml", "cells", "gap"});
  rejected("degree = 2\ncells = [[0, 0, 1, 1], [1, 0, 1, 1]]\n", {"mesh.toml", "zero"});
  rejected("degree = 2\ncells = [[0, 0, nan, 1]]\n", {"mesh.toml", "cells[0]", "finite"});
  rejected("degree = 0\ncells = [[0, 0, 1, 1]]\n", {"mesh.toml", "degree"});
  rejected("degree = 2\ncells = [[0, 0, \"1/x\", 1]]\n", {"mesh.toml", "cells[0]", "not a number"});
  rejected("cells = [[0, 0, 1, 1]]\n", {"mesh.toml", "degree", "missing"});
}

TEST_CASE("adapt writes steps as JSON, CSV, plot and a two-part collection", "[cli][adaptive]") {
  Sandbox box;
  const std::string src = std::string(KNOTWORK_SOURCE_DIR) + "/cases/lshape_adaptive.toml";
  const Result r = box.run("adapt " + src + " --steps 4 --out ad --json -q");
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* key : {"\"steps\"", "\"dofs\"", "\"cells\"", "\"l2_error\"", "\"h1_seminorm_error\"", "\"estimator\"",
                          "\"marked\""})
    REQUIRE(r.out.find(key) != std::string::npos);
  for (const char* f : {"adapt.csv", "adapt.json", "adapt.svg", "adapt.pvd", "step_0.vtu", "step_3.vtu", "step_3_knots.vtp"})
    REQUIRE(fs::exists(box.dir() / "ad" / f));
  const std::string pvd = slurp(box.dir() / "ad/adapt.pvd");
  REQUIRE(pvd.find("part=\"1\" file=\"step_3_knots.vtp\"") != std::string::npos);
  const std::string vtu = slurp(box.dir() / "ad/step_1.vtu");
  REQUIRE(vtu.find("Name=\"error_indicator\"") != std::string::npos);
  const std::string csv = slurp(box.dir() / "ad/adapt.csv");
  REQUIRE(std::count(csv.begin(), csv.end(), '\n') == 5);
}

TEST_CASE("adapt --output-every K writes every K-th step and the last, --no-output writes nothing", "[cli][adaptive]") {
  Sandbox box;
  const std::string src = std::string(KNOTWORK_SOURCE_DIR) + "/cases/lshape_adaptive.toml";
  Result r = box.run("adapt " + src + " --steps 6 --output-every 4 --out ad -q");
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (int step = 0; step < 6; ++step) {
    const bool written = step % 4 == 0 || step == 5;
    CHECK(fs::exists(box.dir() / "ad" / ("step_" + std::to_string(step) + ".vtu")) == written);
  }
  const std::string pvd = slurp(box.dir() / "ad/adapt.pvd");
  CHECK(pvd.find("step_5.vtu") != std::string::npos);
  CHECK(pvd.find("step_1.vtu") == std::string::npos);
  CHECK(std::count(pvd.begin(), pvd.end(), '\n') > 0);
  const std::string csv = slurp(box.dir() / "ad/adapt.csv");
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 7);  // the history keeps every step
  r = box.run("adapt " + src + " --steps 3 --no-output --out quiet -q");
  REQUIRE(r.code == 0);
  CHECK(r.out.find("step") != std::string::npos);  // the table is printed
  CHECK(!fs::exists(box.dir() / "quiet"));
  CHECK(!fs::exists(box.dir() / "results"));
}

TEST_CASE("bad input: adapt", "[cli][bad-input][adaptive]") {
  Sandbox box;
  expect_rejected(box, kGood, {"bad.toml", "[space] family", "knot_segments"}, "", "adapt");
  const std::string segments = replace(kGood, "degree = 2", "family = \"knot_segments\"\ndegree = 2");
  expect_rejected(box, segments, {"--theta", "(0, 1]"}, "--theta 1.5", "adapt");
  expect_rejected(box, segments, {"--steps"}, "--steps 500", "adapt");
  expect_rejected(box, segments, {"--output-every", "at least 1"}, "--output-every 0", "adapt");
  expect_rejected(box, segments + "\n[adapt]\ntheta = 0\n", {"bad.toml", "[adapt] theta"}, "", "adapt");
  expect_rejected(box, segments + "\n[adapt]\nstep = 3\n", {"bad.toml", "did you mean 'steps'"}, "", "adapt");
}

TEST_CASE("bad input: [solver] and --solver", "[cli][bad-input][solver]") {
  Sandbox box;
  const std::string iterative = kGood + "[solver]\nmethod = \"iterative\"\n";
  expect_rejected(box, kGood + "[solver]\nmethod = \"iterativ\"\n", {"bad.toml", "[solver] method", "did you mean 'iterative'"});
  expect_rejected(box, kGood + "[solver]\npreconditioner = \"multigird\"\n",
                  {"bad.toml", "[solver] preconditioner", "did you mean 'multigrid'"});
  expect_rejected(box, kGood + "[solver]\npreconditioner = \"amg\"\n", {"bad.toml", "[solver] preconditioner", "not a choice"});
  expect_rejected(box, kGood + "[solver]\ntolerance = 0\n", {"bad.toml", "[solver] tolerance", "(0, 1)"});
  expect_rejected(box, kGood + "[solver]\ntolerance = 1.5\n", {"bad.toml", "[solver] tolerance", "(0, 1)"});
  expect_rejected(box, kGood + "[solver]\nmax_iterations = 0\n", {"bad.toml", "[solver] max_iterations", "[1, 1000000]"});
  expect_rejected(box, kGood + "[solver]\nmethd = \"direct\"\n", {"bad.toml", "[solver] methd", "did you mean 'method'"});
  expect_rejected(box, kGood + "[solver]\npetsc_options = \"-pc_hypre_boomeramg_max_levels 3\"\n",
                  {"bad.toml", "[solver] petsc_options", "only used with method = \"petsc\" (PETSc's KSP and PC) or preconditioner = \"boomeramg\""});
  expect_rejected(box, iterative + "preconditioner = \"boomeramg\"\npetsc_options = \"-pc_hypre_boomeramg_max_lvls 3\"\n",
                  {"bad.toml", "[solver] petsc_options", "-pc_hypre_boomeramg_max_lvls: not an option"});
  // Not converged: a non-zero exit, the residual reached, and no result files.
  expect_rejected(box, iterative + "preconditioner = \"jacobi\"\nmax_iterations = 2\n",
                  {"bad.toml", "[solver]", "CG stopped after 2 iterations", "backward error", "above the tolerance"});
  expect_rejected(box, kGood, {"--solver", "'cg' is not a choice"}, "--solver cg");
  expect_rejected(box, kGood, {"--tolerance", "(0, 1)"}, "--tolerance -1");
  expect_rejected(box, kGood, {"--preconditioner", "did you mean 'multigrid'"}, "--preconditioner multigird");
  // Under PETSc multigrid on one affine map is built without a matrix: 101 x 101 elements have
  // no coarser level.
  expect_rejected(box, kGood, {"bad.toml", "[solver] preconditioner", "\"multigrid\" without a matrix", "use \"boomeramg\""},
                  "--solver petsc --preconditioner multigrid --elements 101");
  // A preconditioner the family does not have: one line naming the family and what to use.
  const std::string segments = replace(kGood, "[space]\n", "[space]\nfamily = \"knot_segments\"\n") +
                               "[solver]\nmethod = \"iterative\"\npreconditioner = \"fast_diagonalization\"\n";
  expect_rejected(box, segments, {"bad.toml", "[solver] preconditioner", "family \"knot_segments\"", "jacobi"});
  expect_rejected(box, segments, {"bad.toml", "[solver] preconditioner", "\"multigrid\" does not apply", "knot_segments"},
                  "--preconditioner multigrid");
  // Also where the direct solve is taken: a name that would never apply is not kept silently.
  expect_rejected(box, segments, {"bad.toml", "[solver] preconditioner", "\"multigrid\" does not apply", "knot_segments"},
                  "--preconditioner multigrid --solver direct");
  // K without a matrix: a misspelt name, and each condition it needs, named.
  expect_rejected(box, kGood + "[solver]\nmatrix = \"matrixfree\"\n", {"bad.toml", "[solver] matrix", "did you mean 'matrix_free'"});
  expect_rejected(box, kGood, {"--matrix", "not a choice"}, "--matrix free");
  expect_rejected(box, kGood, {"bad.toml", "[solver] matrix", "needs CG", "this solve is direct"},
                  "--solver direct --matrix matrix_free");
  // Multigrid without a matrix needs a coarser level: 101 x 101 elements have none.
  expect_rejected(box, kGood, {"bad.toml", "[solver] preconditioner", "\"multigrid\" without a matrix", "--matrix assembled"},
                  "--solver iterative --preconditioner multigrid --matrix matrix_free --elements 101");
  expect_rejected(box, kGood, {"bad.toml", "[solver] matrix", "does without the matrix", "\"boomeramg\""},
                  "--solver iterative --preconditioner boomeramg --matrix matrix_free");
  expect_rejected(box, replace(kGood, "[problem]\n", "[problem]\ncoefficient = \"1 + x^2\"\n"),
                  {"bad.toml", "[solver] matrix", "constant coefficients"}, "--solver iterative --matrix matrix_free");
  expect_rejected(box, replace(kGood, "[space]\n", "[space]\nfamily = \"knot_segments\"\n"),
                  {"bad.toml", "[solver] matrix", "not available for this space", "knot_segments"},
                  "--solver iterative --preconditioner jacobi --matrix matrix_free");
}

TEST_CASE("run --solver iterative reports the solver, and agrees with the direct solve", "[cli][solver]") {
  Sandbox box;
  box.file("ok.toml", kGood);
  const Result direct = box.run("run -q --no-output --json ok.toml --solver direct");
  const Result cg = box.run("run -q --no-output --json ok.toml --solver iterative");
  INFO(cg.err);
  REQUIRE(cg.code == 0);
  REQUIRE(cg.out.find("\"method\": \"iterative\"") != std::string::npos);
  REQUIRE(cg.out.find("\"preconditioner\": \"fast_diagonalization\"") != std::string::npos);
  REQUIRE(json_number_of(cg.out, "iterations") >= 1);
  REQUIRE(json_number_of(cg.out, "backward_error") <= 1e-15);
  REQUIRE(json_number_of(cg.out, "l2_error") == Approx(json_number_of(direct.out, "l2_error")).epsilon(1e-6));
}
