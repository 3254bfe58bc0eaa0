#pragma once
// What the PETSc module's parts share (inside libknotwork_petsc.so only: this header includes
// PETSc's): errors as exceptions, one initialization, and the user's options checked.
#include <petscsys.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace knotwork {

// PETSc's error code as an exception with PETSc's own message.
void check(PetscErrorCode code, const char* what);

// Initializes PETSc (and MPI: under mpirun, the whole world) once, without PETSc's signal
// handlers, with errors returned as codes; finalized at exit.
void initialize_petsc();

// The user's options ("-ksp_type cg -pc_type hypre") in PETSc's database under `prefix` while
// this object lives (the objects they are for carry the prefix, so nothing else reads them).
// The constructor throws std::invalid_argument for a word that is not an option; read() runs
// set_from_options (e.g. KSPSetFromOptions), throwing std::invalid_argument for a value PETSc
// cannot read; unused() names those nobody has read so far ("-a, -b"; empty when all were):
// ask after the setup, where factorizations read theirs (-mat_mumps_icntl_...).
class ScopedOptions {
 public:
  ScopedOptions(const std::string& prefix, const std::string& options);
  ~ScopedOptions();
  ScopedOptions(const ScopedOptions&) = delete;
  ScopedOptions& operator=(const ScopedOptions&) = delete;
  void read(const std::function<PetscErrorCode()>& set_from_options) const;
  std::string unused() const;
  bool sets(const std::string& name) const;  // name without the dash and prefix

 private:
  std::string prefix_;
  std::vector<std::pair<std::string, std::string>> given_;
};

}  // namespace knotwork
