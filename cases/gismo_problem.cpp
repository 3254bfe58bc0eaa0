// Reading a G+Smo problem file into a knotwork case (see gismo_problem.hpp). Written here:
// the layout is G+Smo's convention (its readers in gsPde/gsBoundaryConditions and its pde/
// examples), which no library reads; pugixml parses the XML.
#include "cases/gismo_problem.hpp"

#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "basis/core/multipatch.hpp"
#include "cases/xml_file.hpp"
#include "solver/expression.hpp"

namespace knotwork {

namespace {

std::string quoted(const std::string& s) {  // a TOML basic string
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') out += '\\';
    if (ch == '\n' || ch == '\r' || ch == '\t') ch = ' ';
    out += ch;
  }
  return out + "\"";
}

std::string trimmed(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

pugi::xml_node with_id(const pugi::xml_node& root, const char* element, int id) {
  for (pugi::xml_node n : root.children(element))
    if (std::string(n.attribute("id").value()) == std::to_string(id))
      return n;
  return {};
}

// A <Function type="FunctionExpr">: its expression(s), checked. One component, or with c="2"
// two <c index="0|1"> children.
std::vector<std::string> function_expressions(const XmlFile& f, const pugi::xml_node& n, const std::string& what) {
  const std::string type = n.attribute("type").value();
  if (type != "FunctionExpr") f.fail(n, what + ": type=\"" + type + "\" is not read (FunctionExpr is)");
  std::vector<std::string> out;
  const long c = n.attribute("c") ? f.integer_attribute(n, "c", what) : 1;
  if (c == 1 && !n.child("c")) {
    out.push_back(trimmed(n.child_value()));
  } else {
    if (c != 2) f.fail(n, what + ": c=\"" + std::to_string(c) + "\": a function of 1 or 2 components is read here");
    out.resize(2);
    std::set<long> seen;
    for (pugi::xml_node k : n.children("c")) {
      const long i = f.integer_attribute(k, "index", what + " <c>");
      if (i < 0 || i > 1 || !seen.insert(i).second) f.fail(k, what + ": <c index=\"" + std::to_string(i) + "\"> is not 0 or 1, or is given twice");
      out[i] = trimmed(k.child_value());
    }
    if (seen.size() != 2) f.fail(n, what + ": two components <c index=\"0\"> and <c index=\"1\"> are needed");
  }
  for (const std::string& e : out) {
    if (e.empty()) f.fail(n, what + ": the expression is empty");
    Expression::parse(e, f.at(n) + ": " + what);  // throws InputError naming the line
  }
  return out;
}

}  // namespace

std::string gismo_problem_as_case(const std::string& path) {
  const XmlFile f(path);
  const pugi::xml_node root = f.doc().child("xml");
  if (!root) throw InputError(path + ": the root element must be <xml> (a G+Smo file)");
  const pugi::xml_node source = with_id(root, "Function", 1);
  const pugi::xml_node conditions = root.child("boundaryConditions");
  if (!source || !conditions)
    throw InputError(path + ": not a G+Smo problem file (it needs the source <Function id=\"1\"> and <boundaryConditions>); "
                            "a geometry alone is named in a case's [geometry] file");
  const MultiPatch domain = read_geometry_file(path);
  std::set<std::string> labels;
  for (const NamedBoundary& b : domain.boundaries) labels.insert(b.name);

  const std::vector<std::string> f_expr = function_expressions(f, source, "the source <Function id=\"1\">");
  if (f_expr.size() != 1) f.fail(source, "the source <Function id=\"1\"> must have one component");
  std::optional<std::string> exact;
  if (const pugi::xml_node e = with_id(root, "Function", 3)) {
    const auto u = function_expressions(f, e, "the exact solution <Function id=\"3\">");
    if (u.size() != 1) f.fail(e, "the exact solution <Function id=\"3\"> must have one component");
    exact = u[0];
  }
  if (const pugi::xml_node o = with_id(root, "OptionList", 4)) {
    // knotwork integrates with degree + 1 Gauss points per direction: G+Smo's quA = 1, quB = 1.
    for (pugi::xml_node k : o.children()) {
      const std::string label = k.attribute("label").value();
      if ((label == "quA" || label == "quB") && k.attribute("value").as_double(-1) != 1)
        f.fail(k, "<OptionList id=\"4\">: " + label + " = " + k.attribute("value").value() +
                      ": knotwork's rule has degree + 1 points (quA = 1, quB = 1); write a case file with [space] "
                      "quadrature_points for another");
      if (label == "quRule" && k.attribute("value").as_int(-1) != 1)
        f.fail(k, "<OptionList id=\"4\">: quRule = " + std::string(k.attribute("value").value()) +
                      ": knotwork integrates with Gauss-Legendre rules (quRule = 1)");
    }
  }

  // The boundary conditions' functions, by index.
  std::map<long, std::pair<pugi::xml_node, std::vector<std::string>>> functions;
  for (pugi::xml_node n : conditions.children("Function")) {
    const long k = f.integer_attribute(n, "index", "<boundaryConditions> <Function>");
    if (functions.count(k)) f.fail(n, "<boundaryConditions>: a second <Function index=\"" + std::to_string(k) + "\">");
    functions[k] = {n, function_expressions(f, n, "<boundaryConditions> <Function index=\"" + std::to_string(k) + "\">")};
  }
  for (pugi::xml_node n : conditions.children())
    if (std::string(n.name()) != "Function" && std::string(n.name()) != "bc")
      f.fail(n, "<boundaryConditions>: <" + std::string(n.name()) + "> is not read (a Poisson problem has <bc> with "
                                                                    "type Dirichlet or Neumann)");

  // Each side (by "P:S" or the file's label) and its datum; sides named twice are refused.
  std::vector<std::pair<std::string, std::string>> dirichlet, neumann;
  std::set<std::pair<int, int>> sides_used;  // (patch, side) through "patch side" lists
  for (pugi::xml_node bc : conditions.children("bc")) {
    std::string type = bc.attribute("type").value();
    for (char& ch : type) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (type != "dirichlet" && type != "neumann")
      f.fail(bc, "<bc type=\"" + std::string(bc.attribute("type").value()) + "\">: a Poisson problem here has Dirichlet or "
                                                                             "Neumann conditions");
    if (bc.attribute("unknown") && f.integer_attribute(bc, "unknown", "<bc>") != 0)
      f.fail(bc, "<bc>: unknown=\"" + std::string(bc.attribute("unknown").value()) + "\": the Poisson problem has one unknown, 0");
    if (bc.attribute("component") && f.integer_attribute(bc, "component", "<bc>") != -1)
      f.fail(bc, "<bc>: component=\"" + std::string(bc.attribute("component").value()) + "\": a scalar problem has none (-1)");
    const long k = f.integer_attribute(bc, "function", "<bc>");
    if (!functions.count(k)) f.fail(bc, "<bc function=\"" + std::to_string(k) + "\">: no <Function index=\"" + std::to_string(k) + "\"> in <boundaryConditions>");
    const std::vector<std::string>& data = functions[k].second;
    if (type == "dirichlet" && data.size() != 1)
      f.fail(bc, "<bc type=\"Dirichlet\" function=\"" + std::to_string(k) + "\">: Dirichlet data have one component");
    const std::string value = data.size() == 1 ? quoted(data[0]) : "[" + quoted(data[0]) + ", " + quoted(data[1]) + "]";
    std::vector<std::string> sides;
    if (const pugi::xml_attribute name = bc.attribute("name")) {
      if (!labels.count(name.value()))
        f.fail(bc, "<bc name=\"" + std::string(name.value()) + "\">: no <boundary name=\"" + name.value() + "\"> in the <MultiPatch>");
      sides.push_back(name.value());
      for (const NamedBoundary& b : domain.boundaries)
        if (b.name == name.value())
          for (const PatchSideRef& s : b.sides)
            if (!sides_used.insert({s.patch, s.side}).second) f.fail(bc, "<bc>: side " + side_name(domain, s) + " has two conditions");
    } else {
      const std::vector<long> pairs = f.integers(bc, "<bc>");
      if (pairs.empty() || pairs.size() % 2) f.fail(bc, "<bc>: the sides are \"patch side\" pairs (patches by position from 0)");
      for (size_t i = 0; i < pairs.size(); i += 2) {
        const long p = pairs[i], s = pairs[i + 1];
        if (p < 0 || p >= domain.num_patches() || s < 1 || s > 4)
          f.fail(bc, "<bc>: (" + std::to_string(p) + ", " + std::to_string(s) + ") is not a side: patches are 0.." +
                         std::to_string(domain.num_patches() - 1) + " by position, sides 1..4");
        const PatchSideRef ref{static_cast<int>(p), static_cast<int>(s)};
        for (const PatchInterface& x : domain.interfaces)
          if (x.a == ref || x.b == ref) f.fail(bc, "<bc>: side " + side_name(domain, ref) + " is an interface, not a boundary side");
        if (!sides_used.insert({ref.patch, ref.side}).second) f.fail(bc, "<bc>: side " + side_name(domain, ref) + " has two conditions");
        sides.push_back(side_name(domain, ref));
      }
    }
    for (const std::string& s : sides) {
      (type == "dirichlet" ? dirichlet : neumann).push_back({s, value});
    }
  }
  if (dirichlet.empty())
    f.fail(conditions, "<boundaryConditions>: no Dirichlet side: the solution would only be defined up to a constant");
  // Sides no <bc> names: G+Smo's natural condition, a zero flux.
  for (const PatchSideRef& s : exterior_sides(domain))
    if (!sides_used.count({s.patch, s.side})) neumann.push_back({side_name(domain, s), "\"0\""});

  int degree = 1;
  for (const NurbsPatch& p : domain.patches) degree = std::max({degree, p.basis_u.degree(), p.basis_v.degree()});
  std::ostringstream t;
  t << "title = " << quoted("G+Smo problem " + std::filesystem::path(path).filename().string()) << "\n"
    << "[geometry]\nfile = " << quoted(std::filesystem::path(path).filename().string()) << "\n"
    << "[space]\ndegree = " << degree << "\nelements = 32\nrational = false\nboundary_quadrature_points = \"interior\"\n"
    << "[problem]\nsource = " << quoted(f_expr[0]) << "\n";
  if (exact) t << "exact = " << quoted(*exact) << "\n";
  t << "[problem.dirichlet]\n";
  for (const auto& [s, v] : dirichlet) t << quoted(s) << " = " << v << "\n";
  if (!neumann.empty()) {
    t << "[problem.neumann]\n";
    for (const auto& [s, v] : neumann) t << quoted(s) << " = " << v << "\n";
  }
  return t.str();
}

}  // namespace knotwork
