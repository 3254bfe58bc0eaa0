// The knotwork command line: run a case, study convergence, benchmark the pipeline.
#include <CLI/CLI.hpp>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <utility>

#include "solver/blas_kernel.hpp"
#include "app/commands.hpp"
#include "cases/output_files.hpp"
#include "cases/spline_space.hpp"
#include "basis/core/input_error.hpp"
#include "solver/petsc_module.hpp"

namespace {

// The families' own preconditioners, for the help: "tensor: a, b; ..." from the registry.
std::string family_preconditioners() {
  std::string text;
  for (const auto& f : knotwork::space_families()) {
    if (f.structured_preconditioners.empty()) continue;
    text += (text.empty() ? "" : "; ") + f.name + ":";
    for (size_t k = 0; k < f.structured_preconditioners.size(); ++k)
      text += (k ? ", " : " ") + f.structured_preconditioners[k];
  }
  return text;
}

void add_common(CLI::App* cmd, knotwork::CommonOptions& o) {
  cmd->add_option("--degree", o.degree, "Polynomial degree in both directions (overrides [space] degree)");
  cmd->add_option("--elements", o.elements, "Elements per geometry knot span and direction (overrides [space] elements)");
  cmd->add_option("--out", o.out, "Output directory (overrides [output] directory; default results/<case name>)");
  cmd->add_option("--ordering", o.ordering, "Fill-reducing ordering for CHOLMOD: auto (amd on planar domains and surfaces, metis on volumes: fastest measured), amd, metis, nesdis, or default (CHOLMOD's own choice)")
      ->capture_default_str();
  cmd->add_option("--solver", o.solver,
                  "Linear solve: direct (CHOLMOD), iterative (preconditioned CG), auto, or petsc (PETSc's KSP, "
                  "distributed over the processes of mpirun -n N; overrides [solver] method)");
  cmd->add_option("--preconditioner", o.preconditioner,
                  "Iterative solve: auto (the family's first; on planar patches multigrid without a matrix from 2M functions), jacobi, "
                  "boomeramg, or the family's own (" + family_preconditioners() + ") (overrides [solver] preconditioner)");
  cmd->add_option("--matrix", o.matrix,
                  "Iterative solve: how CG gets K: assembled, matrix_free (applied by sum factorization, no matrix: "
                  "one-patch tensor spaces and volumes that are one affine map, constant coefficients, no Nitsche), or auto (the default: without a matrix "
                  "where that applies and every element is affine, assembled otherwise) (overrides [solver] matrix)");
  cmd->add_option("--tolerance", o.tolerance,
                  "Iterative solve (CG, and PETSc's KSP with --solver petsc): backward error to reach, "
                  "||b - Kx||/(||K|| ||x|| + ||b||) in the max norm (default 1e-15: the direct solve's errors) "
                  "(overrides [solver] tolerance)");
  cmd->add_option_function<std::string>(
      "--petsc-options",
      [&o](const std::string& v) {
        o.petsc_options = v;
        o.petsc_options_given = true;
      },
      "PETSc options for --solver petsc (after its default: CG with [solver] preconditioner, the space's own or "
      "BoomerAMG; e.g. \"-ksp_type preonly -pc_type cholesky -pc_factor_mat_solver_type mumps\", \"-log_view\") or "
      "for preconditioner boomeramg (overrides [solver] petsc_options)");
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

// The registered families that refine cells locally, for adapt's help.
std::string local_families() {
  std::string names;
  for (const auto& f : knotwork::space_families())
    if (f.local_refinement) names += (names.empty() ? "\"" : ", \"") + f.name + "\"";
  return names;
}

}  // namespace

// Thread defaults that do not collapse when the cores are shared (docs/PERFORMANCE.md):
// - CHOLMOD runs OpenMP regions of its own next to OpenBLAS's threads; with libgomp's
//   default spin-waiting they fight over the cores and the factorization is ~8% slower:
//   OMP_WAIT_POLICY=passive.
// - OpenBLAS's own threads spin too: beside two CPU-bound processes on the two cores the
//   solve took 15x (CHOLMOD) and 10x (CG) longer than with one OpenBLAS thread, which
//   costs 15-35% of the factorization when the machine is quiet: OPENBLAS_NUM_THREADS=1.
//   Assembly and error norms keep their OpenMP threads.
// And OpenBLAS's kernels where it does not know the CPU: OPENBLAS_CORETYPE (solver/blas_kernel.cpp).
// The libraries read these when they load, before main, so the only way to choose them
// from inside is to set them and start again. A user's own settings are kept.
void prefer_robust_defaults(char** argv) {
  bool changed = false;
  for (const auto& [name, value] : {std::pair{"OMP_WAIT_POLICY", "passive"}, std::pair{"OPENBLAS_NUM_THREADS", "1"}})
    if (std::getenv(name) == nullptr) {
      setenv(name, value, 1);
      changed = true;
    }
  if (std::getenv("OPENBLAS_CORETYPE") == nullptr) {
    const std::string kernel = knotwork::better_blas_kernel();
    if (!kernel.empty()) {
      setenv("OPENBLAS_CORETYPE", kernel.c_str(), 1);
      changed = true;
    }
  }
  if (changed) execv("/proc/self/exe", argv);  // returns only on failure: then run as we are
}

int main(int argc, char** argv) {
  prefer_robust_defaults(argv);
  knotwork::remove_partial_output_on_interrupt(knotwork::launched_world().rank == 0);
  CLI::App app{"knotwork: isogeometric Poisson solver (B-splines/NURBS -> Bezier extraction -> CHOLMOD -> ParaView)"};
  app.set_version_flag("--version", "knotwork 0.1.0");
  app.require_subcommand(1);

  knotwork::RunOptions run;
  CLI::App* run_cmd = app.add_subcommand("run", "Solve one case and write ParaView files");
  run_cmd->add_option("case", run.case_file,
                     "Case file (TOML or JSON), e.g. cases/square_sinsin.toml; cases/README.md lists the shipped ones. "
                     "Or a G+Smo problem file (.xml: domain, source, boundary conditions; docs/GUIDE.md)")
      ->required();
  add_common(run_cmd, run);
  run_cmd->add_flag("--condition", run.condition,
                  "Also estimate the condition numbers of the Jacobi-scaled stiffness and mass matrices (Lanczos; "
                  "serial solvers only)");
  run_cmd->add_flag("--no-output", run.no_output, "Write no files (timing and errors only)");
  run_cmd->add_flag("--allow-unverified-space,--allow-non-semi-regular,--allow-dependent", run.allow_unverified_space,
                    "Solve on a space that failed its family's own check (a given collection that is not "
                    "semi-regular, B-splines found linearly dependent: the matrix may be singular)");

  knotwork::ConvergeOptions conv;
  CLI::App* conv_cmd = app.add_subcommand("converge", "Uniform h-refinement study: errors and observed rates per level");
  conv_cmd->add_option("case", conv.case_file, "Case file (TOML or JSON, or a G+Smo problem file .xml) with an exact solution")->required();
  conv_cmd->add_option("--levels", conv.levels,
                      "Number of levels; level l is the case's space refined uniformly l times (elements doubled "
                      "per direction, or the quad mesh subdivided)")
      ->capture_default_str();
  add_common(conv_cmd, conv);
  conv_cmd->add_flag("--condition", conv.condition,
                  "Also estimate the condition numbers of the Jacobi-scaled stiffness and mass matrices (Lanczos; "
                  "serial solvers only)");

  knotwork::AdaptOptions adapt;
  CLI::App* adapt_cmd = app.add_subcommand(
      "adapt", "Adaptive refinement: solve, estimate (residual), mark (Doerfler or maximum), refine marked cells, repeat");
  adapt_cmd->add_option("case", adapt.case_file, "Case file (TOML or JSON) whose [space] family refines cells locally (" +
                                                     local_families() + ")")
      ->required();
  adapt_cmd->add_option("--steps", adapt.steps, "Number of solves (overrides [adapt] steps; default 10)");
  adapt_cmd->add_option("--theta", adapt.theta,
                        "Marking fraction in (0, 1]: Doerfler marks the fewest cells holding this share of the estimated "
                        "error squared, maximum every cell whose indicator is at least this share of the largest "
                        "(overrides [adapt] theta; default 0.5)")
      ->check([](const std::string& text) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(text.c_str(), &end);
        return *end == 0 && x > 0 && x <= 1 ? "" : "must be in (0, 1], got " + text;
      });
  adapt_cmd->add_option("--strategy", adapt.strategy,
                        "Marking strategy: dorfler (default) or maximum (overrides [adapt] strategy)")
      ->check(CLI::IsMember({"dorfler", "maximum"}));
  adapt_cmd->add_option("--min-fraction", adapt.min_fraction,
                        "Mark at least this share of the cells (or functions), largest indicators first, so that "
                        "every step grows the space (overrides [adapt] min_fraction; default 0)")
      ->check(CLI::Range(0.0, 1.0));
  adapt_cmd->add_option("--max-dofs", adapt.max_dofs, "Stop once a space has this many functions (overrides [adapt] max_dofs)");
  adapt_cmd->add_flag("--no-output", adapt.no_output, "Write no files (the table and timing only)");
  adapt_cmd->add_option("--output-every", adapt.output_every,
                        "ParaView files of every K-th step only, and of the last (default 1: every step; adapt.csv/json/svg always)");
  adapt_cmd->add_option("--marking", adapt.marking,
                        "What is marked: cells (default), or functions (their indicator the sum over the cells they "
                        "live on; the cells of their supports are refined) (overrides [adapt] marking)")
      ->check(CLI::IsMember({"cells", "functions"}));
  adapt_cmd->add_flag("--allow-dependent", adapt.allow_unverified_space,
                      "Go on when a refined space fails its family's own check (B-splines found linearly "
                      "dependent: the matrix may be singular)");
  add_common(adapt_cmd, adapt);
  // In adapt, "auto" and "multigrid" mean multigrid over the loop's steps (studies/adaptive.cpp).
  adapt_cmd->get_option("--preconditioner")
      ->description("Iterative solve in adapt: auto (the default) is CG with multigrid over the loop's steps where the "
                    "family's refinement gives its prolongation and measurements chose it, CHOLMOD elsewhere "
                    "(docs/ADAPTIVITY.md names the families); multigrid asks for it by name; jacobi or boomeramg; "
                    "--solver direct forces CHOLMOD (overrides [solver] preconditioner)");

