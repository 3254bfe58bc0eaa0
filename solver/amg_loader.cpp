// Loads the BoomerAMG module (solver/amg_preconditioner.cpp) on first use, so that runs
// that do not ask for it do not load PETSc and its libraries.
#include <dlfcn.h>

#include <cstdlib>
#include <mutex>
#include <stdexcept>

#include "solver/amg_preconditioner.hpp"

namespace knotwork {

namespace {

using Factory = Preconditioner* (*)(const Eigen::SparseMatrix<double>&, const std::string&);

Factory load_factory() {
  static std::once_flag once;
  static Factory factory = nullptr;
  static std::string error;
  std::call_once(once, [] {
    const char* given = std::getenv("KNOTWORK_AMG_MODULE");
    const std::string path = given && *given ? given : KNOTWORK_AMG_MODULE;
    void* module = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!module) {
      error = "boomeramg: cannot load " + path + " (" + dlerror() + "); rebuild knotwork, or set KNOTWORK_AMG_MODULE";
      return;
    }
    factory = reinterpret_cast<Factory>(dlsym(module, "knotwork_boomeramg"));
    if (!factory) error = "boomeramg: " + path + " has no knotwork_boomeramg";
  });
  if (!factory) throw std::runtime_error(error);
  return factory;
}

}  // namespace

std::unique_ptr<Preconditioner> boomeramg_preconditioner(const Eigen::SparseMatrix<double>& lower,
                                                         const std::string& petsc_options) {
  return std::unique_ptr<Preconditioner>(load_factory()(lower, petsc_options));
}

}  // namespace knotwork
