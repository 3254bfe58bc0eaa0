#pragma once
// The names a case file may give to the boundary ids of its mesh ([problem] dirichlet and
// neumann). One patch: bottom, right, top, left (ids 0..3), also "1".."4" in the files' side
// numbering (1: u = 0, 2: u = 1, 3: v = 0, 4: v = 1) and, read from a file, "P:S" and the
// file's own labels, which win over "1".."4". A volume: left, right, bottom, top, front,
// back (ids 0..5: u = 0, u = 1, v = 0, v = 1, w = 0, w = 1), "1".."6" and a file's labels, which
// win over "1".."6"; with removed parts (the Fichera corner) "hole" (id 6) is their faces. Several patches: one id per exterior side
// (exterior_sides), named "P:S" with the file's patch label, and the file's labels, each
// naming several sides.
#include <string>
#include <vector>

#include "cases/case_file.hpp"

namespace knotwork {

struct BoundaryLabels {
  std::vector<std::string> names;  // of each id
  std::vector<std::pair<std::string, std::vector<int>>> groups;  // further names and their ids
  // The ids a name stands for; empty when it names nothing.
  std::vector<int> resolve(const std::string& name) const;
  std::vector<std::string> all_names() const;
};

BoundaryLabels boundary_labels(const CaseDescription& c);

}  // namespace knotwork
