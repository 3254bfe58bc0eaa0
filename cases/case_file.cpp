#include "cases/case_file.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <toml++/toml.h>

#include "basis/g1/quad_mesh.hpp"
#include "cases/geometries.hpp"
#include "basis/g1/gluing_file.hpp"
#include "cases/json_input.hpp"
#include "solver/input_error.hpp"

namespace knotwork {

namespace {

constexpr int kMaxDegree = 10;
constexpr long kMaxCells = 1L << 26;  // ~67M cells: beyond any machine this runs on

const std::vector<std::string> kSides = {"bottom", "right", "top", "left"};

std::string shortest(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

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

std::string closest(const std::string& key, const std::vector<std::string>& valid) {
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

// Reads one case file, prefixing every message with the file and the field.
class Reader {
 public:
  explicit Reader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw InputError(path_ + ": " + field + ": " + what);
  }

  void check_keys(const toml::table& t, const std::string& section,
                  const std::vector<std::string>& valid) const {
    for (const auto& [k, v] : t) {
      const std::string key(k.str());
      if (std::find(valid.begin(), valid.end(), key) == valid.end())
        fail(section.empty() ? key : "[" + section + "] " + key,
             "unknown key (" + closest(key, valid) + ")");
    }
  }

  const toml::table& table(const toml::table& t, const std::string& key, bool required) const {
    static const toml::table empty;
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) fail("[" + key + "]", "missing section");
      return empty;
    }
    if (!n->is_table()) fail(key, "must be a table ([" + key + "])");
    return *n->as_table();
  }

  double number(const toml::node& n, const std::string& field) const {
    double v;
    if (auto i = n.value_exact<int64_t>()) v = static_cast<double>(*i);
    else if (auto d = n.value_exact<double>()) v = *d;
    else if (auto s = n.value_exact<std::string>()) v = rational_string(*s, field);
    else fail(field, "must be a number");
    if (!std::isfinite(v)) fail(field, "must be a finite number (got nan or inf)");
    return v;
  }

