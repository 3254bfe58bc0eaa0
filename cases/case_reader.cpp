// The validated reading of case files shared by every family: values with their field
// names in messages, the JSON route, and the sections of one-patch domains ([geometry],
// [problem]). The families' own [space] readers are in families/<family>/<family>_case.cpp.
#include "cases/case_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <toml++/toml.h>

#include "cases/boundary_labels.hpp"
#include "cases/geometries.hpp"
#include "cases/geometry_file.hpp"
#include "cases/json_input.hpp"
#include "solver/amg_preconditioner.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {


size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

// A JSON value as a document node (nulls refused: no field takes them).
DocumentNode from_json(const JsonValue& v, const std::string& path, const std::string& field) {
  using K = JsonValue::Kind;
  switch (v.kind) {
    case K::kNull: throw InputError(path + ": " + field + ": null is not a valid value here");
    case K::kBool: return DocumentNode::boolean(v.boolean);
    case K::kString: return DocumentNode::string(v.text);
    case K::kNumber:
      if (v.integral && std::abs(v.number) < 9.0e18) return DocumentNode::integer(std::stoll(v.text));
      return DocumentNode::floating(v.number);
    case K::kArray: {
      DocumentNode a = DocumentNode::array();
      for (size_t i = 0; i < v.items.size(); ++i) a.push_back(from_json(v.items[i], path, field + "[" + std::to_string(i) + "]"));
      return a;
    }
    case K::kObject: break;
  }
  DocumentNode t = DocumentNode::table();
  for (const auto& [key, member] : v.members) t.insert(key, from_json(member, path, field.empty() ? key : field + "." + key));
  return t;
}

// A TOML node as a document node. toml++ gives dates and times too: no field takes them.
DocumentNode from_toml(const toml::node& n, const std::string& path, const std::string& field) {
  if (const toml::table* t = n.as_table()) {
    DocumentNode out = DocumentNode::table();
    for (const auto& [k, v] : *t) {
      const std::string key(k.str());
      out.insert(key, from_toml(v, path, field.empty() ? key : field + "." + key));
    }
    return out;
  }
  if (const toml::array* a = n.as_array()) {
    DocumentNode out = DocumentNode::array();
    for (size_t i = 0; i < a->size(); ++i) out.push_back(from_toml(*a->get(i), path, field + "[" + std::to_string(i) + "]"));
    return out;
  }
  if (auto s = n.value_exact<std::string>()) return DocumentNode::string(*s);
  if (auto i = n.value_exact<int64_t>()) return DocumentNode::integer(*i);
  if (auto d = n.value_exact<double>()) return DocumentNode::floating(*d);
  if (auto b = n.value_exact<bool>()) return DocumentNode::boolean(*b);
  std::ostringstream s;
  s << path << ":" << n.source().begin.line << ":" << n.source().begin.column << ": " << field
    << ": dates and times are not valid values here";
  throw InputError(s.str());
}

bool is_json_file(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return ext == ".json";
}

[[noreturn]] void toml_syntax_error(const std::string& name, const toml::parse_error& e) {
  std::ostringstream s;
  s << name << ":" << e.source().begin.line << ":" << e.source().begin.column << ": TOML syntax error: " << e.description();
  throw InputError(s.str());
}

}  // namespace

std::string closest_name(const std::string& key, const std::vector<std::string>& valid) {
  std::string best;
  size_t best_d = 1000;
  for (const auto& v : valid) {
    const size_t d = edit_distance(key, v);
    if (d < best_d) { best_d = d; best = v; }
  }
  std::string all;
  for (const auto& v : valid) all += (all.empty() ? "" : ", ") + v;
  return best_d <= std::max<size_t>(2, key.size() / 2) ? "did you mean '" + best + "'?"
                                                        : "valid keys: " + all;
}


void CaseReader::fail(const std::string& field, const std::string& what) const {
  throw InputError(path_ + ": " + field + ": " + what);
}

void CaseReader::check_keys(const DocumentNode& t, const std::string& section, const std::vector<std::string>& valid) const {
  for (const auto& [k, v] : t) {
    const std::string& key = k;
    if (std::find(valid.begin(), valid.end(), key) != valid.end()) continue;
    const std::string field = section.empty() ? key : "[" + section + "] " + key;
    if (section == "space") {
      std::string owners;
      for (const auto& [family, keys] : other_families_keys_)
        if (std::find(keys.begin(), keys.end(), key) != keys.end()) owners += (owners.empty() ? "\"" : ", \"") + family + "\"";
      if (!owners.empty()) fail(field, "unknown key for family = \"" + family_ + "\" (only family = " + owners + " takes it)");
    }
    fail(field, "unknown key (" + closest_name(key, valid) + ")");
  }
}

const DocumentNode& CaseReader::table(const DocumentNode& t, const std::string& key, bool required) const {
  static const DocumentNode empty = DocumentNode::table();
  const DocumentNode* n = t.get(key);
  if (!n) {
    if (required) fail("[" + key + "]", "missing section");
    return empty;
  }
  if (!n->is_table()) fail(key, "must be a table ([" + key + "])");
  return *n->as_table();
}

double CaseReader::number(const DocumentNode& n, const std::string& field) const {
  double v;
  if (auto i = n.value_exact<int64_t>()) v = static_cast<double>(*i);
  else if (auto d = n.value_exact<double>()) v = *d;
  else if (auto s = n.value_exact<std::string>()) v = rational_string(*s, field);
  else fail(field, "must be a number");
  if (!std::isfinite(v)) fail(field, "must be a finite number (got nan or inf)");
  return v;
}

// An exact rational such as "-1/3" (geometries written from exact data use them).
double CaseReader::rational_string(const std::string& s, const std::string& field) const {
  const auto slash = s.find('/');
  try {
    size_t used = 0;
    if (slash == std::string::npos) {
      const double v = std::stod(s, &used);
      if (used == s.size()) return v;
    } else {
      const double a = std::stod(s.substr(0, slash), &used);
      if (used == slash) {
        size_t used2 = 0;
        const double b = std::stod(s.substr(slash + 1), &used2);
        if (used2 == s.size() - slash - 1 && b != 0) return a / b;
      }
    }
  } catch (const std::exception&) {
  }
  fail(field, "\"" + s + "\" is not a number");
}

