// G+Smo's XML geometry files, read with pugixml: <Geometry type="TensorBSpline2|TensorNurbs2"
// id="..."> with its <Basis> (a TensorBSplineBasis2 of two BSplineBasis <KnotVector
// degree="p">, inside a TensorNurbsBasis2 with <weights> for NURBS) and <coefs geoDim="2">
// (Euclidean control points, u fastest); volumes the same with 3 (TensorBSpline3, three
// BSplineBasis, geoDim="3", sides 1..6); <MultiPatch parDim="2"> with <patches type="id_range"
// or "id_index">, <interfaces> (rows "patch side patch side", the direction map and the
// orientation flags) and <boundary [name="..."]> ("patch side" pairs). Patches in interfaces
// and boundaries are referred to by their id; a file whose references are not ids but all
// lie in 0..N-1 refers by position in <patches> (both occur in the wild).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <pugixml.hpp>
#include <sstream>

#include "basis/core/input_error.hpp"
#include "cases/geometry_file.hpp"
#include "cases/output_files.hpp"
#include "cases/xml_file.hpp"

namespace knotwork {

namespace {



pugi::xml_node child_of_type(const pugi::xml_node& n, const char* element, const char* type) {
  for (pugi::xml_node c : n.children(element))
    if (std::string(c.attribute("type").value()) == type) return c;
  return {};
}

// One TensorBSpline<dim> or TensorNurbs<dim> geometry in R^dim: its knot vectors, Euclidean
// control points (u fastest) and weights.
struct FileTensor {
  std::vector<BSplineBasis1D> bases;
  Eigen::MatrixXd points;
  Eigen::VectorXd weights;
};

FileTensor read_tensor(const XmlFile& f, const pugi::xml_node& g, const std::string& name, int dim) {
  const std::string type = g.attribute("type").value(), d = std::to_string(dim);
  const bool rational = type == "TensorNurbs" + d;
  const std::string nurbs_basis = "TensorNurbsBasis" + d, spline_basis = "TensorBSplineBasis" + d;
  pugi::xml_node basis = child_of_type(g, "Basis", (rational ? nurbs_basis : spline_basis).c_str());
  if (!basis) f.fail(g, name + ": no <Basis type=\"" + (rational ? nurbs_basis : spline_basis) + "\">");
  pugi::xml_node tensor = rational ? child_of_type(basis, "Basis", spline_basis.c_str()) : basis;
  if (!tensor) f.fail(basis, name + ": no <Basis type=\"" + spline_basis + "\"> inside the NURBS basis");
  FileTensor p;
  long n = 1;
  for (int k = 0; k < dim; ++k) {
    pugi::xml_node b;
    for (pugi::xml_node c : tensor.children("Basis"))
      if (std::string(c.attribute("type").value()) == "BSplineBasis" && c.attribute("index").as_int(-1) == k) b = c;
    if (!b) f.fail(tensor, name + ": no <Basis type=\"BSplineBasis\" index=\"" + std::to_string(k) + "\">");
    pugi::xml_node kv = b.child("KnotVector");
    if (!kv) f.fail(b, name + ": no <KnotVector> in direction " + std::to_string(k));
    const long degree = f.integer_attribute(kv, "degree", name + " KnotVector");
    if (degree < 1 || degree > 10) f.fail(kv, name + " KnotVector: degree must be in [1, 10], got " + std::to_string(degree));
    std::vector<double> knots = f.numbers(kv, name + " KnotVector");
    try {
      p.bases.emplace_back(static_cast<int>(degree), std::move(knots));
    } catch (const std::invalid_argument& e) {
      f.fail(kv, name + " KnotVector: " + e.what());
    }
    n *= p.bases.back().num_functions();
    if (n > kMaxControlPoints) f.fail(g, name + ": more than 2^24 control points");
  }
  pugi::xml_node coefs = g.child("coefs");
  if (!coefs) f.fail(g, name + ": no <coefs>");
  const long geo = coefs.attribute("geoDim") ? f.integer_attribute(coefs, "geoDim", name + " coefs") : dim;
  if (geo != dim)
    f.fail(coefs, name + " coefs: geoDim must be " + d + (dim == 2 ? " (a planar domain)" : " (a volume in space)") +
                      ", got " + std::to_string(geo));
  const std::vector<double> c = f.numbers(coefs, name + " coefs");
  if (static_cast<long>(c.size()) != dim * n)
    f.fail(coefs, name + " coefs: the knot vectors need " + std::to_string(n) + " points (" + std::to_string(dim * n) +
                      " numbers), found " + std::to_string(c.size()) + " numbers");
  p.points.resize(n, dim);
  for (long i = 0; i < n; ++i)
    for (int k = 0; k < dim; ++k) p.points(i, k) = c[dim * i + k];
  p.weights = Eigen::VectorXd::Ones(n);
  if (rational) {
    pugi::xml_node w = basis.child("weights");
    if (!w) f.fail(basis, name + ": a " + nurbs_basis + " without <weights>");
    const std::vector<double> ws = f.numbers(w, name + " weights");
    if (static_cast<long>(ws.size()) != n)
      f.fail(w, name + " weights: expected " + std::to_string(n) + ", found " + std::to_string(ws.size()));
    for (long i = 0; i < n; ++i) {
      if (!(ws[i] > 0)) f.fail(w, name + " weights: weight " + std::to_string(i + 1) + " must be positive");
      p.weights[i] = ws[i];
    }
  }
  return p;
}

NurbsPatch read_patch(const XmlFile& f, const pugi::xml_node& g, const std::string& name) {
  FileTensor t = read_tensor(f, g, name, 2);
  NurbsPatch p;
  p.basis_u = std::move(t.bases[0]);
  p.basis_v = std::move(t.bases[1]);
  p.control_points = t.points;
  p.weights = std::move(t.weights);
  return p;
}

// The geometries of the file by id, the ids of its patches (the MultiPatch's, else every
// geometry's) and the MultiPatch (null without one), checked for `dim` parametric directions.
struct FileLayout {
  std::map<long, pugi::xml_node> geometry;
  std::vector<long> ids;
  pugi::xml_node multipatch;
};

FileLayout read_layout(const XmlFile& f, const std::string& path) {
  pugi::xml_node root = f.doc().child("xml");
  if (!root) throw InputError(path + ": the root element must be <xml> (a G+Smo file)");
  FileLayout l;
  for (pugi::xml_node g : root.children("Geometry")) {
    const long id = f.integer_attribute(g, "id", "Geometry");
    if (l.geometry.count(id)) f.fail(g, "Geometry id " + std::to_string(id) + " is given twice");
    l.geometry[id] = g;
  }
  pugi::xml_node mp = root.child("MultiPatch");
  if (mp && mp.next_sibling("MultiPatch")) f.fail(mp.next_sibling("MultiPatch"), "more than one <MultiPatch>");
  l.multipatch = mp;
  if (mp) {
    pugi::xml_node patches = mp.child("patches");
    if (!patches) f.fail(mp, "MultiPatch: no <patches>");
    const std::string type = patches.attribute("type").value();
    const std::vector<long> v = f.integers(patches, "patches");
    if (type == "id_range") {
      if (v.size() != 2 || v[1] < v[0] || v[1] - v[0] >= 100000)
        f.fail(patches, "patches type=\"id_range\" must be \"first last\" with first <= last (at most 100000 patches)");
      for (long id = v[0]; id <= v[1]; ++id) l.ids.push_back(id);
    } else if (type == "id_index") {
      if (v.empty() || v.size() > 100000) f.fail(patches, "patches type=\"id_index\" must list 1 to 100000 ids");
      l.ids = v;
    } else {
      f.fail(patches, "patches type must be \"id_range\" or \"id_index\", got \"" + type + "\"");
    }
    for (long id : l.ids)
      if (!l.geometry.count(id))
        f.fail(patches, "patch id " + std::to_string(id) + " has no <Geometry id=\"" + std::to_string(id) + "\">");
  } else {
    for (const auto& [id, g] : l.geometry) l.ids.push_back(id);
    if (l.ids.empty()) throw InputError(path + ": no <Geometry> and no <MultiPatch>");
  }
  return l;
}

// Whether a Geometry's type is a volume's.
bool is_volume_type(const pugi::xml_node& g) {
  const std::string type = g.attribute("type").value();
  return type == "TensorBSpline3" || type == "TensorNurbs3";
}

// A <Geometry> that must be a volume (TensorBSpline3 or TensorNurbs3), as a NurbsVolume.
NurbsVolume read_volume_patch(const XmlFile& f, const pugi::xml_node& g, long id) {
  const std::string type = g.attribute("type").value(), name = "Geometry id " + std::to_string(id);
  if (!is_volume_type(g))
    f.fail(g, name + " has type \"" + type + "\" where a volume (TensorBSpline3 or TensorNurbs3) is read" +
                  (type == "TensorBSpline2" || type == "TensorNurbs2" ? ": a planar patch" : ""));
  FileTensor t = read_tensor(f, g, name, 3);
  NurbsVolume volume;
  for (int k = 0; k < 3; ++k) volume.bases[k] = std::move(t.bases[k]);
  volume.control_points = t.points;
  volume.weights = std::move(t.weights);
  return volume;
}

// A MultiPatch's <interfaces> rows and <boundary> lists, each parsed once, and how its patch
// references resolve: by id if every one is an id, else by position if every one is one.
struct PatchReferences {
  std::vector<std::pair<pugi::xml_node, std::vector<long>>> interfaces, boundaries;
  std::map<long, int> index_of_id;
  bool by_id = true, by_position = true;
  PatchSideRef resolve(const XmlFile& f, const pugi::xml_node& node, long patch, long side, int sides, const std::string& range) const {
    if (!by_id && !by_position) f.fail(node, "patch " + std::to_string(patch) + " is neither a patch id nor a position in <patches>");
    if (side < 1 || side > sides) f.fail(node, "side " + std::to_string(side) + " does not exist (" + range + ")");
    return PatchSideRef{by_id ? index_of_id.at(patch) : static_cast<int>(patch), static_cast<int>(side)};
  }
  // The named <boundary> lists (an unnamed one only says which sides are boundary).
  std::vector<NamedBoundary> named_boundaries(const XmlFile& f, int sides, const std::string& range) const {
    std::vector<NamedBoundary> out;
    for (const auto& [b, v] : boundaries) {
      NamedBoundary nb;
      nb.name = b.attribute("name").value();
      nb.where = f.at(b);
      for (size_t k = 0; k < v.size(); k += 2) nb.sides.push_back(resolve(f, b, v[k], v[k + 1], sides, range));
      if (nb.name.empty()) continue;
      for (const NamedBoundary& other : out)
        if (other.name == nb.name) f.fail(b, "boundary \"" + nb.name + "\" is given twice");
      out.push_back(std::move(nb));
    }
    return out;
  }
};

// `row`: the integers of one interface row; `row_fault`: what a list of another length breaks;
// `side`: what a boundary list pairs with patches ("side", "face").
PatchReferences read_references(const XmlFile& f, const FileLayout& l, size_t row, const std::string& row_fault,
                                const std::string& side) {
  PatchReferences r;
  if (const pugi::xml_node mp = l.multipatch) {
    for (pugi::xml_node in : mp.children("interfaces")) {
      r.interfaces.emplace_back(in, f.integers(in, "interfaces"));
      if (r.interfaces.back().second.size() % row != 0)
        f.fail(in, row_fault + ", found " + std::to_string(r.interfaces.back().second.size()) + " integers");
    }
    for (pugi::xml_node b : mp.children("boundary")) {
      r.boundaries.emplace_back(b, f.integers(b, "boundary"));
      if (r.boundaries.back().second.size() % 2 != 0)
        f.fail(b, "boundary: expected \"patch " + side + "\" pairs, found an odd number of integers");
    }
  }
  for (size_t k = 0; k < l.ids.size(); ++k) r.index_of_id[l.ids[k]] = static_cast<int>(k);
  const auto note = [&](long patch) {
    r.by_id = r.by_id && r.index_of_id.count(patch);
    r.by_position = r.by_position && patch >= 0 && patch < static_cast<long>(l.ids.size());
  };
  for (const auto& [node, v] : r.interfaces)
    for (size_t k = 0; k < v.size(); k += row) note(v[k]), note(v[k + 2]);
  for (const auto& [node, v] : r.boundaries)
    for (size_t k = 0; k < v.size(); k += 2) note(v[k]);
  return r;
}

}  // namespace

MultiPatch read_gismo_xml(const std::string& path) {
  XmlFile f(path);
  const FileLayout l = read_layout(f, path);
  const pugi::xml_node mp = l.multipatch;
  if (mp && mp.attribute("parDim") && mp.attribute("parDim").as_int() != 2)
    f.fail(mp, std::string("MultiPatch parDim must be 2 (planar patches), got ") + mp.attribute("parDim").value());
  const std::vector<long>& ids = l.ids;
  MultiPatch d;
  long total = 0;
  for (long id : ids) {
    const pugi::xml_node g = l.geometry.at(id);
    const std::string type = g.attribute("type").value();
    if (is_volume_type(g))
      f.fail(g, "Geometry id " + std::to_string(id) + " is a volume (" + type + ") where planar patches are read");
    if (type != "TensorBSpline2" && type != "TensorNurbs2")
      f.fail(g, "Geometry id " + std::to_string(id) + " has type \"" + type +
                    "\": knotwork reads TensorBSpline2 and TensorNurbs2 patches (TensorBSpline3 and TensorNurbs3 volumes)");
    d.patches.push_back(read_patch(f, g, "Geometry id " + std::to_string(id)));
    total += d.patches.back().control_points.rows();
    if (total > kMaxControlPoints) f.fail(g, "more than 2^24 control points in all");
    d.patch_labels.push_back(std::to_string(id));
    d.patch_where.push_back(f.at(g));
  }
  if (!mp) return d;

  const PatchReferences refs = read_references(f, l, 8, "interfaces: each row must have 8 integers (patch side patch side, 2 of the "
                                                        "direction map, 2 orientation flags)", "side");
  const auto& interface_lists = refs.interfaces;
  auto resolve = [&](const pugi::xml_node& node, long patch, long side) { return refs.resolve(f, node, patch, side, 4, "sides are 1 to 4"); };
  for (const auto& [in, v] : interface_lists)
    for (size_t k = 0; k < v.size(); k += 8) {
      PatchInterface i;
      i.a = resolve(in, v[k], v[k + 1]);
      i.b = resolve(in, v[k + 2], v[k + 3]);
      const std::string row = "interface " + std::to_string(k / 8 + 1);
      i.where = f.at(in) + ": " + row;
      // The tangential direction of each side (v on sides 1 and 2, u on 3 and 4) must map to
      // the other's; its orientation flag says whether they run the same way.
      const int ta = i.a.side <= 2 ? 1 : 0, tb = i.b.side <= 2 ? 1 : 0;
      if (v[k + 4 + ta] != tb)
        f.fail(in, row + ": the direction map takes the side's direction " + std::to_string(ta) + " to " +
                       std::to_string(v[k + 4 + ta]) + ", not to the other side's direction " + std::to_string(tb));
      const long o = v[k + 6 + ta];
      if (o != 0 && o != 1) f.fail(in, row + ": orientation flags must be 0 or 1, got " + std::to_string(o));
      i.reversed = o == 0;
      d.interfaces.push_back(i);
    }
  d.boundaries = refs.named_boundaries(f, 4, "sides are 1 to 4");
  return d;
}

int gismo_xml_dimension(const std::string& path) {
  XmlFile f(path);
  const FileLayout l = read_layout(f, path);
  if (l.multipatch && l.multipatch.attribute("parDim")) return l.multipatch.attribute("parDim").as_int() == 3 ? 3 : 2;
  for (long id : l.ids)
    if (is_volume_type(l.geometry.at(id))) return 3;
  return 2;
}

namespace {

// A MultiPatch of several volumes: every TensorBSpline3/TensorNurbs3, the <interfaces> rows of
// 10 integers (patch face patch face, the direction map d0 d1 d2: direction k of the first
// volume is direction d_k of the second, and the orientation flags o0 o1 o2: 1 when direction
// k runs the same way on both), and the <boundary> lists of "patch face" pairs. Patches are
// referred to by id, or by position when not every reference is an id.
VolumeFile read_gismo_volumes(const XmlFile& f, const FileLayout& l) {
  VolumeFile v;
  MultiVolume& d = v.domain;
  long total = 0;
  for (long id : l.ids) {
    const pugi::xml_node g = l.geometry.at(id);
    NurbsVolume volume = read_volume_patch(f, g, id);
    total += volume.control_points.rows();
    if (total > kMaxControlPoints) f.fail(g, "more than 2^24 control points in all");
    d.patches.push_back(std::move(volume));
    d.patch_labels.push_back(std::to_string(id));
    d.patch_where.push_back(f.at(g));
  }
  const PatchReferences refs = read_references(f, l, 10, "interfaces: each row of a volume's must have 10 integers (patch face "
                                                         "patch face, 3 of the direction map, 3 orientation flags)", "face");
  const auto& interface_lists = refs.interfaces;
  const auto resolve = [&](const pugi::xml_node& node, long patch, long face) {
    return refs.resolve(f, node, patch, face, 6, "a volume's sides are 1 to 6");
  };
  for (const auto& [in, list] : interface_lists)
    for (size_t k = 0; k < list.size(); k += 10) {
      VolumeInterface i;
      i.a = resolve(in, list[k], list[k + 1]);
      i.b = resolve(in, list[k + 2], list[k + 3]);
      const std::string row = "interface " + std::to_string(k / 10 + 1);
      i.where = f.at(in) + ": " + row;
      const long* map = &list[k + 4];
      const long* orientation = &list[k + 7];
      for (int x = 0; x < 3; ++x) {
        if (map[x] < 0 || map[x] > 2) f.fail(in, row + ": a direction map's entries are 0, 1 or 2, got " + std::to_string(map[x]));
        if (orientation[x] != 0 && orientation[x] != 1)
          f.fail(in, row + ": orientation flags must be 0 or 1, got " + std::to_string(orientation[x]));
      }
      // The faces' free directions, in the order u, v, w; the map must take a's to b's.
      const int na = (i.a.side - 1) / 2, nb = (i.b.side - 1) / 2;
      const int a1 = na == 0 ? 1 : 0, a2 = na == 2 ? 1 : 2, b1 = nb == 0 ? 1 : 0, b2 = nb == 2 ? 1 : 2;
      if (map[na] != nb)
        f.fail(in, row + ": the direction map takes the normal direction " + std::to_string(na) + " of the first face to " +
                       std::to_string(map[na]) + ", not to the normal " + std::to_string(nb) + " of the second");
      if (!((map[a1] == b1 && map[a2] == b2) || (map[a1] == b2 && map[a2] == b1)))
        f.fail(in, row + ": the direction map does not take the first face's directions to the second's");
      i.same_order = map[a1] == b1;
      i.reverse_first = orientation[a1] == 0;
      i.reverse_second = orientation[a2] == 0;
      d.interfaces.push_back(i);
    }
  d.boundaries = refs.named_boundaries(f, 6, "a volume's sides are 1 to 6");
  v.volume = d.patches.front();
  v.where = d.patch_where.front();
  return v;
}

}  // namespace

VolumeFile read_gismo_volume(const std::string& path) {
  XmlFile f(path);
  const FileLayout l = read_layout(f, path);
  const pugi::xml_node mp = l.multipatch;
  if (mp && mp.attribute("parDim") && mp.attribute("parDim").as_int() != 3)
    f.fail(mp, std::string("MultiPatch parDim must be 3 (a volume), got ") + mp.attribute("parDim").value());
  if (l.ids.size() > 1) return read_gismo_volumes(f, l);
  const long id = l.ids.front();
  const pugi::xml_node g = l.geometry.at(id);
  VolumeFile v;
  v.volume = read_volume_patch(f, g, id);
  v.label = std::to_string(id);
  v.where = f.at(g);
  if (!mp) return v;
  if (pugi::xml_node in = mp.child("interfaces"); in && !f.integers(in, "interfaces").empty())
    f.fail(in, "interfaces on a volume of one patch");
  for (pugi::xml_node b : mp.children("boundary")) {
    const std::vector<long> pairs = f.integers(b, "boundary");
    if (pairs.size() % 2 != 0) f.fail(b, "boundary: expected \"patch side\" pairs, found an odd number of integers");
    NamedBoundary nb;
    nb.name = b.attribute("name").value();
    nb.where = f.at(b);
    for (size_t k = 0; k < pairs.size(); k += 2) {
      // The patch by its id, or by its position 0 (both occur in the wild).
      if (pairs[k] != id && pairs[k] != 0)
        f.fail(b, "patch " + std::to_string(pairs[k]) + " is neither the patch id " + std::to_string(id) + " nor its position 0");
      if (pairs[k + 1] < 1 || pairs[k + 1] > 6)
        f.fail(b, "side " + std::to_string(pairs[k + 1]) + " does not exist (a volume's sides are 1 to 6)");
      nb.sides.push_back({0, static_cast<int>(pairs[k + 1])});
    }
    if (nb.name.empty()) continue;  // an unnamed list only says which sides are boundary
    for (const NamedBoundary& other : v.boundaries)
      if (other.name == nb.name) f.fail(b, "boundary \"" + nb.name + "\" is given twice");
    v.boundaries.push_back(std::move(nb));
  }
  return v;
}

namespace {
std::string escaped(const std::string& text) {
  std::string out;
  for (char ch : text) {
    switch (ch) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += ch;
    }
  }
  return out;
}
}  // namespace

