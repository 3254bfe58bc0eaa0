#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>

#include "solver/blas_kernel.hpp"
#include "app/commands.hpp"
#include "studies/bench_study.hpp"
#include "studies/pipeline.hpp"
#include "cases/json_output.hpp"
#include "cases/case_reader.hpp"
#include "cases/geometries.hpp"
#include "cases/spline_space.hpp"
#include "basis/core/input_error.hpp"
#include "solver/linear_solver.hpp"
#include "solver/poisson_solver.hpp"

namespace knotwork {

namespace {

// Each configuration runs in a child process so that its peak memory is its own.
BenchResult run_isolated(int p, int n, Ordering ordering, bool with_errors, bool floor, const BenchOptions& o) {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("bench: pipe failed");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("bench: fork failed");
  if (pid == 0) {
    close(fds[0]);
    BenchResult r;
    int code = 0;
    try {
      r = bench_configuration(p, n, ordering, with_errors, floor, o.solver, o.tolerance, o.preconditioner, o.matrix,
                              o.domain == "cube");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "knotwork bench: p=%d n=%d failed: %s\n", p, n, e.what());
      code = 1;
    }
    if (write(fds[1], &r, sizeof r) != static_cast<ssize_t>(sizeof r)) code = 1;
    close(fds[1]);
    _exit(code);
  }
  close(fds[1]);
  BenchResult r;
  const ssize_t got = read(fds[0], &r, sizeof r);
  close(fds[0]);
  int status = 0;
  struct rusage usage;
  wait4(pid, &status, 0, &usage);
  if (got != static_cast<ssize_t>(sizeof r) || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error("bench: configuration p=" + std::to_string(p) + " n=" + std::to_string(n) + " failed");
  r.peak_rss_kb = usage.ru_maxrss;
  return r;
}

}  // namespace

int bench_command(const BenchOptions& o) {
  std::vector<std::pair<int, int>> configs;
  std::vector<std::string> specs = o.configs;
  const bool cube = o.domain == "cube";
  if (specs.empty() && cube)
    specs = o.quick ? std::vector<std::string>{"2:8", "2:16", "3:8", "4:8"}
                    : std::vector<std::string>{"2:16", "2:32", "2:48", "3:24", "3:32", "4:16"};
  else if (specs.empty())
    specs = o.quick ? std::vector<std::string>{"2:64", "2:128", "4:32", "4:64"}
                    : std::vector<std::string>{"2:128", "2:512", "2:1024", "4:64", "4:256", "4:512"};
  // At most 2^26 cells, as a case file allows: 8192^2 on the square, 406^3 on the cube.
  const int most = cube ? 406 : 4096;
  for (const auto& s : specs) {
    int p = 0, n = 0;
    char extra;
    if (std::sscanf(s.c_str(), "%d:%d%c", &p, &n, &extra) != 2 || p < 1 || p > 10 || n < 1 || n > most)
      throw InputError("--config: '" + s + "' is not DEGREE:ELEMENTS (degree 1..10, elements 1.." + std::to_string(most) +
                       (cube ? " per direction on the cube" : "") + "), e.g. " + (cube ? "2:32" : "2:512"));
    configs.emplace_back(p, n);
  }
  const Ordering ordering = parse_ordering(o.ordering);
  if (o.solver != "direct" && o.solver != "iterative")
    throw InputError("--solver: '" + o.solver + "' is not direct or iterative");
  if (!(o.tolerance > 0 && o.tolerance < 1)) throw InputError("--tolerance: must be in (0, 1)");
  if (o.solver == "iterative" && o.floor) throw InputError("--floor: times CHOLMOD, not used with --solver iterative");
  checked_name(o.preconditioner, preconditioner_names(), "--preconditioner", "");
  if (o.solver != "iterative" && o.preconditioner != "auto")
    throw InputError("--preconditioner: used with --solver iterative only");
  checked_name(o.matrix, {"auto", "assembled", "matrix_free"}, "--matrix", "");
  if (o.solver != "iterative" && o.matrix != "auto") throw InputError("--matrix: used with --solver iterative only");
  const bool cg = o.solver == "iterative";
  std::vector<BenchResult> results;
  // The BLAS kernel belongs with the figures: on generic kernels the same CPU factorized 2-2.5x slower.
  const std::string kernel = blas_kernel();
  const std::string kernel_text = kernel.empty() ? "not OpenBLAS" : "OpenBLAS kernel " + kernel;
  const char* problem = cube ? "unit cube, u = sin(pi x) sin(pi y) sin(pi z)" : "unit square, u = sin(pi x) sin(pi y)";
  if (!o.json && cg)
    std::printf("knotwork bench: %s, %u hardware threads, %s, CG + %s "
                "to backward error %.0e\n%3s %6s %9s %10s %6s %8s %8s %8s %8s %7s %8s %9s\n",
                problem, std::thread::hardware_concurrency(), kernel_text.c_str(),
                o.preconditioner == "auto" ? "the space's preconditioner" : o.preconditioner.c_str(), o.tolerance, "p", "n", "dofs", "nnz(A)", "iters", "setup", "assemb",
                "precond", "CG", "errors", "total", "peak RSS");
  else if (!o.json)
    std::printf("knotwork bench: %s, %u hardware threads, %s, ordering %s\n"
                "%3s %6s %9s %10s %11s %8s %8s %8s %8s %7s %7s %8s %9s %9s%s\n",
                problem, std::thread::hardware_concurrency(), kernel_text.c_str(), o.ordering.c_str(), "p", "n", "dofs", "nnz(A)", "nnz(L)",
                "setup", "assemb", "analyze", "factor", "solve", "errors", "total", "CHOLMOD", "peak RSS", o.floor ? "    floor" : "");
  for (const auto& [p, n] : configs) {
    const BenchResult r = run_isolated(p, n, ordering, o.with_errors, o.floor, o);
    results.push_back(r);
    if (!o.json && cg) {
      std::printf("%3d %6d %9ld %10ld %6d %8.3f %8.3f %8.3f %8.3f %7.3f %8.3f %6.0f MB\n", r.degree, r.elements, r.dofs,
                  r.matrix_nonzeros, r.iterations, r.setup, r.assembly, r.preconditioner, r.cg, r.errors, r.total,
                  r.peak_rss_kb / 1e3);
      std::fflush(stdout);
    } else if (!o.json) {
      std::printf("%3d %6d %9ld %10ld %11.0f %8.3f %8.3f %8.3f %8.3f %7.3f %7.3f %8.3f %7.0f MB %6.0f MB", r.degree,
                  r.elements, r.dofs, r.matrix_nonzeros, r.factor_nonzeros, r.setup, r.assembly, r.analysis,
                  r.factorization, r.solve, r.errors, r.total, r.cholmod_peak_bytes / 1e6, r.peak_rss_kb / 1e3);
      if (o.floor) std::printf(" %8.3f", r.floor_seconds);
      std::printf("\n");
      std::fflush(stdout);
    }
  }
  if (!o.json && cg) {
    for (const BenchResult& r : results)
      if (r.matrix_nonzeros == 0) {
        std::printf("nnz(A) 0: CG applied K without a matrix ([solver] matrix = \"auto\" on affine elements: "
                    "docs/SOLVERS.md, \"Without a matrix\")\n");
        break;
      }
    if (o.preconditioner == "auto") {  // what "auto" chose, configuration by configuration
      std::printf("preconditioner (auto):");
      for (const BenchResult& r : results) std::printf(" %d:%d %s", r.degree, r.elements, r.preconditioner_name);
      std::printf("\n");
    }
  }
  if (o.json) {
    Json arr = Json::array();
    for (const auto& r : results) {
      Json j = Json::object();
      j.set("degree", r.degree).set("elements", r.elements).set("dofs", r.dofs).set("free_dofs", r.free_dofs)
          .set("matrix_nonzeros", r.matrix_nonzeros).set("factor_nonzeros", r.factor_nonzeros).set("flops", r.flops)
          .set("setup", r.setup).set("assembly", r.assembly).set("analysis", r.analysis)
          .set("factorization", r.factorization).set("solve", r.solve).set("errors", r.errors).set("total", r.total)
          .set("cholmod_peak_bytes", r.cholmod_peak_bytes).set("peak_rss_bytes", r.peak_rss_kb * 1024.0)
          .set("l2_error", r.l2).set("cholmod_default_floor_seconds", r.floor_seconds)
          .set("assembly_method", std::string(r.assembly_name));
      if (cg)
        j.set("solver", Json::object().set("method", "iterative").set("preconditioner", std::string(r.preconditioner_name))
                            .set("matrix", r.matrix_nonzeros == 0 ? "matrix_free" : "assembled")
                            .set("iterations", r.iterations).set("relative_residual", r.relative_residual)
                            .set("tolerance", o.tolerance))
            .set("preconditioner", r.preconditioner).set("iterations", r.cg);
      arr.push(j);
    }
    Json root = Json::object();
    root.set("domain", o.domain).set("ordering", o.ordering).set("threads", static_cast<int>(std::thread::hardware_concurrency()))
        .set("blas_kernel", kernel)
        .set("results", arr);
    std::printf("%s\n", root.dump().c_str());
  }
  return 0;
}

}  // namespace knotwork
