// Runs the real `knotwork` binary in a temporary folder: shared by the CLI test programs.
#pragma once
#include <catch2/catch.hpp>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace cli_test {

struct Result {
  int code;
  std::string out, err;
};

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class Sandbox {
 public:
  Sandbox() {
    char tmpl[] = "/tmp/knotwork-test-cli-XXXXXX";
    dir_ = mkdtemp(tmpl);
  }
  ~Sandbox() { fs::remove_all(dir_); }
  fs::path file(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  // env: a prefix such as "env -u NAME NAME2=value" for the program's environment.
  Result run(const std::string& args, const std::string& env = "") const {
    const std::string cmd =
        "cd " + dir_.string() + " && " + env + " " + KNOTWORK_BINARY + " " + args + " > stdout.txt 2> stderr.txt";
    const int status = std::system(cmd.c_str());
    return {WEXITSTATUS(status), slurp(dir_ / "stdout.txt"), slurp(dir_ / "stderr.txt")};
  }
  const fs::path& dir() const { return dir_; }

 private:
  fs::path dir_;
};

inline const std::string kGood = R"TOML(
[geometry]
type = "rectangle"
[space]
degree = 2
elements = 4
[problem]
exact = "sin(pi*x)*sin(pi*y)"
)TOML";

// The first number stored under "key" in a JSON text.
inline double json_number_of(const std::string& out, const std::string& key) {
  const auto at = out.find("\"" + key + "\": ");
  REQUIRE(at != std::string::npos);
  return std::stod(out.substr(at + key.size() + 4));
}

inline std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  REQUIRE(at != std::string::npos);
  return s.replace(at, from.size(), to);
}

inline const std::string kNurbs = R"TOML(
[geometry]
type = "nurbs"
degrees = [1, 1]
knots_u = [0, 0, 1, 1]
knots_v = [0, 0, 1, 1]
control_points = [[0, 0], [1, 0], [0, 1], [1, 1]]
weights = [1, 1, 1, 1]
[space]
degree = 2
elements = 2
[problem]
exact = "x*y"
)TOML";

// An error exit (not a signal) with one line on stderr that mentions every string.
inline void expect_one_line_error(const Result& r, const std::vector<std::string>& mentions) {
  INFO("stderr: " << r.err);
  REQUIRE(r.code != 0);
  REQUIRE(r.code < 128);
  REQUIRE(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  for (const auto& m : mentions) REQUIRE(r.err.find(m) != std::string::npos);
}

inline void expect_rejected(const Sandbox& box, const std::string& case_text, const std::vector<std::string>& mentions,
                     const std::string& extra_args = "", const std::string& command = "run") {
  const fs::path f = box.file("bad.toml", case_text);
  const fs::path out = box.dir() / "out";
  expect_one_line_error(box.run(command + " -q bad.toml --out " + out.string() + " " + extra_args), mentions);
  REQUIRE(!fs::exists(out));
}

// Fuzzing: one random edit of `text` (a character deleted, inserted or replaced).
inline void random_edit(std::string& text, std::mt19937& rng, const std::string& alphabet) {
  const size_t at = rng() % text.size();
  switch (rng() % 3) {
    case 0: text.erase(at, 1); break;
    case 1: text.insert(at, 1, alphabet[rng() % alphabet.size()]); break;
    default: text[at] = alphabet[rng() % alphabet.size()];
  }
}

// A fuzzed run must end with exit 0 or one "knotwork: error: " line, never a signal.
// Returns whether it was accepted.
inline bool ended_cleanly(const Result& r) {
  REQUIRE(r.code >= 0);
  REQUIRE(r.code < 128);
  if (r.code == 0) return true;
  REQUIRE(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  REQUIRE(r.err.rfind("knotwork: error: ", 0) == 0);
  return false;
}

// Fuzz runs: `prepare(trial)` writes the fuzzed input files and returns {command, what was
// fuzzed}; every run must end cleanly, and both outcomes must occur (else the fuzzing is
// too weak or too strong to test anything).
inline void fuzz(const Sandbox& box, int trials,
                 const std::function<std::pair<std::string, std::string>(int trial)>& prepare) {
  int accepted = 0, rejected = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const auto [command, input] = prepare(trial);
    const Result r = box.run(command);
    INFO("input:\n" << input << "\nstderr: " << r.err);
    (ended_cleanly(r) ? accepted : rejected)++;
  }
  INFO(accepted << " accepted, " << rejected << " rejected");
  REQUIRE(accepted > 0);
  REQUIRE(rejected > 0);
}

}  // namespace cli_test
