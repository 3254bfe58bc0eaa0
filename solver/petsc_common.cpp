// The PETSc module's shared parts (solver/petsc_common.hpp).
#include "solver/petsc_common.hpp"

// AddressSanitizer's builds (gcc defines the first, clang answers the second).
#if defined(__SANITIZE_ADDRESS__)
#define KNOTWORK_LSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define KNOTWORK_LSAN 1
#endif
#endif
#ifdef KNOTWORK_LSAN
#include <sanitizer/lsan_interface.h>
#endif

#include <cstdlib>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace knotwork {

// PETSc's error code as an exception with PETSc's own message.
void check(PetscErrorCode code, const char* what) {
  if (code == 0) return;
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  throw std::runtime_error(std::string("PETSc: ") + what + ": " + (text ? text : "error " + std::to_string(code)));
}

// OpenMPI (under PETSc) allocates in MPI_Init, frees part of it in MPI_Finalize and unloads its
// components, so LeakSanitizer reports blocks whose stacks end in unloaded modules, which no
// suppression can name. They are not knotwork's: in the sanitizer build (docs/RELIABILITY.md)
// what PETSc's initialisation and finalisation allocate is not leak-checked; everything after
// it (matrices, preconditioners: knotwork's to free) is.
#ifdef KNOTWORK_LSAN
struct NoLeakCheck {
  NoLeakCheck() { __lsan_disable(); }
  ~NoLeakCheck() { __lsan_enable(); }
};
#else
struct NoLeakCheck {
  NoLeakCheck() {}  // user-provided: a guard object is not an unused variable
};
#endif

void initialize_petsc() {
  static std::once_flag once;
  std::call_once(once, [] {
    const NoLeakCheck third_party;
    // No signal handlers: Ctrl-C and crashes stay the program's (and Python's) to handle.
    check(PetscOptionsSetValue(nullptr, "-no_signal_handler", nullptr), "options");
    check(PetscInitializeNoArguments(), "initialization");
    // Errors come back as codes (and exceptions here) instead of tracebacks on stderr.
    check(PetscPushErrorHandler(PetscReturnErrorHandler, nullptr), "error handler");
    std::atexit([] {
      const NoLeakCheck finalization;
      PetscFinalize();
    });
  });
}


ScopedOptions::ScopedOptions(const std::string& prefix, const std::string& options) : prefix_(prefix) {
  std::istringstream words(options);
  for (std::string w; words >> w;) {
    if (w.size() < 2 || w[0] != '-' || (w[1] >= '0' && w[1] <= '9')) {
      if (given_.empty() || !given_.back().second.empty())
        throw std::invalid_argument("\"" + w + "\" is not a PETSc option (options start with '-')");
      given_.back().second = w;
    } else {
      given_.emplace_back(w.substr(1), "");
    }
  }
  for (const auto& [name, value] : given_)
    check(PetscOptionsSetValue(nullptr, ("-" + prefix_ + name).c_str(), value.empty() ? nullptr : value.c_str()),
          "options");
}

ScopedOptions::~ScopedOptions() {
  for (const auto& given : given_) PetscOptionsClearValue(nullptr, ("-" + prefix_ + given.first).c_str());
}

void ScopedOptions::read(const std::function<PetscErrorCode()>& set_from_options) const {
  PetscErrorCode code;
  {
    // PETSc's option parsing returns from an error (a value it cannot read) without freeing
    // the strings PetscOptionsBegin allocated: PETSc's leak, on the path where knotwork
    // refuses the options anyway.
    const NoLeakCheck petsc_error_path;
    code = set_from_options();
  }
  if (code != 0) {
    const char* text = nullptr;
    PetscErrorMessage(code, &text, nullptr);
    throw std::invalid_argument(std::string("PETSc could not read them: ") + (text ? text : "error"));
  }
}

bool ScopedOptions::sets(const std::string& name) const {
  for (const auto& given : given_)
    if (given.first == name) return true;
  return false;
}

std::string ScopedOptions::unused() const {
  std::string names;
  for (const auto& given : given_) {
    PetscBool used = PETSC_FALSE;
    // The database stores names without the dash, and this lookup compares them as stored.
    PetscOptionsUsed(nullptr, (prefix_ + given.first).c_str(), &used);
    if (!used) names += (names.empty() ? "-" : ", -") + given.first;
  }
  return names;
}

}  // namespace knotwork
