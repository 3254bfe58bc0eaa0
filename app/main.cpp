// The knotwork command line: run a case, study convergence, benchmark the pipeline.
#include <CLI/CLI.hpp>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>

#include "app/commands.hpp"
#include "solver/input_error.hpp"

namespace {

void add_common(CLI::App* cmd, knotwork::CommonOptions& o) {
  cmd->add_option("--degree", o.degree, "Polynomial degree in both directions (overrides [space] degree)");
  cmd->add_option("--elements", o.elements, "Elements per geometry knot span and direction (overrides [space] elements)");
  cmd->add_option("--out", o.out, "Output directory (overrides [output] directory; default results/<case name>)");
  cmd->add_option("--ordering", o.ordering, "Fill-reducing ordering for CHOLMOD: amd (fastest measured), metis, nesdis, or default (CHOLMOD's own choice)")
      ->capture_default_str();
  cmd->add_flag("--json", o.json, "Print one JSON object on stdout instead of the summary");
  cmd->add_flag("-q,--quiet", o.quiet, "No progress lines on stderr");
}

// Every error is one line on stderr (scripts and tests rely on it), whatever a message
// quotes from the input: control characters such as a newline in a TOML parser's
// "saw '...'" are printed escaped.
void print_error(const std::string& message) {
  std::string line;
  for (const char c : message) {
    if (c == '\n') line += "\\n";
    else if (c == '\t') line += "\\t";
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) line += "?";
    else line += c;
  }
  std::fprintf(stderr, "knotwork: error: %s\n", line.c_str());
}

}  // namespace

// CHOLMOD runs OpenMP regions of its own next to OpenBLAS's threads; with libgomp's
// default spin-waiting they fight over the cores and the factorization is ~8% slower
// (docs/PERFORMANCE.md). libgomp reads OMP_WAIT_POLICY when it loads, before main, so
// the only way to choose it from inside is to set it and start again. A user's own
// setting is kept.
void prefer_passive_openmp_waiting(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  setenv("OMP_WAIT_POLICY", "passive", 1);
  execv("/proc/self/exe", argv);  // returns only on failure: then run as we are
}