void write_gismo_xml(const MultiPatch& d, const std::string& path) {
  std::ostringstream s;
  s.precision(17);
  s << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- written by knotwork -->\n<xml>\n";
  for (int p = 0; p < d.num_patches(); ++p) {
    const NurbsPatch& patch = d.patches[p];
    const bool rational = (patch.weights.array() != 1.0).any();
    s << " <Geometry type=\"" << (rational ? "TensorNurbs2" : "TensorBSpline2") << "\" id=\"" << p << "\">\n";
    if (rational) s << "  <Basis type=\"TensorNurbsBasis2\">\n";
    s << "  <Basis type=\"TensorBSplineBasis2\">\n";
    for (int k = 0; k < 2; ++k) {
      const BSplineBasis1D& b = k == 0 ? patch.basis_u : patch.basis_v;
      s << "   <Basis type=\"BSplineBasis\" index=\"" << k << "\">\n    <KnotVector degree=\"" << b.degree() << "\">";
      for (size_t i = 0; i < b.knots().size(); ++i) s << (i ? " " : "") << b.knots()[i];
      s << "</KnotVector>\n   </Basis>\n";
    }
    s << "  </Basis>\n";
    if (rational) {
      s << "  <weights>";
      for (Eigen::Index i = 0; i < patch.weights.size(); ++i) s << (i ? " " : "") << patch.weights[i];
      s << "</weights>\n  </Basis>\n";
    }
    s << "  <coefs geoDim=\"2\">\n";
    for (Eigen::Index i = 0; i < patch.control_points.rows(); ++i)
      s << patch.control_points(i, 0) << " " << patch.control_points(i, 1) << "\n";
    s << "  </coefs>\n </Geometry>\n";
  }
  s << " <MultiPatch parDim=\"2\" id=\"" << d.num_patches() << "\">\n  <patches type=\"id_range\">0 "
    << d.num_patches() - 1 << "</patches>\n";
  if (!d.interfaces.empty()) {
    s << "  <interfaces>\n";
    for (const PatchInterface& i : d.interfaces) {
      const int ta = i.a.side <= 2 ? 1 : 0, tb = i.b.side <= 2 ? 1 : 0;
      int map[2], orient[2];
      map[ta] = tb, map[1 - ta] = 1 - tb;
      orient[ta] = i.reversed ? 0 : 1, orient[1 - ta] = 1;
      s << "   " << i.a.patch << " " << i.a.side << " " << i.b.patch << " " << i.b.side << " " << map[0] << " " << map[1]
        << " " << orient[0] << " " << orient[1] << "\n";
    }
    s << "  </interfaces>\n";
  }
  std::vector<PatchSideRef> named;
  for (const NamedBoundary& b : d.boundaries) {
    s << "  <boundary name=\"" << escaped(b.name) << "\">\n";
    for (const PatchSideRef& r : b.sides) s << "   " << r.patch << " " << r.side << "\n", named.push_back(r);
    s << "  </boundary>\n";
  }
  std::ostringstream rest;
  for (const PatchSideRef& r : exterior_sides(d))
    if (std::find(named.begin(), named.end(), r) == named.end()) rest << "   " << r.patch << " " << r.side << "\n";
  if (!rest.str().empty()) s << "  <boundary>\n" << rest.str() << "  </boundary>\n";
  s << " </MultiPatch>\n</xml>\n";
  write_file_atomically(path, "G+Smo XML geometry", [&](const std::string& staged) { write_text_file(staged, s.str()); });
}

}  // namespace knotwork