mpq_class CaseReader::rational(const DocumentNode& x, const std::string& field) const {
  try {
    if (auto i64 = x.value_exact<int64_t>()) return mpq_class(static_cast<long>(*i64));
    if (auto s = x.value_exact<std::string>()) return parse_rational(*s);
    if (auto f = x.value_exact<double>()) {
      if (!std::isfinite(*f)) fail(field, "coordinates must be finite (got nan or inf)");
      return mpq_class(*f);  // write "1/10", not 0.1, for exact decimals
    }
  } catch (const std::invalid_argument& e) {
    fail(field, e.what());
  }
  fail(field, "must be a number or a rational string such as \"14/9\"");
}

long CaseReader::integer(const DocumentNode& n, const std::string& field) const {
  if (auto i = n.value_exact<int64_t>()) return static_cast<long>(*i);
  fail(field, "must be an integer");
}

std::vector<long> CaseReader::integers(const DocumentNode& n, const std::string& field, int count) const {
  static const char* const lists[] = {"", "", "a pair [u, v]", "a list [u, v, w]"};
  if (auto a = n.as_array()) {
    if (a->size() != static_cast<size_t>(count)) fail(field, std::string("must be an integer or ") + lists[count]);
    std::vector<long> r;
    for (size_t i = 0; i < a->size(); ++i) r.push_back(integer(*a->get(i), field));
    return r;
  }
  return std::vector<long>(count, integer(n, field));
}

std::array<long, 2> CaseReader::integer_pair(const DocumentNode& n, const std::string& field) const {
  const std::vector<long> v = integers(n, field, 2);
  return {v[0], v[1]};
}

std::vector<double> CaseReader::numbers(const DocumentNode& n, const std::string& field) const {
  const DocumentNode* a = n.as_array();
  if (!a) fail(field, "must be an array of numbers");
  std::vector<double> r;
  for (size_t i = 0; i < a->size(); ++i) r.push_back(number(*a->get(i), field + "[" + std::to_string(i) + "]"));
  return r;
}

Eigen::MatrixXd CaseReader::points(const DocumentNode& n, const std::string& field, int dimension) const {
  const char* point = dimension == 3 ? "[x, y, z]" : "[x, y]";
  const DocumentNode* a = n.as_array();
  if (!a) fail(field, std::string("must be an array of ") + point + " points");
  Eigen::MatrixXd p(a->size(), dimension);
  for (size_t i = 0; i < a->size(); ++i) {
    const std::string f = field + "[" + std::to_string(i) + "]";
    const auto x = numbers(*a->get(i), f);
    if (x.size() != static_cast<size_t>(dimension)) fail(f, std::string("must be a point ") + point);
    for (int d = 0; d < dimension; ++d) p(i, d) = x[d];
  }
  return p;
}

Eigen::MatrixX2d CaseReader::points(const DocumentNode& n, const std::string& field) const { return points(n, field, 2); }

std::string CaseReader::string(const DocumentNode& n, const std::string& field) const {
  if (auto s = n.value_exact<std::string>()) return *s;
  fail(field, "must be a string");
}

bool CaseReader::boolean(const DocumentNode& n, const std::string& field) const {
  if (auto b = n.value_exact<bool>()) return *b;
  fail(field, "must be true or false");
}

std::string CaseReader::resolve(const std::string& file) const {
  const std::filesystem::path f = file;
  return (f.is_relative() ? std::filesystem::path(path_).parent_path() / f : f).string();
}

std::string CaseReader::readable_file(const DocumentNode& n, const std::string& field) const {
  return readable_file(string(n, field), field);
}

std::string CaseReader::readable_file(const std::string& name, const std::string& field) const {
  const std::string file = resolve(name);
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) fail(field, "no such file: " + file + " (relative paths start at the case file's folder)");
  if (std::filesystem::is_directory(file, ec)) fail(field, file + " is a folder, not a file");
  if (!std::ifstream(file)) fail(field, file + " cannot be read");
  return file;
}

DocumentNode parse_document(const std::string& path) {
  if (is_json_file(path)) {
    const JsonValue doc = read_json_file(path);
    if (doc.kind != JsonValue::Kind::kObject) throw InputError(path + ": the JSON document must be an object {...}");
    return from_json(doc, path, "");
  }
  std::ifstream probe(path);
  if (!probe) {
    const std::string why = std::filesystem::exists(path) ? "cannot be read" : "no such file";
    throw InputError(path + ": cannot open the file (" + why + ")");
  }
  if (std::filesystem::is_directory(path)) throw InputError(path + ": is a directory, not a file to read");
  try {
    return from_toml(toml::parse_file(path), path, "");
  } catch (const toml::parse_error& e) {
    toml_syntax_error(path, e);
  }
}

DocumentNode parse_document_text(const std::string& text, const std::string& name) {
  try {
    return from_toml(toml::parse(text, name), name, "");
  } catch (const toml::parse_error& e) {
    toml_syntax_error(name, e);
  }
}

