#pragma once
// The [space] of family "pt": PT-splines over a T-mesh in the geometry's parameter domain.
// The start is `cells` (inline or from [space] tmesh) or else the tensor grid of the
// geometry's knot spans; every start cell is cut into `elements` parts, then `segments` are
// inserted (exact rationals).
#include <string>
#include <vector>

#include "basis/pt/pt_spline.hpp"
#include "families/tensor/tensor_case.hpp"

namespace knotwork {

struct PtSection : PatchSpaceSection {
  std::vector<RationalBox> cells;
  std::vector<AxisSegment> segments;
  std::string tmesh_file;  // resolved; empty for inline cells or the tensor start
  PtExtension extension = PtExtension::kAuto;
  std::unique_ptr<CaseSection> clone() const override { return std::make_unique<PtSection>(*this); }
};

inline PtSection& pt_section(CaseDescription& c) { return family_section<PtSection>(c); }
inline const PtSection& pt_section(const CaseDescription& c) { return family_section<PtSection>(c); }

// The keys [space] takes.
const std::vector<std::string>& pt_space_keys();

void read_pt_case(const CaseDocument& doc, CaseDescription& c);

}  // namespace knotwork