int main(int argc, char** argv) {
  prefer_passive_openmp_waiting(argv);
  CLI::App app{"knotwork: isogeometric Poisson solver (B-splines/NURBS -> Bezier extraction -> CHOLMOD -> ParaView)"};
  app.set_version_flag("--version", "knotwork 0.1.0");
  app.require_subcommand(1);

  knotwork::RunOptions run;
  CLI::App* run_cmd = app.add_subcommand("run", "Solve one case and write ParaView files");
  run_cmd->add_option("case", run.case_file,
                     "Case file (TOML), e.g. cases/square_sinsin.toml, or a G1 case such as cases/g1_sphere_xy.toml")
      ->required();
  add_common(run_cmd, run);
  run_cmd->add_flag("--no-output", run.no_output, "Write no files (timing and errors only)");
  run_cmd->add_flag("--allow-non-semi-regular", run.allow_non_semi_regular,
                    "Solve on a [space] collection that is not semi-regular (its functions may be dependent)");

  knotwork::ConvergeOptions conv;
  CLI::App* conv_cmd = app.add_subcommand("converge", "Uniform h-refinement study: errors and observed rates per level");
  conv_cmd->add_option("case", conv.case_file, "Case file (TOML) with [problem] exact")->required();
  conv_cmd->add_option("--levels", conv.levels,
                      "Number of levels; level l has elements * 2^l per span (G1 cases: the quad mesh subdivided l times)")
      ->capture_default_str();
  add_common(conv_cmd, conv);

  knotwork::AdaptOptions adapt;
  CLI::App* adapt_cmd = app.add_subcommand(
      "adapt", "Adaptive refinement by knot segments or PT-splines: solve, estimate (residual), mark (Doerfler), refine, repeat");
  adapt_cmd->add_option("case", adapt.case_file, "Case file (TOML) with [space] family = \"knot_segments\" or \"pt\"")->required();
  adapt_cmd->add_option("--steps", adapt.steps, "Number of solves (overrides [adapt] steps; default 10)");
  adapt_cmd->add_option("--theta", adapt.theta,
                        "Doerfler fraction: mark the fewest cells holding this share of the estimated error squared "
                        "(overrides [adapt] theta; default 0.5)");
  adapt_cmd->add_option("--max-dofs", adapt.max_dofs, "Stop once a space has this many functions (overrides [adapt] max_dofs)");
  add_common(adapt_cmd, adapt);

  knotwork::BenchOptions bench;
  CLI::App* bench_cmd = app.add_subcommand("bench", "Benchmark setup, assembly, CHOLMOD and error norms (unit square, sin*sin)");
  bench_cmd->add_option("--config", bench.configs,
                        "DEGREE:ELEMENTS, repeatable (default 2:128 2:512 2:1024 4:64 4:256 4:512)");
  bench_cmd->add_flag("--quick", bench.quick, "Small configurations only (2:64 2:128 4:32 4:64)");
  bench_cmd->add_option("--ordering", bench.ordering, "amd, metis, nesdis, or default (CHOLMOD's own choice)")->capture_default_str();
  bench_cmd->add_flag("--json", bench.json, "Print JSON instead of the table");
  bench_cmd->add_flag("!--no-errors", bench.with_errors, "Skip the error norms");
  bench_cmd->add_flag("--floor", bench.floor,
                      "Also time bare CHOLMOD with its default settings on the same matrix (the floor)");

  knotwork::BasisOptions basis;
  CLI::App* basis_cmd = app.add_subcommand(
      "basis", "Check a spline basis: semi-regularity, partition of unity, rank, dimension (or, with --g1, the G1 basis on a quad mesh)");
  basis_cmd->add_option("file", basis.case_file,
                        "Case file, T-mesh file (cells = [...], degree) or collection file (functions = [...], degree); "
                        "TOML or JSON");
  basis_cmd->add_option("--g1", basis.g1_mesh,
                        "Quad mesh (Wavefront OBJ): the G1 spline space S_k^{1,r} on it (4-split macro-patches)");
  basis_cmd->add_option("--degree", basis.degree, "--g1: degree k of the face splines (>= 2)")->capture_default_str();
  basis_cmd->add_option("--split-smoothness", basis.split_smoothness, "--g1: smoothness r at the 4-split, 0 <= r < k")->capture_default_str();
  basis_cmd->add_option("--gluing", basis.gluing, "--g1: symmetric | symmetric_c1 | geometric | regular_fans | FILE.json (per-edge a, b, c)")->capture_default_str();
  basis_cmd->add_option("--export", basis.export_file,
                        "Write every function to this JSON file (local knot vectors; with --g1, per-face B-spline coefficients)");
  basis_cmd->add_option("--vtk", basis.vtk_file,
                        "--g1: write the G1 surface fitted to the mesh, with the --show functions as fields, to this .vtu; "
                        "--pt: the T-mesh cells with the --show functions");
  basis_cmd->add_option("--show", basis.show,
                        "--g1 --vtk: functions to write: vertex:N (OBJ index), edge:I-J, face:N (1-based), all, or "
                        "extraordinary (the first interior vertex of valence != 4); --pt --vtk: all, 0-based indices such as 0,5, "
                        "or by default the four functions with the largest supports")
      ->capture_default_str();
  basis_cmd->add_flag("--json", basis.json, "Print one JSON object");
  basis_cmd->add_flag("--pt", basis.pt, "PT-splines of the T-mesh file (edge extension + Extended Edge Elimination)");
  basis_cmd->add_option("--extension", basis.pt_extension,
                        "--pt: minimal (l-edges lengthened as LR meshlines, certified), horizontal or vertical "
                        "(those l-edges extended to cross-cuts), diagonalizable (LR meshlines lengthened until the "
                        "extended mesh is diagonalizable, certified), or auto: minimal, else the full extension with "
                        "fewer extended edges")
      ->capture_default_str();
  basis_cmd->add_flag("!--no-prop1", basis.pt_non_negative,
                      "--pt: keep the EEE combinations instead of the non-negative basis of Prop. 1");
  basis_cmd->add_flag("--reference", basis.pt_reference,
                      "--pt: also build the full-extension reference and report its support sizes (slow)");

  knotwork::DimensionOptions dim;
  CLI::App* dim_cmd = app.add_subcommand(
      "dimension", "Brute-force dimension of S(m, n, alpha, beta) over a T-mesh / rectangular partition");
  dim_cmd->add_option("mesh", dim.file, "Partition file (TOML): cells = [[x0, y0, x1, y1], ...], degree = [m, n]")
      ->required();
  dim_cmd->add_flag("--exact", dim.exact, "Rank by exact rational elimination (slower) instead of modulo two primes");
  dim_cmd->add_flag("--json", dim.json, "Print one JSON object");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    print_error(std::string(e.what()) + " (see knotwork --help)");
    return e.get_exit_code() != 0 ? e.get_exit_code() : 2;
  }
  try {
    if (*run_cmd) return knotwork::run_command(run);
    if (*conv_cmd) return knotwork::converge_command(conv);
    if (*adapt_cmd) return knotwork::adapt_command(adapt);
    if (*bench_cmd) return knotwork::bench_command(bench);
    if (*dim_cmd) return knotwork::dimension_command(dim);
    if (*basis_cmd) {
      if (basis.g1_mesh.empty() == basis.case_file.empty())
        throw knotwork::InputError("basis: give one input, a case/T-mesh/collection file or --g1 MESH.obj");
      if (!basis.g1_mesh.empty()) return knotwork::g1_basis_command(basis);
      if (basis.pt) return knotwork::pt_basis_command(basis);
      return knotwork::basis_command(basis);
    }
  } catch (const knotwork::InputError& e) {
    print_error(e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    print_error("out of memory (try fewer elements or a lower degree)");
    return 3;
  } catch (const std::exception& e) {
    print_error(e.what());
    return 1;
  }
  return 0;
}
