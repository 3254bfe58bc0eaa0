#include "families/knot_segments/collection_checks.hpp"

#include <cstdio>
#include <fstream>

#include "basis/tmesh/partition_topology.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "cases/json_output.hpp"
#include "cases/output_files.hpp"

namespace knotwork {

CollectionChecks check_collection(const SemiRegularCollection& collection, bool simple_knots) {
  CollectionChecks r;
  for (const auto& v : collection.violations()) r.violations.push_back(v.reason);
  if (!simple_knots) return r;
  const RectangularPartition part = collection.partition();
  const int dx = collection.degree_x(), dy = collection.degree_y();
  check_brute_force_size(part.num_cells(), dx, dy, RankMethod::kModular);
  r.dimension_bruteforce = spline_space_dimension(part, dx, dy, dx - 1, dy - 1).dimension;
  if (dx == dy) r.dimension_formula = weller_dimension_formula(partition_topology(part), dx);
  return r;
}

std::string describe_insertion(const KnotInsertion& s) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "%s %s = %g, %s in [%g, %g]", s.vertical ? "vertical" : "horizontal",
                s.vertical ? "x" : "y", s.position, s.vertical ? "y" : "x", s.from, s.to);
  return buf;
}

void export_collection(const std::string& file, const std::string& source, const SemiRegularCollection& collection) {
  Json fs = Json::array();
  for (const auto& b : collection.splines()) {
    Json x = Json::array(), y = Json::array();
    for (double v : b.x) x.push(v);
    for (double v : b.y) y.push(v);
    fs.push(Json::object().set("x", x).set("y", y));
  }
  Json root = Json::object();
  root.set("case", source)
      .set("degree", Json::array().push(double(collection.degree_x())).push(double(collection.degree_y())))
      .set("functions", fs);
  write_file_atomically(file, "--export", [&](const std::string& path) {
    std::ofstream out(path);
    out << root.dump() << "\n";
    if (!out) throw std::runtime_error("write failed");
  });
}

}  // namespace knotwork
