// The registry of the spline families. A new family is a construction folder in basis/, a plugin
// folder here and its name in KNOTWORK_FAMILIES (families/CMakeLists.txt), from which the build
// generates the list below (docs/ARCHITECTURE.md).
#include <algorithm>

#include "cases/spline_space.hpp"
#include "basis/core/input_error.hpp"
#include "solver/amg_preconditioner.hpp"

namespace knotwork {

#include "registered_families.inc"

const std::vector<SpaceFamily>& space_families() {
  static const std::vector<SpaceFamily> families{KNOTWORK_REGISTERED_FAMILIES};
  return families;
}

const SpaceFamily& space_family(const CaseDescription& c) {
  std::string names;
  for (const SpaceFamily& f : space_families()) {
    if (f.name == c.family) return f;
    names += (names.empty() ? "" : ", ") + f.name;
  }
  throw InputError(c.path + ": [space] family: '" + c.family + "' is not a registered family (" + names + ")");
}

std::vector<std::string> preconditioner_names() {
  std::vector<std::string> names{"auto", "jacobi", kBoomerAmgName};
  for (const SpaceFamily& f : space_families())
    for (const std::string& name : f.structured_preconditioners)
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  return names;
}

void check_adaptive_family(const CaseDescription& c) {
  const SpaceFamily& family = space_family(c);
  if (!family.local_refinement) {
    std::string names;
    for (const SpaceFamily& f : space_families())
      if (f.local_refinement) names += (names.empty() ? "\"" : ", \"") + f.name + "\"";
    throw InputError(c.path + ": [space] family: \"" + c.family +
                     "\" does not refine cells locally, which adaptive refinement needs (families that do: " + names + ")");
  }
  if (family.check_adapt) family.check_adapt(c);
}

}  // namespace knotwork