  knotwork::BenchOptions bench;
  CLI::App* bench_cmd = app.add_subcommand(
      "bench", "Benchmark setup, assembly, the solve and error norms (unit square, sin*sin; or unit cube, sin*sin*sin)");
  bench_cmd->add_option("--config", bench.configs,
                        "DEGREE:ELEMENTS, repeatable (default 2:128 2:512 2:1024 4:64 4:256 4:512; on the cube "
                        "2:16 2:32 2:48 3:24 3:32 4:16, ELEMENTS per direction)");
  bench_cmd->add_flag("--quick", bench.quick, "Small configurations only (2:64 2:128 4:32 4:64; on the cube 2:8 2:16 3:8 4:8)");
  bench_cmd->add_option("--domain", bench.domain, "square (the unit square) or cube (the unit cube, hexahedra)")
      ->check(CLI::IsMember({"square", "cube"}))
      ->capture_default_str();
  bench_cmd->add_option("--ordering", bench.ordering, "auto (amd on planar domains and surfaces, metis on volumes), amd, metis, nesdis, or default (CHOLMOD's own choice)")->capture_default_str();
  bench_cmd->add_flag("--json", bench.json, "Print JSON instead of the table");
  bench_cmd->add_option("--solver", bench.solver, "direct (CHOLMOD) or iterative (CG with the space's preconditioner)")
      ->capture_default_str();
  bench_cmd->add_option("--tolerance", bench.tolerance, "--solver iterative: backward error to reach")->capture_default_str();
  bench_cmd->add_option("--preconditioner", bench.preconditioner,
                        "--solver iterative: auto (the space's own), jacobi, boomeramg or the family's own (" +
                            family_preconditioners() + ")")
      ->capture_default_str();
  bench_cmd->add_option("--matrix", bench.matrix,
                        "--solver iterative: how CG gets K: auto (without a matrix on affine elements, as run), "
                        "assembled or matrix_free")
      ->capture_default_str();
  bench_cmd->add_flag("!--no-errors", bench.with_errors, "Skip the error norms");
  bench_cmd->add_flag("--floor", bench.floor,
                      "Also time bare CHOLMOD with its default settings on the same matrix (the floor)");