  double rational_string(const std::string& s, const std::string& field) const {
    // Exact rational such as "-1/3" (used by geometries written from exact data).
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

  // Exact: integers, rational strings ("14/9", "0.1" = 1/10), or a float's exact binary value.
  mpq_class rational(const toml::node& x, const std::string& field) const {
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

  long integer(const toml::node& n, const std::string& field) const {
    if (auto i = n.value_exact<int64_t>()) return static_cast<long>(*i);
    fail(field, "must be an integer");
  }

  std::array<long, 2> integer_pair(const toml::node& n, const std::string& field) const {
    if (auto a = n.as_array()) {
      if (a->size() != 2) fail(field, "must be an integer or a pair [u, v]");
      return {integer(*a->get(0), field), integer(*a->get(1), field)};
    }
    const long v = integer(n, field);
    return {v, v};
  }

  std::vector<double> numbers(const toml::node& n, const std::string& field) const {
    const toml::array* a = n.as_array();
    if (!a) fail(field, "must be an array of numbers");
    std::vector<double> r;
    for (size_t i = 0; i < a->size(); ++i)
      r.push_back(number(*a->get(i), field + "[" + std::to_string(i) + "]"));
    return r;
  }

  Eigen::MatrixX2d points(const toml::node& n, const std::string& field) const {
    const toml::array* a = n.as_array();
    if (!a) fail(field, "must be an array of [x, y] points");
    Eigen::MatrixX2d p(a->size(), 2);
    for (size_t i = 0; i < a->size(); ++i) {
      const std::string f = field + "[" + std::to_string(i) + "]";
      const auto xy = numbers(*a->get(i), f);
      if (xy.size() != 2) fail(f, "must be a point [x, y]");
      p(i, 0) = xy[0];
      p(i, 1) = xy[1];
    }
    return p;
  }

  std::string string(const toml::node& n, const std::string& field) const {
    if (auto s = n.value_exact<std::string>()) return *s;
    fail(field, "must be a string");
  }

  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// JSON input goes through the same validation as TOML: the document becomes a toml::table.
// Appends the converted value to `out` (plain recursion: no template instantiated per level).
void append_json(toml::array& out, const JsonValue& v, const std::string& path, const std::string& field) {
  using K = JsonValue::Kind;
  switch (v.kind) {
    case K::kNull: throw InputError(path + ": " + field + ": null is not a valid value here");
    case K::kBool: out.push_back(v.boolean); return;
    case K::kString: out.push_back(v.text); return;
    case K::kNumber:
      if (v.integral && std::abs(v.number) < 9.0e18) out.push_back(static_cast<int64_t>(std::stoll(v.text)));
      else out.push_back(v.number);
      return;
    case K::kArray: {
      toml::array a;
      for (size_t i = 0; i < v.items.size(); ++i) append_json(a, v.items[i], path, field + "[" + std::to_string(i) + "]");
      out.push_back(std::move(a));
      return;
    }
    case K::kObject: {
      toml::table t;
      for (const auto& [key, member] : v.members) {
        toml::array one;
        append_json(one, member, path, field.empty() ? key : field + "." + key);
        toml::node& n = *one.get(0);
        if (auto* x = n.as_table()) t.insert(key, std::move(*x));
        else if (auto* x = n.as_array()) t.insert(key, std::move(*x));
        else if (auto* x = n.as_string()) t.insert(key, x->get());
        else if (auto* x = n.as_integer()) t.insert(key, x->get());
        else if (auto* x = n.as_floating_point()) t.insert(key, x->get());
        else if (auto* x = n.as_boolean()) t.insert(key, x->get());
      }
      out.push_back(std::move(t));
      return;
    }
  }
}

bool is_json_file(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return ext == ".json";
}

toml::table parse_toml(const std::string& path) {
  if (is_json_file(path)) {
    const JsonValue doc = read_json_file(path);
    if (doc.kind != JsonValue::Kind::kObject) throw InputError(path + ": the JSON document must be an object {...}");
    toml::array one;
    append_json(one, doc, path, "");
    toml::table root = std::move(*one.get(0)->as_table());
    return root;
  }
  std::ifstream probe(path);
  if (!probe) {
    const std::string why = std::filesystem::exists(path) ? "cannot be read" : "no such file";
    throw InputError(path + ": cannot open case file (" + why + ")");
  }
  if (std::filesystem::is_directory(path)) throw InputError(path + ": is a directory, not a case file");
  try {
    return toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << path << ":" << e.source().begin.line << ":" << e.source().begin.column
      << ": TOML syntax error: " << e.description();
    throw InputError(s.str());
  }
}

NurbsPatch read_nurbs(const Reader& r, const toml::table& g, const std::string& section) {
  r.check_keys(g, section, {"type", "degrees", "knots_u", "knots_v", "control_points", "weights", "file"});
  const toml::table* src = &g;
  toml::table from_file;
  std::string field_prefix = "[" + section + "] ";
  if (const toml::node* f = g.get("file")) {
    std::filesystem::path file = r.string(*f, field_prefix + "file");
    if (file.is_relative()) file = std::filesystem::path(r.path()).parent_path() / file;
    from_file = parse_toml(file.string());
    Reader(file.string()).check_keys(from_file, "", {"degrees", "knots_u", "knots_v", "control_points", "weights"});
    src = &from_file;
    field_prefix = "(file " + file.string() + ") ";
  }
  auto need = [&](const char* key) -> const toml::node& {
    const toml::node* n = src->get(key);
    if (!n) r.fail(field_prefix + key, "missing required key for a nurbs geometry");
    return *n;
  };
  const auto deg = r.integer_pair(need("degrees"), field_prefix + "degrees");
  for (long d : deg)
    if (d < 1 || d > kMaxDegree) r.fail(field_prefix + "degrees", "must be in [1, 10]");
  NurbsPatch p;
  try {
    p.basis_u = BSplineBasis1D(static_cast<int>(deg[0]), r.numbers(need("knots_u"), field_prefix + "knots_u"));
  } catch (const std::invalid_argument& e) { r.fail(field_prefix + "knots_u", e.what()); }
  try {
    p.basis_v = BSplineBasis1D(static_cast<int>(deg[1]), r.numbers(need("knots_v"), field_prefix + "knots_v"));
  } catch (const std::invalid_argument& e) { r.fail(field_prefix + "knots_v", e.what()); }
  p.control_points = r.points(need("control_points"), field_prefix + "control_points");
  if (const toml::node* w = src->get("weights")) {
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

void read_geometry(const Reader& r, const toml::table& g, CaseDescription& c) {
  const toml::node* type = g.get("type");
  if (!type) r.fail("[geometry] type", "missing (rectangle, quarter_annulus, lshape or nurbs)");
  c.geometry_type = r.string(*type, "[geometry] type");
  if (c.geometry_type == "rectangle") {
    r.check_keys(g, "geometry", {"type", "corners"});
    Eigen::MatrixX2d corners(2, 2);
    corners << 0, 0, 1, 1;
    if (const toml::node* n = g.get("corners")) corners = r.points(*n, "[geometry] corners");
    if (corners.rows() != 2) r.fail("[geometry] corners", "must be [[x0, y0], [x1, y1]]");
    if (!(corners(1, 0) > corners(0, 0) && corners(1, 1) > corners(0, 1)))
      r.fail("[geometry] corners", "need x1 > x0 and y1 > y0");
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
  } else {
    r.fail("[geometry] type", "unknown geometry '" + c.geometry_type + "' (" +
                                  closest(c.geometry_type, {"rectangle", "quarter_annulus", "lshape", "nurbs"}) + ")");
  }
}

void check_degree(const Reader& r, const std::array<long, 2>& d, const std::string& field) {
  for (long v : d)
    if (v < 1 || v > kMaxDegree) r.fail(field, "must be in [1, 10], got " + std::to_string(v));
}

void check_elements(const Reader& r, const std::array<long, 2>& e, const std::string& field) {
  for (long v : e)
    if (v < 1) r.fail(field, "must be >= 1, got " + std::to_string(v));
  if (e[0] * e[1] > kMaxCells || e[0] > kMaxCells || e[1] > kMaxCells)
    r.fail(field, "too many elements (more than 2^26 cells)");
}

void read_quadrature(const Reader& r, const toml::table& s, CaseDescription& c) {
  auto read_points = [&](const char* key, int& pu, int& pv) {
    if (const toml::node* k = s.get(key)) {
      const auto q = r.integer_pair(*k, std::string("[space] ") + key);
      for (long v : q)
        if (v < 1 || v > 30) r.fail(std::string("[space] ") + key, "must be in [1, 30]");
      pu = static_cast<int>(q[0]);
      pv = static_cast<int>(q[1]);
    }
  };
  read_points("quadrature_points", c.quadrature.points_u, c.quadrature.points_v);
  read_points("error_quadrature_points", c.quadrature.error_points_u, c.quadrature.error_points_v);
}

// cells = [[x0, y0, x1, y1], ...] with exact coordinates (`field` names the key).
std::vector<RationalBox> read_cells(const Reader& r, const toml::node& node, const std::string& field) {
  const toml::array* a = node.as_array();
  if (!a) r.fail(field, "must be a list of cells [[x0, y0, x1, y1], ...]");
  std::vector<RationalBox> cells;
  for (size_t i = 0; i < a->size(); ++i) {
    const std::string f = field + "[" + std::to_string(i) + "]";
    const toml::array* c = a->get(i)->as_array();
    if (!c || c->size() != 4) r.fail(f, "must be [x0, y0, x1, y1]");
    mpq_class v[4];
    for (size_t k = 0; k < 4; ++k) v[k] = r.rational(*c->get(k), f);
    cells.push_back({v[0], v[1], v[2], v[3]});
  }
  return cells;
}

// segments = [{direction = "vertical", position, from, to}, ...] with exact coordinates.
std::vector<AxisSegment> read_axis_segments(const Reader& r, const toml::node& node, const std::string& field) {
  const toml::array* a = node.as_array();
  if (!a) r.fail(field, "must be a list of { direction, position, from, to }");
  std::vector<AxisSegment> out;
  for (size_t i = 0; i < a->size(); ++i) {
    const std::string f = field + "[" + std::to_string(i) + "]";
    const toml::table* t = a->get(i)->as_table();
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

// A T-mesh from `cells`, or from `grid` = {x = [...], y = [...]} and `segments` (`prefix`
// goes in front of the field names). Validated as a partition of a rectangle.
std::vector<RationalBox> read_tmesh(const Reader& r, const toml::table& t, const std::string& prefix) {
  std::vector<RationalBox> cells;
  const toml::node* c = t.get("cells");
  const toml::node* g = t.get("grid");
  if (c && g) r.fail(prefix + "grid", "give either cells or grid (with segments), not both");
  if (c) {
    if (t.get("segments")) r.fail(prefix + "segments", "inserted into a grid: use grid = {x = [...], y = [...]} with them");
    cells = read_cells(r, *c, prefix + "cells");
  } else if (g) {
    const toml::table* gt = g->as_table();
    if (!gt) r.fail(prefix + "grid", "must be a table {x = [...], y = [...]}");
    r.check_keys(*gt, prefix.empty() ? "grid" : prefix.substr(1, prefix.size() - 3) + ".grid", {"x", "y"});
    std::vector<mpq_class> xy[2];
    for (int d = 0; d < 2; ++d) {
      const std::string f = prefix + "grid." + (d == 0 ? "x" : "y");
      const toml::node* n = gt->get(d == 0 ? "x" : "y");
      if (!n || !n->as_array()) r.fail(f, "missing: the grid's coordinates, increasing");
      for (size_t i = 0; i < n->as_array()->size(); ++i)
        xy[d].push_back(r.rational(*n->as_array()->get(i), f + "[" + std::to_string(i) + "]"));
    }
    try {
      cells = grid_cells(xy[0], xy[1]);
    } catch (const std::invalid_argument& e) {
      r.fail(prefix + "grid", e.what());
    }
    if (const toml::node* sg = t.get("segments")) {
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

// [space] of family "pt".
void read_pt_space(const Reader& r, const toml::table& s, CaseDescription& c) {
  r.check_keys(s, "space", {"family", "degree", "elements", "cells", "tmesh", "segments", "extension",
                            "quadrature_points", "error_quadrature_points"});
  c.space.rational = false;
  const toml::node* d = s.get("degree");
  if (!d) r.fail("[space] degree", "missing required key");
  const auto dd = r.integer_pair(*d, "[space] degree");
  check_degree(r, dd, "[space] degree");
  c.space.degree = {static_cast<int>(dd[0]), static_cast<int>(dd[1])};
  const bool given = s.get("cells") || s.get("tmesh");
  c.space.elements_per_span = {1, 1};
  if (const toml::node* e = s.get("elements")) {
    const auto el = r.integer_pair(*e, "[space] elements");
    check_elements(r, el, "[space] elements");
    c.space.elements_per_span = {static_cast<int>(el[0]), static_cast<int>(el[1])};
  } else if (!given) {
    r.fail("[space] elements", "missing: give elements (a tensor start on the geometry's knot spans), cells or tmesh");
  }
  if (s.get("cells") && s.get("tmesh")) r.fail("[space] tmesh", "give either cells or tmesh, not both");
  if (const toml::node* cl = s.get("cells")) {
    c.pt.cells = read_cells(r, *cl, "[space] cells");
    try {
      RectangularPartition check(c.pt.cells);
    } catch (const std::invalid_argument& e) {
      r.fail("[space] cells", e.what());
    }
  }
  if (const toml::node* tm = s.get("tmesh")) {
    std::filesystem::path file = r.string(*tm, "[space] tmesh");
    if (file.is_relative()) file = std::filesystem::path(r.path()).parent_path() / file;
    c.pt.tmesh_file = file.string();
    c.pt.cells = load_partition(c.pt.tmesh_file, false).cells;
  }
  if (const toml::node* sg = s.get("segments")) c.pt.segments = read_axis_segments(r, *sg, "[space] segments");
  if (const toml::node* x = s.get("extension")) {
    const std::string e = r.string(*x, "[space] extension");
    if (const auto parsed = parse_pt_extension(e)) c.pt.extension = *parsed;
    else r.fail("[space] extension", "'" + e + "' is not one of auto, minimal, horizontal, vertical, diagonalizable (" +
                                         closest(e, {"auto", "minimal", "horizontal", "vertical", "diagonalizable"}) + ")");
  }
  read_quadrature(r, s, c);
}

void read_space(const Reader& r, const toml::table& s, CaseDescription& c) {
  if (const toml::node* f = s.get("family"); f && f->value_exact<std::string>() == "pt") {
    c.family = "pt";
    return read_pt_space(r, s, c);
  }
  r.check_keys(s, "space", {"family", "degree", "elements", "continuity", "rational", "quadrature_points",
                            "error_quadrature_points", "insert_knots_u", "insert_knots_v", "segments", "collection"});
  if (const toml::node* f = s.get("family")) {
    c.family = r.string(*f, "[space] family");
    if (c.family != "tensor" && c.family != "knot_segments")
      r.fail("[space] family", "'" + c.family + "' is not available (" +
                                   closest(c.family, {"tensor", "knot_segments", "g1", "pt"}) +
                                   "; this version builds \"tensor\", \"knot_segments\", \"g1\" and \"pt\")");
  }
  const bool segments_family = c.family == "knot_segments";
  if (segments_family) {
    c.space.rational = false;  // knot-segment spaces are polynomial B-splines on the exact geometry
    for (const char* key : {"continuity", "insert_knots_u", "insert_knots_v"})
      if (s.get(key))
        r.fail(std::string("[space] ") + key, "not used with family = \"knot_segments\" (its knots are C^(d-1); "
                                              "refine with segments, which take a multiplicity)");
    if (const toml::node* k = s.get("rational"))
      if (k->value_exact<bool>().value_or(false)) r.fail("[space] rational", "knot_segments spaces are polynomial B-splines");
    if (const toml::node* segs = s.get("segments")) {
      const toml::array* a = segs->as_array();
      if (!a) r.fail("[space] segments", "must be a list of { direction, position, from, to, multiplicity }");
      for (size_t i = 0; i < a->size(); ++i) {
        const std::string field = "[space] segments[" + std::to_string(i) + "]";
        const toml::table* t = a->get(i)->as_table();
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
        if (const toml::node* m = t->get("multiplicity")) k.multiplicity = static_cast<int>(r.integer(*m, field + " multiplicity"));
        c.segments.push_back(k);
      }
    }
    if (const toml::node* f = s.get("collection")) {
      std::filesystem::path file = r.string(*f, "[space] collection");
      if (file.is_relative()) file = std::filesystem::path(r.path()).parent_path() / file;
      for (const char* key : {"segments", "elements"})
        if (s.get(key))
          r.fail(std::string("[space] ") + key, "not used with an explicit collection (its functions are fixed)");
      c.collection_file = file.string();
      const CollectionDescription cd = load_collection(c.collection_file);
      c.collection = cd.splines;
      if (const toml::node* d = s.get("degree")) {
        const auto deg = r.integer_pair(*d, "[space] degree");
        if (deg[0] != cd.dx || deg[1] != cd.dy)
          r.fail("[space] degree", "the collection " + c.collection_file + " has degree [" + std::to_string(cd.dx) + ", " +
                                       std::to_string(cd.dy) + "]");
      }
      c.space.degree = {cd.dx, cd.dy};
      c.space.elements_per_span = {1, 1};
    }
  } else if (s.get("segments")) {
    r.fail("[space] segments", "only with family = \"knot_segments\"");
  } else if (s.get("collection")) {
    r.fail("[space] collection", "only with family = \"knot_segments\"");
  }
  if (c.collection_file.empty()) {
    const toml::node* d = s.get("degree");
    if (!d) r.fail("[space] degree", "missing required key");
    const auto dd = r.integer_pair(*d, "[space] degree");
    check_degree(r, dd, "[space] degree");
    c.space.degree = {static_cast<int>(dd[0]), static_cast<int>(dd[1])};
    const toml::node* e = s.get("elements");
    if (!e) r.fail("[space] elements", "missing required key");
    const auto el = r.integer_pair(*e, "[space] elements");
    check_elements(r, el, "[space] elements");
    c.space.elements_per_span = {static_cast<int>(el[0]), static_cast<int>(el[1])};
  }
  const std::array<long, 2> deg = {c.space.degree[0], c.space.degree[1]};
  if (const toml::node* k = s.get("continuity")) {
    const auto cont = r.integer_pair(*k, "[space] continuity");
    for (int i = 0; i < 2; ++i)
      if (cont[i] < 0 || cont[i] > deg[i] - 1)
        r.fail("[space] continuity", "must be in [0, degree-1], got " + std::to_string(cont[i]));
    c.space.continuity = {static_cast<int>(cont[0]), static_cast<int>(cont[1])};
  }
  if (const toml::node* k = s.get("rational")) {
    auto b = k->value_exact<bool>();
    if (!b) r.fail("[space] rational", "must be true or false");
    c.space.rational = *b;
  }
  for (int d = 0; d < 2; ++d) {
    const std::string key = d == 0 ? "insert_knots_u" : "insert_knots_v";
    if (const toml::node* k = s.get(key)) {
      c.space.extra_knots[d] = r.numbers(*k, "[space] " + key);
      const BSplineBasis1D& g = d == 0 ? c.geometry.basis_u : c.geometry.basis_v;
      for (double t : c.space.extra_knots[d])
        if (!(t > g.domain_begin() && t < g.domain_end()))
          r.fail("[space] " + key, "knot " + shortest(t) + " is not inside the parameter domain (" +
                                       shortest(g.domain_begin()) + ", " + shortest(g.domain_end()) + ")");
    }
  }
  read_quadrature(r, s, c);
}

int side_index(const Reader& r, const std::string& side, const std::string& field) {
  for (size_t i = 0; i < kSides.size(); ++i)
    if (kSides[i] == side) return static_cast<int>(i);
  r.fail(field, "unknown side '" + side + "' (" + closest(side, kSides) + "; sides are bottom, right, top, left)");
}

void read_problem(const Reader& r, const toml::table& t, CaseDescription& c) {
  r.check_keys(t, "problem", {"exact", "source", "dirichlet", "neumann"});
  PoissonProblem& pb = c.problem;
  const std::string& f = r.path();
  if (const toml::node* e = t.get("exact")) {
    const Expression u = Expression::parse(r.string(*e, "[problem] exact"), f + ": [problem] exact");
    pb.exact = differentiate_exact_solution(u);
  }
  if (const toml::node* s = t.get("source"))
    pb.source = Expression::parse(r.string(*s, "[problem] source"), f + ": [problem] source");
  else if (pb.exact)
    pb.source = pb.exact->minus_laplacian;
  else
    r.fail("[problem] source", "missing: give `source`, or `exact` to derive it from");

  pb.boundary.assign(4, BoundaryCondition{});
  std::set<int> neumann;
  if (const toml::node* n = t.get("neumann")) {
    if (const toml::array* a = n->as_array()) {
      for (size_t i = 0; i < a->size(); ++i) {
        const int s = side_index(r, r.string(*a->get(i), "[problem] neumann"), "[problem] neumann");
        pb.boundary[s].kind = BoundaryKind::kNeumann;
        neumann.insert(s);
      }
    } else if (const toml::table* nt = n->as_table()) {
      for (const auto& [k, v] : *nt) {
        const std::string field = "[problem] neumann." + std::string(k.str());
        const int s = side_index(r, std::string(k.str()), field);
        const std::string val = r.string(v, field);
        pb.boundary[s].kind = BoundaryKind::kNeumann;
        if (val != "exact") {
          pb.boundary[s].from_exact = false;
          pb.boundary[s].value = Expression::parse(val, f + ": " + field);
        }
        neumann.insert(s);
      }
    } else {
      r.fail("[problem] neumann", "must be a list of sides or a table side = \"flux expression\"");
    }
  }
  if (neumann.size() == 4)
    r.fail("[problem] neumann", "every side is Neumann: the solution would only be defined up to a "
                                "constant; keep at least one Dirichlet side");
  if (const toml::node* d = t.get("dirichlet")) {
    if (auto s = d->value_exact<std::string>()) {
      const Expression g = Expression::parse(*s, f + ": [problem] dirichlet");
      for (auto& bc : pb.boundary)
        if (bc.kind == BoundaryKind::kDirichlet) { bc.from_exact = false; bc.value = g; }
    } else if (const toml::table* dt = d->as_table()) {
      for (const auto& [k, v] : *dt) {
        const std::string field = "[problem] dirichlet." + std::string(k.str());
        const int s = side_index(r, std::string(k.str()), field);
        if (neumann.count(s)) r.fail(field, "side is also listed under neumann");
        const std::string val = r.string(v, field);
        if (val != "exact") {
          pb.boundary[s].from_exact = false;
          pb.boundary[s].value = Expression::parse(val, f + ": " + field);
        }
      }
    } else {
      r.fail("[problem] dirichlet", "must be an expression or a table side = \"expression\"");
    }
  }
  for (size_t s = 0; s < 4; ++s)
    if (pb.boundary[s].from_exact && !pb.exact)
      r.fail("[problem] " + std::string(pb.boundary[s].kind == BoundaryKind::kDirichlet ? "dirichlet" : "neumann"),
             "side '" + kSides[s] + "' takes its data from the exact solution, but [problem] exact is not given");
}

void read_output(const Reader& r, const toml::table& t, CaseDescription& c) {
  r.check_keys(t, "output", {"directory", "bezier", "sampled", "samples"});
  if (const toml::node* d = t.get("directory")) c.output_directory = r.string(*d, "[output] directory");
  auto flag = [&](const char* key, bool& out) {
    if (const toml::node* n = t.get(key)) {
      auto b = n->value_exact<bool>();
      if (!b) r.fail(std::string("[output] ") + key, "must be true or false");
      out = *b;
    }
  };
  flag("bezier", c.write_bezier);
  flag("sampled", c.write_sampled);
  if (const toml::node* s = t.get("samples")) {
    c.samples = static_cast<int>(r.integer(*s, "[output] samples"));
    if (c.samples < 1 || c.samples > 64) r.fail("[output] samples", "must be in [1, 64]");
  }
}

void read_adapt(const Reader& r, const toml::table& t, CaseDescription& c) {
  r.check_keys(t, "adapt", {"steps", "theta", "max_dofs"});
  if (const toml::node* n = t.get("steps")) {
    c.adapt.steps = static_cast<int>(r.integer(*n, "[adapt] steps"));
    if (c.adapt.steps < 1 || c.adapt.steps > 200) r.fail("[adapt] steps", "must be in [1, 200]");
  }
  if (const toml::node* n = t.get("theta")) {
    c.adapt.theta = r.number(*n, "[adapt] theta");
    if (!(c.adapt.theta > 0 && c.adapt.theta <= 1)) r.fail("[adapt] theta", "must be in (0, 1]");
  }
  if (const toml::node* n = t.get("max_dofs")) {
    c.adapt.max_dofs = r.integer(*n, "[adapt] max_dofs");
    if (c.adapt.max_dofs < 1) r.fail("[adapt] max_dofs", "must be positive");
  }
}

// A case of family "g1": [space] mesh/degree/split_smoothness/gluing/refine, [geometry]
// shape, [problem] operator/exact/source/reaction/dirichlet. See cases/README.md.
void read_g1_case(const Reader& r, const toml::table& root, CaseDescription& c) {
  auto& g = c.g1;
  const toml::table& s = r.table(root, "space", true);
  r.check_keys(s, "space", {"family", "mesh", "degree", "split_smoothness", "gluing", "refine", "smoothness",
                            "quadrature_points", "error_quadrature_points"});
  const std::filesystem::path folder = std::filesystem::path(r.path()).parent_path();
  auto resolve = [&](const std::string& file) {
    std::filesystem::path f = file;
    return (f.is_relative() ? folder / f : f).string();
  };
  const toml::node* m = s.get("mesh");
  if (!m) r.fail("[space] mesh", "missing: the quad mesh (.obj) the G1 space lives on");
  g.mesh_file = resolve(r.string(*m, "[space] mesh"));
  QuadMesh mesh;
  try {
    mesh = QuadMesh::read_obj(g.mesh_file);
  } catch (const std::invalid_argument& e) {
    r.fail("[space] mesh", e.what());
  }
  g.faces = mesh.num_faces();
  if (const toml::node* d = s.get("degree")) g.degree = static_cast<int>(r.integer(*d, "[space] degree"));
  if (g.degree < 2 || g.degree > 12) r.fail("[space] degree", "must be in [2, 12] (one integer: the bidegree k of the patches)");
  if (const toml::node* d = s.get("split_smoothness"))
    g.split_smoothness = static_cast<int>(r.integer(*d, "[space] split_smoothness"));
  if (g.split_smoothness < 1 || g.split_smoothness > g.degree - 1)
    r.fail("[space] split_smoothness", "must be in [1, degree-1] (C^r across the 4-split lines; r >= 1 for "
                                       "refinement to nest the spaces), got " + std::to_string(g.split_smoothness));
  if (const toml::node* d = s.get("gluing")) {
    g.gluing = r.string(*d, "[space] gluing");
    if (!is_named_gluing(g.gluing)) g.gluing = resolve(g.gluing);
  }
  if (const toml::node* d = s.get("refine")) g.refine = static_cast<int>(r.integer(*d, "[space] refine"));
  if (const toml::node* d = s.get("smoothness")) {
    const std::string v = r.string(*d, "[space] smoothness");
    if (v != "g1" && v != "c0") r.fail("[space] smoothness", "must be \"g1\" (default) or \"c0\" (the C0 multipatch baseline)");
    g.c0 = v == "c0";
  }
  if (g.refine < 0 || g.refine > 6) r.fail("[space] refine", "must be in [0, 6]");
  auto read_points = [&](const char* key, int& pu, int& pv) {
    if (const toml::node* k = s.get(key)) {
      const long q = r.integer(*k, std::string("[space] ") + key);
      if (q < 1 || q > 30) r.fail(std::string("[space] ") + key, "must be in [1, 30]");
      pu = pv = static_cast<int>(q);
    }
  };
  read_points("quadrature_points", c.quadrature.points_u, c.quadrature.points_v);
  read_points("error_quadrature_points", c.quadrature.error_points_u, c.quadrature.error_points_v);
  c.space.degree = {g.degree, g.degree};

  const toml::table& geo = r.table(root, "geometry", false);
  r.check_keys(geo, "geometry", {"shape", "center", "radius", "major_radius", "minor_radius"});
  if (const toml::node* n = geo.get("shape")) g.shape = r.string(*n, "[geometry] shape");
  if (g.shape != "bilinear" && g.shape != "sphere" && g.shape != "torus")
    r.fail("[geometry] shape", "unknown shape '" + g.shape + "' (" + closest(g.shape, {"bilinear", "sphere", "torus"}) + ")");
  if (const toml::node* n = geo.get("center")) {
    const toml::array* a = n->as_array();
    if (!a || a->size() != 3) r.fail("[geometry] center", "must be [x, y, z]");
    for (int i = 0; i < 3; ++i) g.center(i) = r.number(*a->get(i), "[geometry] center");
  }
  auto positive = [&](const char* key, double& out) {
    if (const toml::node* n = geo.get(key)) {
      out = r.number(*n, std::string("[geometry] ") + key);
      if (!(out > 0)) r.fail(std::string("[geometry] ") + key, "must be > 0");
    }
  };
  positive("radius", g.radius);
  positive("major_radius", g.major_radius);
  positive("minor_radius", g.minor_radius);
  if (g.shape == "torus" && !(g.minor_radius < g.major_radius))
    r.fail("[geometry] minor_radius", "must be smaller than major_radius");
  if (g.shape != "sphere" && (geo.get("radius")))
    r.fail("[geometry] radius", "only with shape = \"sphere\"");

  const toml::table& t = r.table(root, "problem", true);
  r.check_keys(t, "problem", {"operator", "exact", "source", "reaction", "dirichlet"});
  std::string op = "laplace";
  if (const toml::node* n = t.get("operator")) op = r.string(*n, "[problem] operator");
  if (op != "laplace" && op != "laplace_beltrami")
    r.fail("[problem] operator", "'" + op + "' (" + closest(op, {"laplace", "laplace_beltrami"}) + ")");
  g.surface = op == "laplace_beltrami";
  const std::string& f = r.path();
  if (!g.surface) {
    if (!mesh.planar()) {
      int v = 0;
      while (v < mesh.num_vertices() && mesh.vertex(v).z() == 0) ++v;
      r.fail("[space] mesh", g.mesh_file + ": vertex " + std::to_string(v + 1) + " has z = " +
                                 std::to_string(mesh.vertex(v).z()) +
                                 "; operator = \"laplace\" needs a planar mesh (z = 0), surfaces take "
                                 "operator = \"laplace_beltrami\"");
    }
    if (mesh.closed()) r.fail("[space] mesh", "a planar mesh without boundary");
    if (g.shape != "bilinear") r.fail("[geometry] shape", "planar cases use shape = \"bilinear\"");
    if (t.get("reaction")) r.fail("[problem] reaction", "only with operator = \"laplace_beltrami\"");
    PoissonProblem& pb = c.problem;
    if (const toml::node* e = t.get("exact"))
      pb.exact = differentiate_exact_solution(Expression::parse(r.string(*e, "[problem] exact"), f + ": [problem] exact"));
    if (const toml::node* e = t.get("source"))
      pb.source = Expression::parse(r.string(*e, "[problem] source"), f + ": [problem] source");
    else if (pb.exact)
      pb.source = pb.exact->minus_laplacian;
    else
      r.fail("[problem] source", "missing: give `source`, or `exact` to derive it from");
    pb.boundary.assign(1, BoundaryCondition{});  // one boundary: the whole of it
    if (const toml::node* d = t.get("dirichlet")) {
      const auto text = d->value_exact<std::string>();
      if (!text) r.fail("[problem] dirichlet", "must be \"exact\" or an expression (G1 domains have one boundary)");
      if (*text != "exact") {
        pb.boundary[0].from_exact = false;
        pb.boundary[0].value = Expression::parse(*text, f + ": [problem] dirichlet");
      }
    }
    if (pb.boundary[0].from_exact && !pb.exact)
      r.fail("[problem] dirichlet", "the boundary data come from the exact solution, but [problem] exact is not given");
    return;
  }
  if (t.get("dirichlet"))
    r.fail("[problem] dirichlet", mesh.closed() ? "the surface " + g.mesh_file + " is closed: it has no boundary to "
                                                  "put Dirichlet data on"
                                                : "Dirichlet data on surfaces are not supported (closed surfaces only)");
  if (!mesh.closed())
    r.fail("[space] mesh", g.mesh_file + " has a boundary; Laplace-Beltrami problems are solved on closed surfaces");
  PoissonProblem& pb = c.problem;
  if (const toml::node* n = t.get("reaction")) {
    pb.reaction = r.number(*n, "[problem] reaction");
    if (!(pb.reaction >= 0)) r.fail("[problem] reaction", "must be >= 0 (0: zero-mean solution)");
  }
  if (const toml::node* e = t.get("exact"))
    pb.exact = differentiate_surface_solution(Expression::parse(r.string(*e, "[problem] exact"), f + ": [problem] exact"));
  // No source: derived from the exact solution on the discrete surface by the assembler.
  if (const toml::node* e = t.get("source"))
    pb.source = Expression::parse(r.string(*e, "[problem] source"), f + ": [problem] source");
  if (!pb.exact && pb.source.empty())
    r.fail("[problem] source", "missing: give `source`, or `exact` to derive it on the surface");
}

}  // namespace

CaseDescription load_case(const std::string& path) {
  const toml::table root = parse_toml(path);
  Reader r(path);
  r.check_keys(root, "", {"title", "description", "geometry", "space", "problem", "output", "adapt"});
  CaseDescription c;
  c.path = path;
  c.name = std::filesystem::path(path).stem().string();
  c.output_directory = "results/" + c.name;
  if (const toml::node* t = root.get("title")) c.title = r.string(*t, "title");
  if (const toml::node* t = root.get("description")) r.string(*t, "description");
  if (const toml::node* sp = root.get("space"); sp && sp->is_table())
    if (const toml::node* fam = sp->as_table()->get("family"); fam && fam->value_exact<std::string>() == "g1") {
      c.family = "g1";
      read_g1_case(r, root, c);
      read_output(r, r.table(root, "output", false), c);
      if (root.get("adapt")) r.fail("[adapt]", "not available for family = \"g1\" (refinement is uniform subdivision)");
      return c;
    }
  read_geometry(r, r.table(root, "geometry", true), c);
  read_space(r, r.table(root, "space", true), c);
  read_problem(r, r.table(root, "problem", true), c);
  read_output(r, r.table(root, "output", false), c);
  read_adapt(r, r.table(root, "adapt", false), c);
  return c;
}

void require_highest_smoothness(const PartitionDescription& p, const std::string& path, const std::string& space) {
  if (p.alpha != p.m - 1 || p.beta != p.n - 1)
    throw InputError(path + ": smoothness: " + space + " (smoothness = [" + std::to_string(p.m - 1) + ", " +
                     std::to_string(p.n - 1) + "]); `knotwork dimension` counts other smoothness");
}

PartitionDescription load_partition(const std::string& path, bool need_degree) {
  const toml::table root = parse_toml(path);
  Reader r(path);
  r.check_keys(root, "", {"cells", "grid", "segments", "degree", "smoothness", "title", "description"});
  PartitionDescription d;
  const toml::node* deg = root.get("degree");
  if (!deg && need_degree) r.fail("degree", "missing required key ([m, n] or one int)");
  if (deg) {
    const auto mn = r.integer_pair(*deg, "degree");
    check_degree(r, mn, "degree");
    d.m = static_cast<int>(mn[0]);
    d.n = static_cast<int>(mn[1]);
  }
  d.alpha = d.m - 1;
  d.beta = d.n - 1;
  if (const toml::node* sm = root.get("smoothness")) {
    const auto ab = r.integer_pair(*sm, "smoothness");
    if (ab[0] < -1 || ab[0] > d.m - 1 || ab[1] < -1 || ab[1] > d.n - 1)
      r.fail("smoothness", "must be in [-1, degree-1] per direction");
    d.alpha = static_cast<int>(ab[0]);
    d.beta = static_cast<int>(ab[1]);
  }
  d.cells = read_tmesh(r, root, "");
  return d;
}

CollectionDescription load_collection(const std::string& path) {
  const toml::table root = parse_toml(path);
  Reader r(path);
  r.check_keys(root, "", {"degree", "functions", "case", "title", "description"});
  const toml::node* deg = root.get("degree");
  if (!deg) r.fail("degree", "missing required key ([dx, dy] or one int)");
  const auto d = r.integer_pair(*deg, "degree");
  check_degree(r, d, "degree");
  CollectionDescription c;
  c.dx = static_cast<int>(d[0]);
  c.dy = static_cast<int>(d[1]);
  const toml::node* fs = root.get("functions");
  if (!fs || !fs->is_array() || fs->as_array()->empty())
    r.fail("functions", "missing: give functions = [{x = [...], y = [...]}, ...], each with its local knot vectors");
  const toml::array& a = *fs->as_array();
  for (size_t i = 0; i < a.size(); ++i) {
    const std::string field = "functions[" + std::to_string(i) + "]";
    const toml::table* t = a.get(i)->as_table();
    if (!t) r.fail(field, "must be a table {x = [...], y = [...]}");
    r.check_keys(*t, field, {"x", "y"});
    LocalBSpline b;
    for (const char* key : {"x", "y"}) {
      const toml::node* k = t->get(key);
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

InputKind input_kind(const std::string& path) {
  const toml::table root = parse_toml(path);
  if (root.get("functions")) return InputKind::kCollection;
  if (root.get("cells") || root.get("grid")) return InputKind::kPartition;
  return InputKind::kCase;
}

void override_degree(CaseDescription& c, int degree) {
  if (!c.collection_file.empty())
    throw InputError("--degree: not used with [space] collection (" + c.collection_file + " fixes the degree)");
  if (degree < 1 || degree > kMaxDegree)
    throw InputError("--degree: must be in [1, 10], got " + std::to_string(degree));
  c.space.degree = {degree, degree};
  for (int& r : c.space.continuity)
    if (r > degree - 1) r = degree - 1;
}

void override_elements(CaseDescription& c, int elements) {
  if (!c.collection_file.empty())
    throw InputError("--elements: not used with [space] collection (" + c.collection_file + " fixes the functions)");
  if (elements < 1) throw InputError("--elements: must be >= 1, got " + std::to_string(elements));
  if (static_cast<long>(elements) * elements > kMaxCells)
    throw InputError("--elements: too many elements (more than 2^26 cells)");
  c.space.elements_per_span = {elements, elements};
}

void check_uniform_levels(const CaseDescription& c, int levels) {
  const long finest = static_cast<long>(c.space.elements_per_span[0]) << (levels - 1);
  if (finest * (static_cast<long>(c.space.elements_per_span[1]) << (levels - 1)) > kMaxCells)
    throw InputError("--levels: the finest level would have more than 2^26 cells");
}

}  // namespace knotwork
