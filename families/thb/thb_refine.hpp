#pragma once
// One refinement step of a THB space, on one patch (ThbHierarchy, ThbCell) or several
// (ThbMultiPatch, ThbPatchCell): the marked mesh cells' leaves halved, with what grading and
// the interfaces add; bad requests and sizes refused as the case's errors.
#include <stdexcept>
#include <string>
#include <vector>

#include "basis/core/input_error.hpp"
#include "cases/case_file.hpp"
#include "basis/thb/thb_hierarchy.hpp"
#include "cases/spline_space.hpp"
#include "families/tensor/tensor_case.hpp"

namespace knotwork {

// The hierarchy's basis; its failure as the case's [space] error.
inline ThbHierarchy::Basis built_basis(const CaseDescription& c, const ThbHierarchy& h) {
  try {
    return h.build();
  } catch (const std::runtime_error& e) {
    throw InputError(c.path + ": [space]: " + e.what());
  }
}

// `knotwork basis`'s line of a THB space: its functions per level.
inline ReportField functions_per_level_field(const std::vector<int>& per_level) {
  std::string text;
  std::vector<std::string> counts;
  for (size_t l = 0; l < per_level.size(); ++l) {
    text += (l ? ", " : "") + std::to_string(per_level[l]);
    counts.push_back(std::to_string(per_level[l]));
  }
  return {.key = "functions_per_level", .value = counts, .text = text, .label = "per level"};
}

template <class Hierarchy, class Leaf>
Hierarchy refined_hierarchy(const CaseDescription& c, const Hierarchy& hierarchy, const std::vector<Leaf>& leaves,
                            const std::vector<int>& marked, int* extended) {
  // THB refinement halves a cell in both directions; a split direction does not apply.
  std::vector<Leaf> cells;
  cells.reserve(marked.size());
  for (int m : marked) cells.push_back(leaves.at(m));
  Hierarchy next = hierarchy;
  int extra = 0;
  try {
    extra = next.refine(cells);
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": [space]: " + e.what());
  }
  if (extended) *extended = extra;
  check_refined_memory(c, double(next.num_leaves()), "THB");
  return next;
}

}  // namespace knotwork