namespace {

bool is_volume_type(const std::string& type) { return type == "box" || type == "thick_quarter_annulus" || type == "fichera"; }

NurbsPatch read_nurbs(const CaseReader& r, const DocumentNode& g, const std::string& section) {
  r.check_keys(g, section, {"type", "degrees", "knots_u", "knots_v", "control_points", "weights", "file"});
  const DocumentNode* src = &g;
  DocumentNode from_file = DocumentNode::table();
  std::string field_prefix = "[" + section + "] ";
  if (const DocumentNode* f = g.get("file")) {
    const std::filesystem::path file = r.readable_file(*f, field_prefix + "file");
    from_file = parse_document(file.string());
    CaseReader(file.string()).check_keys(from_file, "", {"degrees", "knots_u", "knots_v", "control_points", "weights"});
    src = &from_file;
    field_prefix = "(file " + file.string() + ") ";
  }
  auto need = [&](const char* key) -> const DocumentNode& {
    const DocumentNode* n = src->get(key);
    if (!n) r.fail(field_prefix + key, "missing required key for a nurbs geometry");
    return *n;
  };
  const auto deg = r.integer_pair(need("degrees"), field_prefix + "degrees");
  for (long d : deg)
    if (d < 1 || d > kMaxCaseDegree) r.fail(field_prefix + "degrees", "must be in [1, 10]");
  NurbsPatch p;
  try {
    p.basis_u = BSplineBasis1D(static_cast<int>(deg[0]), r.numbers(need("knots_u"), field_prefix + "knots_u"));
  } catch (const std::invalid_argument& e) { r.fail(field_prefix + "knots_u", e.what()); }
  try {
    p.basis_v = BSplineBasis1D(static_cast<int>(deg[1]), r.numbers(need("knots_v"), field_prefix + "knots_v"));
  } catch (const std::invalid_argument& e) { r.fail(field_prefix + "knots_v", e.what()); }
  p.control_points = r.points(need("control_points"), field_prefix + "control_points");
  if (const DocumentNode* w = src->get("weights")) {
    const auto ws = r.numbers(*w, field_prefix + "weights");
    p.weights = Eigen::Map<const Eigen::VectorXd>(ws.data(), ws.size());
  } else {
    p.weights.setOnes(p.control_points.rows());
  }
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    const std::string field = what.rfind("weight", 0) == 0 ? "weights"
                              : what.rfind("knots_u", 0) == 0 ? "knots_u"
                              : what.rfind("knots_v", 0) == 0 ? "knots_v" : "control_points";
    r.fail(field_prefix + field, what);
  }
  return p;
}


}  // namespace

void read_patch_geometry(const CaseDocument& doc, CaseDescription& c, bool multipatch_allowed) {
  const CaseReader& r = doc.reader;
  const DocumentNode& g = r.table(doc.root, "geometry", true);
  const DocumentNode* type = g.get("type");
  const DocumentNode* file = g.get("file");
  const std::optional<std::string> file_name = file ? std::optional(r.string(*file, "[geometry] file")) : std::nullopt;
  if (file_name && std::filesystem::path(*file_name).extension() != ".toml") {  // a peer's file; .toml: a nurbs patch, below
    r.check_keys(g, "geometry", {"type", "file"});
    if (type && r.string(*type, "[geometry] type") != "nurbs")
      r.fail("[geometry] type", "the geometry is read from [geometry] file: leave type out (or set it to \"nurbs\")");
    const std::string path = r.readable_file(*file, "[geometry] file");  // relative to the case file
    try {
      if (geometry_file_dimension(path) == 3)
        throw InputError(path + ": is a volume, and [space] family = \"" + c.family +
                         "\" works on planar patches (docs/VOLUMES.md names the families that solve on volumes)");
      c.domain = read_geometry_file(path);
    } catch (const InputError& e) {
      throw InputError(c.path + ": [geometry] file: " + e.what());
    }
    c.geometry_type = "file";
    if (c.domain.num_patches() == 1)
      c.geometry = c.domain.patches.front();
    else if (!multipatch_allowed)
      r.fail("[geometry] file", "has " + std::to_string(c.domain.num_patches()) +
                                    " patches, and [space] family = \"" + c.family + "\" works on one patch");
    return;
  }
  if (!type) r.fail("[geometry] type", "missing (rectangle, quarter_annulus, lshape or nurbs; or give [geometry] file)");
  c.geometry_type = r.string(*type, "[geometry] type");
  if (c.geometry_type == "rectangle") {
    r.check_keys(g, "geometry", {"type", "corners"});
    Eigen::MatrixX2d corners(2, 2);
    corners << 0, 0, 1, 1;
    if (const DocumentNode* n = g.get("corners")) corners = r.points(*n, "[geometry] corners");
    if (corners.rows() != 2) r.fail("[geometry] corners", "must be [[x0, y0], [x1, y1]]");
    if (!(corners(1, 0) > corners(0, 0) && corners(1, 1) > corners(0, 1)))
      r.fail("[geometry] corners", "need x1 > x0 and y1 > y0");
    // The Jacobian is the product of the sides and the stiffness their inverse squares: both
    // stay normal doubles only for sides of moderate size (rescale the problem otherwise).
    for (int d = 0; d < 2; ++d) {
      const double side = corners(1, d) - corners(0, d);
      if (!(side >= 1e-100 && side <= 1e100)) {
        char msg[160];
        std::snprintf(msg, sizeof msg, "side length %g is outside [1e-100, 1e100], where the Jacobian and its inverse "
                                       "are normal doubles; rescale the problem", side);
        r.fail("[geometry] corners", msg);
      }
    }
    c.geometry = rectangle_patch(corners(0, 0), corners(0, 1), corners(1, 0), corners(1, 1));
  } else if (c.geometry_type == "quarter_annulus") {
    r.check_keys(g, "geometry", {"type", "inner_radius", "outer_radius"});
    const double ri = g.get("inner_radius") ? r.number(*g.get("inner_radius"), "[geometry] inner_radius") : 1.0;
    const double ro = g.get("outer_radius") ? r.number(*g.get("outer_radius"), "[geometry] outer_radius") : 2.0;
    if (!(ri > 0)) r.fail("[geometry] inner_radius", "must be > 0");
    if (!(ro > ri)) r.fail("[geometry] outer_radius", "must be > inner_radius");
    c.geometry = quarter_annulus_patch(ri, ro);
  } else if (c.geometry_type == "lshape") {
    r.check_keys(g, "geometry", {"type"});
    c.geometry = lshape_patch();
  } else if (c.geometry_type == "nurbs") {
    c.geometry = read_nurbs(r, g, "geometry");
  } else if (is_volume_type(c.geometry_type)) {
    r.fail("[geometry] type", "'" + c.geometry_type + "' is a volume, and [space] family = \"" + c.family +
                                  "\" works on planar patches (docs/VOLUMES.md names the families that solve on volumes)");
  } else {
    r.fail("[geometry] type", "unknown geometry '" + c.geometry_type + "' (" +
                                  closest_name(c.geometry_type, {"rectangle", "quarter_annulus", "lshape", "nurbs", "box",
                                                                 "thick_quarter_annulus", "fichera"}) + ")");
  }
}

