// Reading [space] of family "pt" (see pt_case.hpp).
#include "families/pt/pt_case.hpp"

#include "cases/case_reader.hpp"

namespace knotwork {

const std::vector<std::string>& pt_space_keys() {
  static const std::vector<std::string> keys{"family", "degree", "elements", "cells", "tmesh", "segments", "extension",
                                             "quadrature_points", "error_quadrature_points"};
  return keys;
}

void read_pt_case(const CaseDocument& doc, CaseDescription& c) {
  const CaseReader& r = doc.reader;
  read_patch_geometry(doc, c);
  const DocumentNode& s = r.table(doc.root, "space", true);
  r.check_keys(s, "space", pt_space_keys());
  PtSection& pt = c.section.emplace<PtSection>();
  pt.space.rational = false;
  const bool given = s.get("cells") || s.get("tmesh");
  pt.space.elements_per_span = {1, 1};
  read_patch_degree_elements(doc, pt.space, true);
  if (!s.get("elements") && !given)
    r.fail("[space] elements", "missing: give elements (a tensor start on the geometry's knot spans), cells or tmesh");
  if (s.get("cells") && s.get("tmesh")) r.fail("[space] tmesh", "give either cells or tmesh, not both");
  if (const DocumentNode* cl = s.get("cells")) {
    pt.cells = read_cells(r, *cl, "[space] cells");
    try {
      RectangularPartition check(pt.cells);
    } catch (const std::invalid_argument& e) {
      r.fail("[space] cells", e.what());
    }
  }
  if (const DocumentNode* tm = s.get("tmesh")) {
    pt.tmesh_file = r.readable_file(*tm, "[space] tmesh");
    pt.cells = load_partition(pt.tmesh_file, false).cells;
  }
  if (const DocumentNode* sg = s.get("segments")) pt.segments = read_axis_segments(r, *sg, "[space] segments");
  if (const DocumentNode* x = s.get("extension")) {
    const std::string e = r.string(*x, "[space] extension");
    if (const auto parsed = parse_pt_extension(e)) pt.extension = *parsed;
    else r.fail("[space] extension", "'" + e + "' is not one of auto, minimal, horizontal, vertical, diagonalizable (" +
                                         closest_name(e, {"auto", "minimal", "horizontal", "vertical", "diagonalizable"}) + ")");
  }
  read_quadrature(r, s, c);
  read_patch_problem(doc, c);
}

}  // namespace knotwork