  knotwork::BasisRequest basis;
  CLI::App* basis_cmd = app.add_subcommand(
      "basis", "Check a spline basis: partition of unity, rank, dimension and the family's own checks");
  basis_cmd->add_option("file", basis.file,
                        "Case file, T-mesh file (cells = [...], degree) or collection file (functions = [...], degree); "
                        "TOML or JSON");
  basis_cmd->add_option("--export", basis.export_file, "Write every function to this JSON file (the format is the family's)");
  CLI::Option* vtk_option = basis_cmd->add_option("--vtk", basis.vtk_file);
  CLI::Option* show_option = basis_cmd->add_option("--show", basis.show);
  basis_cmd->add_flag("--json", basis.json, "Print one JSON object");
  // Each family adds its own mode (a space on a quad mesh, on a T-mesh file, ...) and its options, and
  // says what --vtk writes for it.
  std::vector<std::unique_ptr<knotwork::BasisTool>> basis_tools;
  for (const auto& f : knotwork::space_families())
    if (f.add_basis_tool) basis_tools.push_back(f.add_basis_tool(*basis_cmd));
  std::string writers, shows;
  for (const auto& t : basis_tools)
    if (!t->show_help().empty()) {
      writers += (writers.empty() ? "" : ", ") + t->selector();
      shows += "; " + t->selector() + ": " + t->show_help();
    }
  vtk_option->description("Write the basis with the --show functions as fields to this .vtu (" + writers + ")");
  show_option->description("--vtk: the functions to write" + shows);

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
  // Under mpirun: run and converge share the solve among the processes (--solver petsc); rank
  // 0 alone prints and writes, the others stay quiet.
  const knotwork::ParallelWorld launched = knotwork::launched_world();
  if (launched.size > 1) {
    if (!*run_cmd && !*conv_cmd) {
      if (launched.rank == 0)
        print_error("under mpirun (" + std::to_string(launched.size) +
                    " processes) only `run` and `converge` work, with --solver petsc; start other commands without mpirun");
      return 2;
    }
    if (launched.rank > 0) {
      run.quiet = conv.quiet = true;
      if (!std::freopen("/dev/null", "w", stdout)) return 1;
    }
  }
  // An error every rank met alike (the input, or one rank's failure shared with all) is
  // printed by rank 0 only.
  const auto report = [&](const std::string& message) {
    if (launched.rank == 0 || !knotwork::failure_shared_by_all_ranks()) print_error(message);
  };
  try {
    if (*run_cmd) return knotwork::run_command(run);
    if (*conv_cmd) return knotwork::converge_command(conv);
    if (*adapt_cmd) return knotwork::adapt_command(adapt);
    if (*bench_cmd) return knotwork::bench_command(bench);
    if (*dim_cmd) return knotwork::dimension_command(dim);
    if (*basis_cmd) return knotwork::basis_command(basis, basis_tools);
  } catch (const knotwork::InputError& e) {
    if (launched.rank == 0) print_error(e.what());  // the input's errors are the same on every rank
    return 2;
  } catch (const std::bad_alloc&) {
    report("out of memory (try fewer elements or a lower degree)");
    return 3;
  } catch (const std::exception& e) {
    report(e.what());
    return 1;
  }
  return 0;
}