namespace {

// [geometry] file when it names a peer's file (.xml, .txt; a .toml holds an inline patch).
std::optional<std::string> peer_geometry_file(const CaseReader& r, const DocumentNode& g) {
  const DocumentNode* file = g.get("file");
  if (!file || std::filesystem::path(r.string(*file, "[geometry] file")).extension() == ".toml") return std::nullopt;
  return r.readable_file(*file, "[geometry] file");  // relative to the case file
}

}  // namespace

bool is_volume_geometry(const CaseDocument& doc) {
  const DocumentNode* g = doc.root.get("geometry");
  if (!g || !g->as_table()) return false;
  if (const auto path = peer_geometry_file(doc.reader, *g)) {
    try {
      return geometry_file_dimension(*path) == 3;
    } catch (const InputError& e) {
      throw InputError(doc.reader.path() + ": [geometry] file: " + e.what());
    }
  }
  const DocumentNode* type = g->get("type");
  const auto name = type ? type->value_exact<std::string>() : std::nullopt;
  // An inline NURBS is a volume when it has a third knot vector.
  return name && (is_volume_type(*name) || (*name == "nurbs" && g->get("knots_w")));
}

namespace {

// [geometry] type = "nurbs" with knots_w: degrees (one int or [p, q, r]), knots_u/v/w, control
// points [x, y, z] numbered u fastest, then v, then w, and weights (default all 1).
NurbsVolume read_nurbs_volume(const CaseReader& r, const DocumentNode& g) {
  r.check_keys(g, "geometry", {"type", "degrees", "knots_u", "knots_v", "knots_w", "control_points", "weights"});
  auto need = [&](const char* key) -> const DocumentNode& {
    const DocumentNode* n = g.get(key);
    if (!n) r.fail(std::string("[geometry] ") + key, "missing required key for a nurbs volume");
    return *n;
  };
  const std::vector<long> degrees = r.integers(need("degrees"), "[geometry] degrees", 3);
  for (long d : degrees)
    if (d < 1 || d > kMaxCaseDegree) r.fail("[geometry] degrees", "must be in [1, 10]");
  NurbsVolume v;
  static const char* const knots[3] = {"knots_u", "knots_v", "knots_w"};
  for (int k = 0; k < 3; ++k) {
    const std::string field = std::string("[geometry] ") + knots[k];
    try {
      v.bases[k] = BSplineBasis1D(static_cast<int>(degrees[k]), r.numbers(need(knots[k]), field));
    } catch (const std::invalid_argument& e) { r.fail(field, e.what()); }
  }
  v.control_points = r.points(need("control_points"), "[geometry] control_points", 3);
  if (const DocumentNode* w = g.get("weights")) {
    const auto ws = r.numbers(*w, "[geometry] weights");
    v.weights = Eigen::Map<const Eigen::VectorXd>(ws.data(), static_cast<Eigen::Index>(ws.size()));
  } else {
    v.weights.setOnes(v.control_points.rows());
  }
  try {
    v.validate();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    std::string field = "control_points";
    for (const char* key : {"weights", "knots_u", "knots_v", "knots_w"})
      if (what.rfind(key, 0) == 0) field = key;
    if (what.rfind("weight", 0) == 0) field = "weights";
    r.fail("[geometry] " + field, what);
  }
  return v;
}

}  // namespace

void read_volume_geometry(const CaseDocument& doc, CaseDescription& c) {
  const CaseReader& r = doc.reader;
  const DocumentNode& g = r.table(doc.root, "geometry", true);
  if (const auto path = peer_geometry_file(r, g)) {
    r.check_keys(g, "geometry", {"type", "file"});
    if (const DocumentNode* type = g.get("type"); type && r.string(*type, "[geometry] type") != "nurbs")
      r.fail("[geometry] type", "the geometry is read from [geometry] file: leave type out (or set it to \"nurbs\")");
    try {
      VolumeFile v = read_volume_file(*path);
      c.volume = std::move(v.volume);
      c.volume_boundaries = std::move(v.boundaries);
      c.volume_domain = std::move(v.domain);
    } catch (const InputError& e) {
      throw InputError(c.path + ": [geometry] file: " + e.what());
    }
    c.geometry_type = "file";
    return;
  }
  c.geometry_type = r.string(*g.get("type"), "[geometry] type");
  // Lengths stay where the Jacobian, its inverse and their products are normal doubles.
  const auto check_length = [&](double length, const std::string& field, const char* what) {
    if (!(length >= 1e-100 && length <= 1e100)) {
      char msg[200];
      std::snprintf(msg, sizeof msg, "%s %g is outside [1e-100, 1e100], where the Jacobian and its inverse are normal "
                                     "doubles; rescale the problem", what, length);
      r.fail(field, msg);
    }
  };
  if (c.geometry_type == "nurbs") {
    c.volume = read_nurbs_volume(r, g);
  } else if (c.geometry_type == "box") {
    r.check_keys(g, "geometry", {"type", "corners"});
    Eigen::MatrixXd corners(2, 3);
    corners << 0, 0, 0, 1, 1, 1;
    if (const DocumentNode* n = g.get("corners")) corners = r.points(*n, "[geometry] corners", 3);
    if (corners.rows() != 2) r.fail("[geometry] corners", "must be [[x0, y0, z0], [x1, y1, z1]]");
    for (int d = 0; d < 3; ++d) {
      if (!(corners(1, d) > corners(0, d))) r.fail("[geometry] corners", "need x1 > x0, y1 > y0 and z1 > z0");
      check_length(corners(1, d) - corners(0, d), "[geometry] corners", "side length");
    }
    c.volume = box_volume(corners.row(0).transpose(), corners.row(1).transpose());
  } else if (c.geometry_type == "fichera") {
    r.check_keys(g, "geometry", {"type"});
    c.volume = fichera_box_volume();
    c.volume_removed_boxes = {kFicheraRemovedBox};
  } else {
    r.check_keys(g, "geometry", {"type", "inner_radius", "outer_radius", "height"});
    const auto value = [&](const char* key, double fallback) {
      const DocumentNode* n = g.get(key);
      return n ? r.number(*n, std::string("[geometry] ") + key) : fallback;
    };
    const double ri = value("inner_radius", 1), ro = value("outer_radius", 2), h = value("height", 1);
    if (!(ri > 0)) r.fail("[geometry] inner_radius", "must be > 0");
    if (!(ro > ri)) r.fail("[geometry] outer_radius", "must be > inner_radius");
    check_length(ro - ri, "[geometry] outer_radius", "the wall's thickness");
    check_length(ro, "[geometry] outer_radius", "the radius");
    if (!(h > 0)) r.fail("[geometry] height", "must be > 0");
    check_length(h, "[geometry] height", "the height");
    c.volume = thick_quarter_annulus_volume(ri, ro, h);
  }
}

