// Case files (KNOTWORK_FUZZ_EXTENSION toml, json, or xml: a G+Smo problem file): load_case
// reads the top level, the
// family's [space] (with the files it names: T-meshes, collections, OBJ meshes, gluing data,
// NURBS patches) and derives the problem symbolically. For a case that loads, the cheap
// checks every command makes before building: the command-line overrides and the family's
// refusals for `converge` and `adapt`.
#include "cases/case_file.hpp"
#include "cases/spline_space.hpp"
#include "fuzz/fuzz_input.hpp"
#include "basis/core/input_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = knotwork_fuzz::scratch_file(data, size, std::string("case.") + KNOTWORK_FUZZ_EXTENSION);
  knotwork::CaseDescription c;
  try {
    c = knotwork::load_case(path);
  } catch (const knotwork::InputError&) {
    return 0;
  }
  const knotwork::SpaceFamily& family = knotwork::space_family(c);
  try {
    if (family.check_converge) family.check_converge(c, 2);
  } catch (const knotwork::InputError&) {
  }
  try {
    knotwork::check_adaptive_family(c);
  } catch (const knotwork::InputError&) {
  }
  try {
    knotwork::override_solver(c, "iterative", 1e-10);
  } catch (const knotwork::InputError&) {
  }
  return 0;
}
