// Reading [space] of family "knot_segments" and collection files.
#include "families/knot_segments/knot_segments_case.hpp"

#include <algorithm>

#include "cases/case_reader.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// segments = [{direction, position, from, to, multiplicity}, ...] in parameter coordinates.
std::vector<KnotInsertion> read_knot_insertions(const CaseReader& r, const DocumentNode& segs) {
  const DocumentNode* a = segs.as_array();
  if (!a) r.fail("[space] segments", "must be a list of { direction, position, from, to, multiplicity }");
  std::vector<KnotInsertion> out;
  for (size_t i = 0; i < a->size(); ++i) {
    const std::string field = "[space] segments[" + std::to_string(i) + "]";
    const DocumentNode* t = a->get(i)->as_table();
    if (!t) r.fail(field, "must be a table { direction = \"vertical\", position = ..., from = ..., to = ... }");
    r.check_keys(*t, "space] segments[" + std::to_string(i), {"direction", "position", "from", "to", "multiplicity"});
    KnotInsertion k;
    for (const char* key : {"direction", "position", "from", "to"})
      if (!t->get(key)) r.fail(field + " " + key, "missing");
    const std::string dir = r.string(*t->get("direction"), field + " direction");
    if (dir != "vertical" && dir != "horizontal") r.fail(field + " direction", "must be \"vertical\" or \"horizontal\"");
    k.vertical = dir == "vertical";
    k.position = r.number(*t->get("position"), field + " position");
    k.from = r.number(*t->get("from"), field + " from");
    k.to = r.number(*t->get("to"), field + " to");
    if (const DocumentNode* m = t->get("multiplicity")) k.multiplicity = static_cast<int>(r.integer(*m, field + " multiplicity"));
    out.push_back(k);
  }
  return out;
}

}  // namespace

const std::vector<std::string>& knot_segments_space_keys() {
  static const std::vector<std::string> keys{"family",   "degree",     "elements", "rational", "quadrature_points",
                                             "error_quadrature_points", "segments", "collection",
                                             "extension"};
  return keys;
}

void read_knot_segments_case(const CaseDocument& doc, CaseDescription& c) {
  const CaseReader& r = doc.reader;
  read_patch_geometry(doc, c);
  const DocumentNode& s = r.table(doc.root, "space", true);
  // continuity and the extra knots are the tensor family's: refused below with the reason.
  std::vector<std::string> valid = knot_segments_space_keys();
  valid.insert(valid.end(), {"continuity", "insert_knots_u", "insert_knots_v"});
  r.check_keys(s, "space", valid);
  KnotSegmentsSection& k = c.section.emplace<KnotSegmentsSection>();
  k.space.rational = false;  // knot-segment spaces are polynomial B-splines on the exact geometry
  for (const char* key : {"continuity", "insert_knots_u", "insert_knots_v"})
    if (s.get(key))
      r.fail(std::string("[space] ") + key, "not used with family = \"knot_segments\" (its knots are C^(d-1); "
                                            "refine with segments, which take a multiplicity)");
  if (const DocumentNode* x = s.get("rational"))
    if (r.boolean(*x, "[space] rational")) r.fail("[space] rational", "knot_segments spaces are polynomial B-splines");
  if (const DocumentNode* x = s.get("extension")) {
    const std::string name = r.string(*x, "[space] extension");
    const auto& names = KnotSegmentsSection::kExtensionNames;
    const auto found = std::find(std::begin(names), std::end(names), name);
    if (found == std::end(names))
      r.fail("[space] extension", std::string("must be \"") + names[0] + "\", \"" + names[1] + "\" or \"" + names[2] +
                                      "\", not \"" + name + "\"");
    k.extension = static_cast<SemiRegularCollection::Extension>(found - std::begin(names));
  }
  if (const DocumentNode* segs = s.get("segments")) k.segments = read_knot_insertions(r, *segs);
  if (const DocumentNode* f = s.get("collection")) {
    for (const char* key : {"segments", "elements"})
      if (s.get(key)) r.fail(std::string("[space] ") + key, "not used with an explicit collection (its functions are fixed)");
    k.collection_file = r.readable_file(*f, "[space] collection");
    const CollectionDescription cd = load_collection(k.collection_file);
    k.collection = cd.splines;
    if (const DocumentNode* d = s.get("degree")) {
      const auto deg = r.integer_pair(*d, "[space] degree");
      if (deg[0] != cd.dx || deg[1] != cd.dy)
        r.fail("[space] degree", "the collection " + k.collection_file + " has degree [" + std::to_string(cd.dx) + ", " +
                                     std::to_string(cd.dy) + "]");
    }
    k.space.degree = {cd.dx, cd.dy};
    k.space.elements_per_span = {1, 1};
  } else {
    read_patch_degree_elements(doc, k.space, false);
  }
  read_quadrature(r, s, c);
  read_patch_problem(doc, c);
}

CollectionDescription load_collection(const std::string& path) {
  const DocumentNode root = parse_document(path);
  CaseReader r(path);
  r.check_keys(root, "", {"degree", "functions", "case", "title", "description"});
  const DocumentNode* deg = root.get("degree");
  if (!deg) r.fail("degree", "missing required key ([dx, dy] or one int)");
  const auto d = r.integer_pair(*deg, "degree");
  check_degree(r, d, "degree");
  CollectionDescription c;
  c.dx = static_cast<int>(d[0]);
  c.dy = static_cast<int>(d[1]);
  const DocumentNode* fs = root.get("functions");
  if (!fs || !fs->is_array() || fs->as_array()->empty())
    r.fail("functions", "missing: give functions = [{x = [...], y = [...]}, ...], each with its local knot vectors");
  const DocumentNode& a = *fs->as_array();
  for (size_t i = 0; i < a.size(); ++i) {
    const std::string field = "functions[" + std::to_string(i) + "]";
    const DocumentNode* t = a.get(i)->as_table();
    if (!t) r.fail(field, "must be a table {x = [...], y = [...]}");
    r.check_keys(*t, field, {"x", "y"});
    LocalBSpline b;
    for (const char* key : {"x", "y"}) {
      const DocumentNode* k = t->get(key);
      if (!k) r.fail(field + " " + key, "missing local knot vector");
      std::vector<double>& v = key[0] == 'x' ? b.x : b.y;
      v = r.numbers(*k, field + " " + key);
      const int need = (key[0] == 'x' ? c.dx : c.dy) + 2;
      if (static_cast<int>(v.size()) != need)
        r.fail(field + " " + key, "needs degree+2 = " + std::to_string(need) + " knots, got " + std::to_string(v.size()));
      for (size_t j = 1; j < v.size(); ++j)
        if (!(v[j] >= v[j - 1])) r.fail(field + " " + key, "knots must be non-decreasing");
      if (!(v.back() > v.front())) r.fail(field + " " + key, "the support has zero width");
    }
    c.splines.push_back(std::move(b));
  }
  return c;
}

}  // namespace knotwork