void check_degree(const CaseReader& r, const std::array<long, 2>& d, const std::string& field) {
  for (long v : d)
    if (v < 1 || v > kMaxCaseDegree) r.fail(field, "must be in [1, 10], got " + std::to_string(v));
}

void check_elements(const CaseReader& r, const std::array<long, 2>& e, const std::string& field) {
  for (long v : e)
    if (v < 1) r.fail(field, "must be >= 1, got " + std::to_string(v));
  if (e[0] * e[1] > kMaxCaseCells || e[0] > kMaxCaseCells || e[1] > kMaxCaseCells)
    r.fail(field, "too many elements (more than 2^26 cells)");
}

void read_quadrature(const CaseReader& r, const DocumentNode& s, CaseDescription& c, int directions) {
  auto read_points = [&](const char* key, int& pu, int& pv, int& pw) {
    if (const DocumentNode* k = s.get(key)) {
      const std::string field = std::string("[space] ") + key;
      const std::vector<long> q = directions == 1 ? std::vector<long>(3, r.integer(*k, field)) : r.integers(*k, field, directions);
      for (long v : q)
        if (v < 1 || v > 30) r.fail(field, "must be in [1, 30]");
      pu = static_cast<int>(q[0]);
      pv = static_cast<int>(q[1]);
      if (directions == 3) pw = static_cast<int>(q[2]);
    }
  };
  read_points("quadrature_points", c.quadrature.points_u, c.quadrature.points_v, c.quadrature.points_w);
  read_points("error_quadrature_points", c.quadrature.error_points_u, c.quadrature.error_points_v,
              c.quadrature.error_points_w);
  if (const DocumentNode* k = s.get("boundary_quadrature_points")) {
    // "interior": the interior rule's number along each side, as GeoPDEs and G+Smo integrate.
    if (k->value_exact<std::string>() == std::optional<std::string>("interior")) {
      c.quadrature.boundary_points = -1;
      return;
    }
    const long n = r.integer(*k, "[space] boundary_quadrature_points");
    if (n < 1 || n > 30) r.fail("[space] boundary_quadrature_points", "must be in [1, 30], got " + std::to_string(n));
    c.quadrature.boundary_points = static_cast<int>(n);
  }
}

// cells = [[x0, y0, x1, y1], ...] with exact coordinates (`field` names the key).
std::vector<RationalBox> read_cells(const CaseReader& r, const DocumentNode& node, const std::string& field) {
  const DocumentNode* a = node.as_array();
  if (!a) r.fail(field, "must be a list of cells [[x0, y0, x1, y1], ...]");
  std::vector<RationalBox> cells;
  for (size_t i = 0; i < a->size(); ++i) {
    const std::string f = field + "[" + std::to_string(i) + "]";
    const DocumentNode* c = a->get(i)->as_array();
    if (!c || c->size() != 4) r.fail(f, "must be [x0, y0, x1, y1]");
    mpq_class v[4];
    for (size_t k = 0; k < 4; ++k) v[k] = r.rational(*c->get(k), f);
    cells.push_back({v[0], v[1], v[2], v[3]});
  }
  return cells;
}

// segments = [{direction = "vertical", position, from, to}, ...] with exact coordinates.
std::vector<AxisSegment> read_axis_segments(const CaseReader& r, const DocumentNode& node, const std::string& field) {
  const DocumentNode* a = node.as_array();
  if (!a) r.fail(field, "must be a list of { direction, position, from, to }");
  std::vector<AxisSegment> out;
  for (size_t i = 0; i < a->size(); ++i) {
    const std::string f = field + "[" + std::to_string(i) + "]";
    const DocumentNode* t = a->get(i)->as_table();
    if (!t) r.fail(f, "must be a table { direction = \"vertical\", position = ..., from = ..., to = ... }");
    r.check_keys(*t, f.front() == '[' ? f.substr(1) : f, {"direction", "position", "from", "to"});
    for (const char* key : {"direction", "position", "from", "to"})
      if (!t->get(key)) r.fail(f + " " + key, "missing");
    const std::string dir = r.string(*t->get("direction"), f + " direction");
    if (dir != "vertical" && dir != "horizontal") r.fail(f + " direction", "must be \"vertical\" or \"horizontal\"");
    AxisSegment s;
    s.vertical = dir == "vertical";
    s.position = r.rational(*t->get("position"), f + " position");
    s.from = r.rational(*t->get("from"), f + " from");
    s.to = r.rational(*t->get("to"), f + " to");
    out.push_back(std::move(s));
  }
  return out;
}

