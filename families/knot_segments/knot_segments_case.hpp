#pragma once
// The [space] of family "knot_segments", and collection files (B-splines by their local knot
// vectors: what `knotwork basis --export` writes and [space] collection reads).
#include <string>
#include <vector>

#include "basis/knot_segments/semi_regular_collection.hpp"
#include "families/tensor/tensor_case.hpp"

namespace knotwork {

struct KnotSegmentsSection : PatchSpaceSection {
  std::vector<KnotInsertion> segments;  // inserted in order, parameter coordinates
  std::string collection_file;          // a collection given explicitly ([space] collection), resolved
  std::vector<LocalBSpline> collection;  // its functions, not yet checked for semi-regularity
  // [space] extension: how a segment that does not refine or breaks semi-regularity is extended.
  SemiRegularCollection::Extension extension = SemiRegularCollection::Extension::kGalloping;
  // The names [space] extension takes, in the order of SemiRegularCollection::Extension.
  static constexpr const char* kExtensionNames[] = {"galloping", "directed", "minimal"};
  std::unique_ptr<CaseSection> clone() const override { return std::make_unique<KnotSegmentsSection>(*this); }
};

inline KnotSegmentsSection& knot_segments_section(CaseDescription& c) { return family_section<KnotSegmentsSection>(c); }
inline const KnotSegmentsSection& knot_segments_section(const CaseDescription& c) {
  return family_section<KnotSegmentsSection>(c);
}

// The keys [space] takes.
const std::vector<std::string>& knot_segments_space_keys();

void read_knot_segments_case(const CaseDocument& doc, CaseDescription& c);

// A collection file (JSON or TOML):
//   degree = [dx, dy]
//   functions = [{x = [dx+2 knots], y = [dy+2 knots]}, ...]
struct CollectionDescription {
  int dx = 2, dy = 2;
  std::vector<LocalBSpline> splines;
};
// Throws InputError naming the file and the field.
CollectionDescription load_collection(const std::string& path);

}  // namespace knotwork
