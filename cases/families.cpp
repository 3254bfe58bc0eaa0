// The registration of the spline families: one line each. A new family is a folder in
// basis/ plus one line here (docs/ARCHITECTURE.md).
#include "cases/spline_space.hpp"
#include "solver/input_error.hpp"

namespace knotwork {

SpaceFamily tensor_family();
SpaceFamily knot_segments_family();
SpaceFamily pt_family();
SpaceFamily g1_family();

const std::vector<SpaceFamily>& space_families() {
  static const std::vector<SpaceFamily> families{tensor_family(), knot_segments_family(), pt_family(), g1_family()};
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