namespace {

// An expression field that may also be written as a number (a constant coefficient).
Expression expression_or_number(const CaseReader& r, const DocumentNode& n, const std::string& field) {
  std::string text;
  if (n.value_exact<std::string>()) {
    text = r.string(n, field);
  } else {
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", r.number(n, field));
    text = b;
  }
  return Expression::parse(text, r.path() + ": " + field);
}

}  // namespace

// [problem] coefficient: a scalar a (A = a I) or a symmetric size x size matrix of expressions
// or numbers; a_ji must be a_ij (compared at a few points). Returns the upper triangle by rows.
std::vector<Expression> read_coefficient(const CaseReader& r, const DocumentNode& n, int size) {
  const std::string field = "[problem] coefficient";
  const DocumentNode* rows = n.as_array();
  if (!rows) return {expression_or_number(r, n, field)};
  const std::string shape = size == 2 ? "must be an expression (A = a I) or a symmetric 2x2 matrix [[a11, a12], [a12, a22]]"
                                      : "must be an expression (A = a I) or a symmetric 3x3 matrix [[a11, a12, a13], "
                                        "[a12, a22, a23], [a13, a23, a33]] (on a surface: its tangential part acts)";
  if (int(rows->size()) != size) r.fail(field, shape);
  std::vector<std::vector<Expression>> a(size, std::vector<Expression>(size));
  for (int i = 0; i < size; ++i) {
    const DocumentNode* row = rows->get(i)->as_array();
    if (!row || int(row->size()) != size) r.fail(field, shape);
    for (int j = 0; j < size; ++j)
      a[i][j] = expression_or_number(r, *row->get(j), field + "[" + std::to_string(i + 1) + "][" + std::to_string(j + 1) + "]");
  }
  const double points[3][3] = {{0.31, 0.72, 0.18}, {-0.43, 0.27, -0.61}, {0.64, -0.85, 0.39}};
  std::vector<Expression> upper_triangle;
  for (int i = 0; i < size; ++i)
    for (int j = i; j < size; ++j) {
      upper_triangle.push_back(a[i][j]);
      if (j == i) continue;
      ExpressionEvaluator upper(a[i][j]), lower(a[j][i]);
      for (const auto& p : points) {
        const double u = upper(p[0], p[1], p[2]), l = lower(p[0], p[1], p[2]);
        if (std::abs(u - l) > 1e-12 * (1 + std::abs(u)) || std::isnan(u) != std::isnan(l)) {
          char at[128];
          if (size == 2) std::snprintf(at, sizeof at, " differ at (%g, %g): %g and %g", p[0], p[1], u, l);
          else std::snprintf(at, sizeof at, " differ at (%g, %g, %g): %g and %g", p[0], p[1], p[2], u, l);
          const std::string ij = std::to_string(i + 1) + std::to_string(j + 1), ji = std::to_string(j + 1) + std::to_string(i + 1);
          r.fail(field, "not symmetric: a" + ij + " = \"" + a[i][j].text() + "\" and a" + ji + " = \"" + a[j][i].text() + "\"" + at);
        }
      }
    }
  return upper_triangle;
}

void read_coefficient_and_reaction(const CaseReader& r, const DocumentNode& t, int matrix_size, PoissonProblem& pb) {
  const std::string& f = r.path();
  if (const DocumentNode* a = t.get("coefficient")) {
    pb.coefficients.diffusion = read_coefficient(r, *a, matrix_size);
    pb.coefficients.diffusion_where = f + ": [problem] coefficient";
  }
  if (const DocumentNode* n = t.get("reaction")) {
    if (n->value_exact<std::string>()) {
      pb.coefficients.reaction = Expression::parse(r.string(*n, "[problem] reaction"), f + ": [problem] reaction");
    } else {
      pb.reaction = r.number(*n, "[problem] reaction");
      if (!(pb.reaction >= 0) || !std::isfinite(pb.reaction)) r.fail("[problem] reaction", "must be >= 0");
    }
  }
}

void read_exact_and_source(const CaseReader& r, const DocumentNode& t, CaseDescription& c, int dimension) {
  PoissonProblem& pb = c.problem;
  const std::string& f = r.path();
  if (const DocumentNode* e = t.get("exact")) {
    const Expression u = Expression::parse(r.string(*e, "[problem] exact"), f + ": [problem] exact");
    pb.exact = dimension == 3 ? differentiate_volume_solution(u) : differentiate_exact_solution(u);
  }
  read_coefficient_and_reaction(r, t, dimension, pb);
  const bool general = !pb.coefficients.constant() || pb.reaction != 0;
  if (const DocumentNode* s = t.get("source"))
    pb.source = Expression::parse(r.string(*s, "[problem] source"), f + ": [problem] source");
  else if (pb.exact && general)
    pb.source = derive_general_source(pb.exact->u, pb.coefficients.diffusion, pb.coefficients.reaction, pb.reaction, dimension);
  else if (pb.exact)
    pb.source = pb.exact->minus_laplacian;
  else
    r.fail("[problem] source", "missing: give `source`, or `exact` to derive it from");
}

void read_planar_exact_and_source(const CaseReader& r, const DocumentNode& t, CaseDescription& c) {
  read_exact_and_source(r, t, c, 2);
}

void read_dirichlet_method(const CaseReader& r, const DocumentNode& t, PoissonProblem& pb) {
  if (const DocumentNode* n = t.get("dirichlet_method")) {
    const std::string m = r.string(*n, "[problem] dirichlet_method");
    if (m == "projection") pb.dirichlet_method = DirichletMethod::kProjection;
    else if (m == "nitsche") pb.dirichlet_method = DirichletMethod::kNitsche;
    else r.fail("[problem] dirichlet_method", "'" + m + "' (" + closest_name(m, {"projection", "nitsche"}) + ")");
  }
  if (const DocumentNode* n = t.get("nitsche_penalty")) {
    if (pb.dirichlet_method != DirichletMethod::kNitsche)
      r.fail("[problem] nitsche_penalty", "only with dirichlet_method = \"nitsche\"");
    pb.nitsche_penalty = r.number(*n, "[problem] nitsche_penalty");
    if (!(pb.nitsche_penalty > 1 && pb.nitsche_penalty <= 1e6)) {
      char got[32];
      std::snprintf(got, sizeof got, "%g", pb.nitsche_penalty);
      r.fail("[problem] nitsche_penalty", std::string("must be above 1 (the coercivity bound) and at most 1e6, got ") + got);
    }
  }
}

