#include "cases/boundary_labels.hpp"

#include <algorithm>

namespace knotwork {

std::vector<int> BoundaryLabels::resolve(const std::string& name) const {
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return {static_cast<int>(i)};
  for (const auto& [label, ids] : groups)
    if (label == name) return ids;
  return {};
}

std::vector<std::string> BoundaryLabels::all_names() const {
  std::vector<std::string> out = names;
  for (const auto& g : groups) out.push_back(g.first);
  return out;
}

namespace {

// A file's labels as groups of the exterior sides' ids (their positions in `exterior`).
void add_groups(BoundaryLabels& l, const std::vector<NamedBoundary>& boundaries, const std::vector<PatchSideRef>& exterior) {
  for (const NamedBoundary& b : boundaries) {
    std::vector<int> ids;
    for (const PatchSideRef& s : b.sides) ids.push_back(static_cast<int>(std::find(exterior.begin(), exterior.end(), s) - exterior.begin()));
    l.groups.emplace_back(b.name, ids);
  }
}

}  // namespace

BoundaryLabels boundary_labels(const CaseDescription& c) {
  BoundaryLabels l;
  const MultiPatch& d = c.domain;
  if (c.multipatch()) {
    const std::vector<PatchSideRef> exterior = exterior_sides(d);
    for (const PatchSideRef& s : exterior) l.names.push_back(side_name(d, s));
    add_groups(l, d.boundaries, exterior);
    return l;
  }
  if (c.multivolume()) {
    // One id per exterior face (exterior_faces), named "P:F"; the file's labels name groups.
    const MultiVolume& d = c.volume_domain;
    const std::vector<PatchSideRef> exterior = exterior_faces(d);
    l.names = exterior_face_names(d, exterior);
    add_groups(l, d.boundaries, exterior);
    return l;
  }
  if (c.is_volume()) {
    // A volume's ids 0..5 are its sides u = 0, u = 1, v = 0, v = 1, w = 0, w = 1: named as a
    // patch's sides (left: u = 0, bottom: v = 0) and front/back along w, and "1".."6".
    // A file's own labels win over "1".."6", as on a patch.
    l.names = {"left", "right", "bottom", "top", "front", "back"};
    for (const NamedBoundary& b : c.volume_boundaries) {
      std::vector<int> ids;
      for (const PatchSideRef& s : b.sides) ids.push_back(s.side - 1);
      l.groups.emplace_back(b.name, ids);
    }
    for (int s = 1; s <= 6; ++s)
      if (l.resolve(std::to_string(s)).empty()) l.groups.emplace_back(std::to_string(s), std::vector<int>{s - 1});
    if (!c.volume_removed_boxes.empty()) l.names.push_back("hole");  // id 6: the faces of the removed parts
    return l;
  }
  l.names = {"bottom", "right", "top", "left"};
  // Side s of the files is the mesh's id of that cell side (bottom 0, right 1, top 2, left 3).
  auto id_of_side = [](int side) { return static_cast<int>(cell_side_of_patch_side(side)); };
  for (const NamedBoundary& b : d.boundaries) {
    std::vector<int> ids;
    for (const PatchSideRef& s : b.sides) ids.push_back(id_of_side(s.side));
    l.groups.emplace_back(b.name, ids);
  }
  if (d.num_patches() == 1)
    for (int s = 1; s <= 4; ++s) l.groups.emplace_back(side_name(d, {0, s}), std::vector<int>{id_of_side(s)});
  for (int s = 1; s <= 4; ++s)
    if (l.resolve(std::to_string(s)).empty()) l.groups.emplace_back(std::to_string(s), std::vector<int>{id_of_side(s)});
  return l;
}

}  // namespace knotwork
