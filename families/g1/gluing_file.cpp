#include "families/g1/gluing_file.hpp"

#include <stdexcept>
#include <string>

#include "basis/tmesh/rectangular_partition.hpp"
#include "cases/json_input.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

using K = JsonValue::Kind;

mpq_class exact_number(const JsonValue& v, const std::string& where) {
  try {
    if (v.kind == K::kNumber || v.kind == K::kString) return parse_rational(v.text);
  } catch (const std::invalid_argument& e) {
    throw InputError(where + ": " + e.what());
  }
  throw InputError(where + ": must be a number or a rational string such as \"-1/3\"");
}

std::vector<mpq_class> coefficient_list(const JsonValue& v, const std::string& where) {
  if (v.items.empty()) throw InputError(where + ": an empty list of coefficients");
  std::vector<mpq_class> out;
  for (size_t i = 0; i < v.items.size(); ++i) out.push_back(exact_number(v.items[i], where + "[" + std::to_string(i) + "]"));
  return out;
}

PiecewisePolynomial function_of(const JsonValue& v, const std::string& where) {
  if (v.kind != K::kArray) {
    const mpq_class c = exact_number(v, where);
    return PiecewisePolynomial::constant(c);
  }
  if (!v.items.empty() && v.items[0].kind == K::kArray) {
    if (v.items.size() != 2 || v.items[1].kind != K::kArray)
      throw InputError(where + ": a piecewise function is a pair of coefficient lists [[...], [...]]");
    return PiecewisePolynomial::from_exact({coefficient_list(v.items[0], where + "[0]"), coefficient_list(v.items[1], where + "[1]")});
  }
  const auto c = coefficient_list(v, where);
  return PiecewisePolynomial::from_exact({c, c});
}

const JsonValue* member(const JsonValue& o, const std::string& key) {
  for (const auto& [k, v] : o.members)
    if (k == key) return &v;
  return nullptr;
}

}  // namespace

GluingData load_gluing_file(const std::string& path, const QuadMesh& mesh) {
  const JsonValue root = read_json_file(path);
  if (root.kind != K::kObject) throw InputError(path + ": the document must be an object {\"gluing\": [...]}");
  for (const auto& [k, v] : root.members)
    if (k != "gluing" && k != "description")
      throw InputError(path + ": " + k + ": unknown key (the file has \"gluing\" and optionally \"description\")");
  const JsonValue* list = member(root, "gluing");
  if (!list || list->kind != K::kArray) throw InputError(path + ": gluing: missing, give a list of {edge, a, b, c}");
  GluingData g;
  g.edges.resize(mesh.num_edges());
  for (size_t n = 0; n < list->items.size(); ++n) {
    const std::string where = path + ": gluing[" + std::to_string(n) + "]";
    const JsonValue& item = list->items[n];
    if (item.kind != K::kObject) throw InputError(where + ": must be an object {edge, a, b, c}");
    for (const auto& [k, v] : item.members)
      if (k != "edge" && k != "a" && k != "b" && k != "c")
        throw InputError(where + "." + k + ": unknown key (edge, a, b, c)");
    const JsonValue* edge = member(item, "edge");
    if (!edge || edge->kind != K::kArray || edge->items.size() != 2 || edge->items[0].kind != K::kNumber ||
        edge->items[1].kind != K::kNumber || !edge->items[0].integral || !edge->items[1].integral)
      throw InputError(where + ".edge: must be [i, j], two 1-based vertex numbers");
    // Vertex numbers as written; one beyond a long (found by fuzzing: std::stol threw) names no vertex.
    auto vertex_number = [](const std::string& text) {
      try {
        return std::stol(text);
      } catch (const std::out_of_range&) {
        return 0L;
      }
    };
    const long i = vertex_number(edge->items[0].text), j = vertex_number(edge->items[1].text);
    const int e = (i >= 1 && j >= 1 && i <= mesh.num_vertices() && j <= mesh.num_vertices())
                      ? mesh.find_edge(static_cast<int>(i - 1), static_cast<int>(j - 1))
                      : -1;
    if (e < 0)
      throw InputError(where + ".edge: [" + edge->items[0].text + ", " + edge->items[1].text + "] is not an edge of the mesh");
    if (mesh.edge(e).boundary())
      throw InputError(where + ".edge: [" + std::to_string(i) + ", " + std::to_string(j) +
                       "] is a boundary edge; gluing data belong to interior edges");
    if (g.edges[e]) throw InputError(where + ".edge: [" + std::to_string(i) + ", " + std::to_string(j) + "] is given twice");
    EdgeGluing eg;
    for (const char* key : {"a", "b", "c"}) {
      const JsonValue* v = member(item, key);
      if (!v) throw InputError(where + "." + key + ": missing");
      (key[0] == 'a' ? eg.a : key[0] == 'b' ? eg.b : eg.c) = function_of(*v, where + "." + key);
    }
    // Stored in the mesh edge's own orientation (u = 0 at its first vertex).
    g.edges[e] = mesh.edge(e).v[0] == i - 1 ? eg : reversed(eg);
  }
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (!mesh.edge(e).boundary() && !g.edges[e])
      throw InputError(path + ": gluing: no data for the interior edge [" + std::to_string(mesh.edge(e).v[0] + 1) + ", " +
                       std::to_string(mesh.edge(e).v[1] + 1) + "]");
  return g;
}

bool is_named_gluing(const std::string& name) {
  return name == "analysis_suitable" || name == "symmetric" || name == "symmetric_c1" || name == "geometric" ||
         name == "regular_fans";
}

GluingData make_gluing(const std::string& name_or_file, const QuadMesh& mesh, const std::string& mesh_name) {
  if (name_or_file == "analysis_suitable") {
    try {
      return analysis_suitable_gluing(mesh);
    } catch (const std::invalid_argument& e) {
      throw InputError(mesh_name + ": gluing \"analysis_suitable\": " + e.what());
    }
  }
  if (name_or_file == "symmetric") return symmetric_gluing(mesh);
  if (name_or_file == "symmetric_c1") return symmetric_gluing(mesh, SymmetricBlend::kC1);
  if (name_or_file == "geometric" || name_or_file == "regular_fans") {
    try {
      return geometric_gluing(mesh, name_or_file == "regular_fans");
    } catch (const std::invalid_argument& e) {
      throw InputError(mesh_name + ": gluing \"geometric\": " + e.what());
    }
  }
  return load_gluing_file(name_or_file, mesh);
}

}  // namespace knotwork