void read_patch_problem(const CaseDocument& doc, CaseDescription& c) {
  const CaseReader& r = doc.reader;
  const DocumentNode& t = r.table(doc.root, "problem", true);
  r.check_keys(t, "problem",
               {"exact", "source", "coefficient", "reaction", "dirichlet", "neumann", "dirichlet_method", "nitsche_penalty"});
  PoissonProblem& pb = c.problem;
  const std::string& f = r.path();
  const int dimension = c.is_volume() ? 3 : 2;
  read_exact_and_source(r, t, c, dimension);
  read_dirichlet_method(r, t, pb);

  // One condition per boundary id; sides are named as boundary_labels says.
  const BoundaryLabels labels = boundary_labels(c);
  const size_t sides = labels.names.size();
  pb.boundary.assign(sides, BoundaryCondition{});
  const auto ids_of = [&](const std::string& name, const std::string& field) {
    const std::vector<int> ids = labels.resolve(name);
    if (ids.empty()) {
      const std::vector<std::string> all = labels.all_names();
      std::string known;
      for (size_t i = 0; i < all.size() && i < 12; ++i) known += (i ? ", " : "") + all[i];
      if (all.size() > 12) known += ", ...";
      const std::string closest = closest_name(name, all);
      r.fail(field, "unknown side '" + name + "' (" + (closest.rfind("did you mean", 0) == 0 ? closest + "; " : "") +
                        "sides are " + known + ")");
    }
    return ids;
  };
  std::set<int> neumann;
  if (const DocumentNode* n = t.get("neumann")) {
    if (const DocumentNode* a = n->as_array()) {
      for (size_t i = 0; i < a->size(); ++i)
        for (int s : ids_of(r.string(*a->get(i), "[problem] neumann"), "[problem] neumann")) {
          pb.boundary[s].kind = BoundaryKind::kNeumann;
          neumann.insert(s);
        }
    } else if (const DocumentNode* nt = n->as_table()) {
      for (const auto& [k, v] : *nt) {
        const std::string field = "[problem] neumann." + k;
        // A flux h = du/dn ("exact": from the exact solution), or a flux vector [Fx, Fy(, Fz)]: h = F.n.
        std::vector<Expression> flux;
        std::string val;
        if (const DocumentNode* a = v.as_array()) {
          if (a->size() != static_cast<size_t>(dimension))
            r.fail(field, dimension == 3 ? "a flux vector is three expressions [Fx, Fy, Fz]; or give the flux du/dn as one expression"
                                         : "a flux vector is two expressions [Fx, Fy]; or give the flux du/dn as one expression");
          for (size_t i = 0; i < a->size(); ++i)
            flux.push_back(Expression::parse(r.string(*a->get(i), field), f + ": " + field + "[" + std::to_string(i) + "]"));
        } else {
          val = r.string(v, field);
        }
        for (int s : ids_of(k, field)) {
          pb.boundary[s].kind = BoundaryKind::kNeumann;
          if (!flux.empty()) {
            pb.boundary[s].from_exact = false;
            pb.boundary[s].flux = flux;
          } else if (val != "exact") {
            pb.boundary[s].from_exact = false;
            pb.boundary[s].value = Expression::parse(val, f + ": " + field);
          }
          neumann.insert(s);
        }
      }
    } else {
      r.fail("[problem] neumann", "must be a list of sides or a table side = \"flux expression\"");
    }
  }
  if (neumann.size() == sides)
    r.fail("[problem] neumann", "every side is Neumann: the solution would only be defined up to a "
                                "constant; keep at least one Dirichlet side");
  if (const DocumentNode* d = t.get("dirichlet")) {
    if (auto s = d->value_exact<std::string>()) {
      const Expression g = Expression::parse(*s, f + ": [problem] dirichlet");
      for (auto& bc : pb.boundary)
        if (bc.kind == BoundaryKind::kDirichlet) { bc.from_exact = false; bc.value = g; }
    } else if (const DocumentNode* dt = d->as_table()) {
      for (const auto& [k, v] : *dt) {
        const std::string field = "[problem] dirichlet." + k;
        const std::string val = r.string(v, field);
        for (int s : ids_of(k, field)) {
          if (neumann.count(s)) r.fail(field, "side '" + labels.names[s] + "' is also listed under neumann");
          if (val != "exact") {
            pb.boundary[s].from_exact = false;
            pb.boundary[s].value = Expression::parse(val, f + ": " + field);
          }
        }
      }
    } else {
      r.fail("[problem] dirichlet", "must be an expression or a table side = \"expression\"");
    }
  }
  for (size_t s = 0; s < sides; ++s)
    if (pb.boundary[s].from_exact && !pb.exact)
      r.fail("[problem] " + std::string(pb.boundary[s].kind == BoundaryKind::kDirichlet ? "dirichlet" : "neumann"),
             "side '" + labels.names[s] + "' takes its data from the exact solution, but [problem] exact is not given");
}

void read_output(const CaseReader& r, const DocumentNode& t, CaseDescription& c) {
  r.check_keys(t, "output", {"directory", "bezier", "sampled", "samples"});
  if (const DocumentNode* d = t.get("directory")) c.output_directory = r.string(*d, "[output] directory");
  auto flag = [&](const char* key, bool& out) {
    if (const DocumentNode* n = t.get(key)) {
      auto b = n->value_exact<bool>();
      if (!b) r.fail(std::string("[output] ") + key, "must be true or false");
      out = *b;
    }
  };
  flag("bezier", c.write_bezier);
  flag("sampled", c.write_sampled);
  if (const DocumentNode* s = t.get("samples")) {
    c.samples = static_cast<int>(r.integer(*s, "[output] samples"));
    if (c.samples < 1 || c.samples > 64) r.fail("[output] samples", "must be in [1, 64]");
  }
}

