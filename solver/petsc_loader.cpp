// Loads the PETSc module (libknotwork_petsc.so: solver/petsc_solver.cpp, amg_preconditioner.cpp)
// on first use, so that runs that do not ask for PETSc do not load it and its ~85 libraries.
#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <string>

#include "solver/amg_preconditioner.hpp"
#include "solver/petsc_module_api.hpp"

namespace knotwork {

namespace {

// Where the module is: next to the file that holds this code when it is there (an installed
// Python package: knotwork/_core*.so and knotwork/libknotwork_petsc.so), else where the build
// put it.
std::string module_path() {
  Dl_info self{};
  if (dladdr(reinterpret_cast<void*>(&module_path), &self) && self.dli_fname) {
    std::string next = self.dli_fname;
    next = next.substr(0, next.find_last_of('/') + 1) + "libknotwork_petsc.so";
    if (access(next.c_str(), R_OK) == 0) return next;
  }
  return KNOTWORK_PETSC_MODULE;
}

const PetscModuleApi& api() {
  static std::once_flag once;
  static const PetscModuleApi* table = nullptr;
  static std::string error;
  std::call_once(once, [] {
    const char* given = std::getenv("KNOTWORK_PETSC_MODULE");
    const std::string path = given && *given ? given : module_path();
    void* module = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!module) {
      error = "PETSc module: cannot load " + path + " (" + dlerror() + "); rebuild knotwork, or set KNOTWORK_PETSC_MODULE";
      return;
    }
    using Entry = const PetscModuleApi* (*)();
    const auto entry = reinterpret_cast<Entry>(dlsym(module, "knotwork_petsc_api"));
    if (!entry) error = "PETSc module: " + path + " has no knotwork_petsc_api";
    else table = entry();
  });
  if (!table) throw std::runtime_error(error);
  return *table;
}

int environment_number(const char* name, int otherwise) {
  const char* text = std::getenv(name);
  if (!text || !*text) return otherwise;
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  return *end == '\0' && v >= 0 && v < (1L << 30) ? static_cast<int>(v) : otherwise;
}

}  // namespace

std::unique_ptr<Preconditioner> boomeramg_preconditioner(const Eigen::SparseMatrix<double>& lower,
                                                         const std::string& petsc_options) {
  return std::unique_ptr<Preconditioner>(api().boomeramg(lower, petsc_options));
}

ParallelWorld parallel_world() { return api().world(); }

ParallelWorld launched_world() {
  // OpenMPI's variables, then the PMI ones of MPICH and Slurm.
  ParallelWorld w;
  w.size = environment_number("OMPI_COMM_WORLD_SIZE", environment_number("PMI_SIZE", 1));
  w.rank = environment_number("OMPI_COMM_WORLD_RANK", environment_number("PMI_RANK", 0));
  if (w.size < 1 || w.rank >= w.size) w = ParallelWorld{};
  return w;
}

void sum_over_ranks(double* values, int n) {
  if (launched_world().size > 1) api().reduce(values, n, false);
}

void max_over_ranks(double* values, int n) {
  if (launched_world().size > 1) api().reduce(values, n, true);
}

namespace {
bool shared_failure = false;
}  // namespace

std::optional<RankFailure> agree_on_failure(int kind, const std::string& message) {
  std::optional<RankFailure> f;
  if (launched_world().size == 1) {
    if (kind != 0) f = RankFailure{0, kind, message};
  } else {
    f = api().agree_on_failure(kind, message);
  }
  if (f) shared_failure = true;
  return f;
}

bool failure_shared_by_all_ranks() { return shared_failure; }

void broadcast_from_first(std::string& text) {
  if (launched_world().size > 1) api().broadcast(text);
}

std::vector<double> gather_from_all_ranks(const std::vector<double>& mine) {
  return launched_world().size > 1 ? api().gather_all(mine) : mine;
}

std::unique_ptr<DistributedSystem> make_distributed_system(int num_free, int first_row, int last_row) {
  return std::unique_ptr<DistributedSystem>(api().make_system(num_free, first_row, last_row));
}

}  // namespace knotwork
