// Rectangular partition (T-mesh) files, which `dimension`, `basis` and the T-mesh families
// read, and the sniffing of file kinds. Case files: families/load_case.cpp.
#include "cases/case_file.hpp"

#include "cases/case_reader.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

std::vector<RationalBox> read_tmesh(const CaseReader& r, const DocumentNode& t, const std::string& prefix) {
  std::vector<RationalBox> cells;
  const DocumentNode* c = t.get("cells");
  const DocumentNode* g = t.get("grid");
  if (c && g) r.fail(prefix + "grid", "give either cells or grid (with segments), not both");
  if (c) {
    if (t.get("segments")) r.fail(prefix + "segments", "inserted into a grid: use grid = {x = [...], y = [...]} with them");
    cells = read_cells(r, *c, prefix + "cells");
  } else if (g) {
    const DocumentNode* gt = g->as_table();
    if (!gt) r.fail(prefix + "grid", "must be a table {x = [...], y = [...]}");
    r.check_keys(*gt, prefix.empty() ? "grid" : prefix.substr(1, prefix.size() - 3) + ".grid", {"x", "y"});
    std::vector<mpq_class> xy[2];
    for (int d = 0; d < 2; ++d) {
      const std::string f = prefix + "grid." + (d == 0 ? "x" : "y");
      const DocumentNode* n = gt->get(d == 0 ? "x" : "y");
      if (!n || !n->as_array()) r.fail(f, "missing: the grid's coordinates, increasing");
      for (size_t i = 0; i < n->as_array()->size(); ++i)
        xy[d].push_back(r.rational(*n->as_array()->get(i), f + "[" + std::to_string(i) + "]"));
    }
    try {
      cells = grid_cells(xy[0], xy[1]);
    } catch (const std::invalid_argument& e) {
      r.fail(prefix + "grid", e.what());
    }
    if (const DocumentNode* sg = t.get("segments")) {
      const auto segs = read_axis_segments(r, *sg, prefix + "segments");
      try {
        cells = insert_segments(std::move(cells), segs);
      } catch (const std::invalid_argument& e) {
        r.fail(prefix + "segments", e.what());
      }
    }
  } else {
    r.fail(prefix + "cells", "missing: give cells = [[x0, y0, x1, y1], ...] or grid = {x = [...], y = [...]}");
  }
  try {
    RectangularPartition check(cells);
  } catch (const std::invalid_argument& e) {
    r.fail(prefix + "cells", e.what());
  }
  return cells;
}

void require_highest_smoothness(const PartitionDescription& p, const std::string& path, const std::string& space) {
  if (p.alpha != p.m - 1 || p.beta != p.n - 1)
    throw InputError(path + ": smoothness: " + space + " (smoothness = [" + std::to_string(p.m - 1) + ", " +
                     std::to_string(p.n - 1) + "]); `knotwork dimension` counts other smoothness");
}

PartitionDescription load_partition(const std::string& path, bool need_degree) {
  return load_partition_document(parse_document(path), path, need_degree);
}

PartitionDescription load_partition_document(const DocumentNode& root, const std::string& path, bool need_degree) {
  CaseReader r(path);
  r.check_keys(root, "", {"cells", "grid", "segments", "degree", "smoothness", "title", "description"});
  PartitionDescription d;
  const DocumentNode* deg = root.get("degree");
  if (!deg && need_degree) r.fail("degree", "missing required key ([m, n] or one int)");
  if (deg) {
    const auto mn = r.integer_pair(*deg, "degree");
    check_degree(r, mn, "degree");
    d.m = static_cast<int>(mn[0]);
    d.n = static_cast<int>(mn[1]);
  }
  d.alpha = d.m - 1;
  d.beta = d.n - 1;
  if (const DocumentNode* sm = root.get("smoothness")) {
    const auto ab = r.integer_pair(*sm, "smoothness");
    if (ab[0] < -1 || ab[0] > d.m - 1 || ab[1] < -1 || ab[1] > d.n - 1)
      r.fail("smoothness", "must be in [-1, degree-1] per direction, got [" + std::to_string(ab[0]) + ", " +
                               std::to_string(ab[1]) + "] for degree [" + std::to_string(d.m) + ", " + std::to_string(d.n) + "]");
    d.alpha = static_cast<int>(ab[0]);
    d.beta = static_cast<int>(ab[1]);
  }
  d.cells = read_tmesh(r, root, "");
  return d;
}

bool document_has_key(const std::string& path, const std::vector<std::string>& keys) {
  const DocumentNode root = parse_document(path);
  for (const auto& k : keys)
    if (root.get(k)) return true;
  return false;
}

}  // namespace knotwork