void read_adapt(const CaseReader& r, const DocumentNode& t, CaseDescription& c) {
  r.check_keys(t, "adapt", {"steps", "theta", "max_dofs", "marking", "strategy", "min_fraction"});
  if (const DocumentNode* n = t.get("strategy")) {
    const std::string m = r.string(*n, "[adapt] strategy");
    if (m != "dorfler" && m != "maximum") r.fail("[adapt] strategy", "must be \"dorfler\" or \"maximum\", not \"" + m + "\"");
    c.adapt.maximum_strategy = m == "maximum";
  }
  if (const DocumentNode* n = t.get("min_fraction")) {
    c.adapt.min_fraction = r.number(*n, "[adapt] min_fraction");
    if (!(c.adapt.min_fraction >= 0 && c.adapt.min_fraction <= 1)) r.fail("[adapt] min_fraction", "must be in [0, 1]");
  }
  if (const DocumentNode* n = t.get("marking")) {
    const std::string m = r.string(*n, "[adapt] marking");
    if (m != "cells" && m != "functions") r.fail("[adapt] marking", "must be \"cells\" or \"functions\", not \"" + m + "\"");
    c.adapt.mark_functions = m == "functions";
  }
  if (const DocumentNode* n = t.get("steps")) {
    c.adapt.steps = static_cast<int>(r.integer(*n, "[adapt] steps"));
    if (c.adapt.steps < 1 || c.adapt.steps > 200) r.fail("[adapt] steps", "must be in [1, 200]");
  }
  if (const DocumentNode* n = t.get("theta")) {
    c.adapt.theta = r.number(*n, "[adapt] theta");
    if (!(c.adapt.theta > 0 && c.adapt.theta <= 1)) r.fail("[adapt] theta", "must be in (0, 1]");
  }
  if (const DocumentNode* n = t.get("max_dofs")) {
    c.adapt.max_dofs = r.integer(*n, "[adapt] max_dofs");
    if (c.adapt.max_dofs < 1) r.fail("[adapt] max_dofs", "must be positive");
  }
}

const std::vector<std::string>& solver_methods() {
  static const std::vector<std::string> names{"direct", "iterative", "auto", "petsc"};
  return names;
}

// `what` names the field in messages ("[solver] method" or "--solver").
std::string checked_name(const std::string& value, const std::vector<std::string>& valid, const std::string& what,
                         const std::string& file) {
  if (std::find(valid.begin(), valid.end(), value) != valid.end()) return value;
  std::string all;
  for (const auto& v : valid) all += (all.empty() ? "" : ", ") + v;
  std::string hint = closest_name(value, valid);
  if (hint.rfind("valid keys", 0) == 0) hint = "one of " + all;
  throw InputError((file.empty() ? "" : file + ": ") + what + ": '" + value + "' is not a choice (" + hint + ")");
}

namespace {

void check_tolerance(double t, const std::string& what, const std::string& file) {
  if (!(t > 0 && t < 1))
    throw InputError((file.empty() ? "" : file + ": ") + what + ": must be in (0, 1) (the backward error CG stops at, "
                     "or PETSc's relative residual), got " + std::to_string(t));
}

}  // namespace

void read_solver(const CaseReader& r, const DocumentNode& t, CaseDescription& c) {
  r.check_keys(t, "solver", {"method", "preconditioner", "tolerance", "max_iterations", "petsc_options", "matrix"});
  if (const DocumentNode* n = t.get("matrix"))
    c.solver.matrix = checked_name(r.string(*n, "[solver] matrix"), {"auto", "assembled", "matrix_free"}, "[solver] matrix", r.path());
  if (const DocumentNode* n = t.get("petsc_options")) c.solver.petsc_options = r.string(*n, "[solver] petsc_options");
  if (const DocumentNode* n = t.get("method"))
    c.solver.method = checked_name(r.string(*n, "[solver] method"), solver_methods(), "[solver] method", r.path());
  // Checked against the registered families' preconditioners by load_case.
  if (const DocumentNode* n = t.get("preconditioner")) c.solver.preconditioner = r.string(*n, "[solver] preconditioner");
  if (const DocumentNode* n = t.get("tolerance")) {
    c.solver.tolerance = r.number(*n, "[solver] tolerance");
    check_tolerance(c.solver.tolerance, "[solver] tolerance", r.path());
    c.solver.tolerance_given = true;
  }
  if (const DocumentNode* n = t.get("max_iterations")) {
    const long m = r.integer(*n, "[solver] max_iterations");
    if (m < 1 || m > 1000000) r.fail("[solver] max_iterations", "must be in [1, 1000000], got " + std::to_string(m));
    c.solver.max_iterations = static_cast<int>(m);
  }
}

void check_petsc_options(const CaseDescription& c, const std::string& what) {
  if (c.solver.petsc_options.empty() || c.solver.method == "petsc" || c.solver.preconditioner == kBoomerAmgName) return;
  throw InputError((what[0] == '[' ? c.path + ": " : std::string()) + what +
                   ": only used with method = \"petsc\" (PETSc's KSP and PC) or preconditioner = \"" + kBoomerAmgName +
                   "\" (PETSc's hypre BoomerAMG)");
}

void override_solver(CaseDescription& c, const std::string& method, double tolerance, const std::string* petsc_options) {
  if (!method.empty()) c.solver.method = checked_name(method, solver_methods(), "--solver", "");
  if (petsc_options) c.solver.petsc_options = *petsc_options;
  check_petsc_options(c, petsc_options ? "--petsc-options" : "[solver] petsc_options");
  if (tolerance != 0) {
    check_tolerance(tolerance, "--tolerance", "");
    c.solver.tolerance = tolerance;
    c.solver.tolerance_given = true;
  }
}

}  // namespace knotwork
