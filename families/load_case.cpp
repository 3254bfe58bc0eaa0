// load_case: the top level of a case file and the sections every family shares; the family
// named by [space] family (default "tensor") reads the rest through its own reader.
#include <filesystem>

#include "cases/case_reader.hpp"
#include "cases/gismo_problem.hpp"
#include "cases/spline_space.hpp"
#include "solver/amg_preconditioner.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

CaseDescription read_case(const DocumentNode& root, const std::string& path) {
  CaseReader r(path);
  r.check_keys(root, "", {"title", "description", "geometry", "space", "problem", "output", "adapt", "solver"});
  CaseDescription c;
  c.path = path;
  c.name = std::filesystem::path(path).stem().string();
  c.output_directory = "results/" + c.name;
  if (const DocumentNode* t = root.get("title")) c.title = r.string(*t, "title");
  if (const DocumentNode* t = root.get("description")) r.string(*t, "description");
  const DocumentNode& space = r.table(root, "space", true);
  if (const DocumentNode* f = space.get("family")) c.family = r.string(*f, "[space] family");
  std::vector<std::string> names;
  const SpaceFamily* family = nullptr;
  for (const SpaceFamily& f : space_families()) {
    names.push_back(f.name);
    if (f.name == c.family) family = &f;
  }
  if (!family) {
    std::string all;
    for (const auto& n : names) all += (all.empty() ? "\"" : ", \"") + n + "\"";
    r.fail("[space] family", "'" + c.family + "' is not a registered family (" + closest_name(c.family, names) +
                                 "; this version builds " + all + ")");
  }
  std::vector<std::pair<std::string, std::vector<std::string>>> others;
  for (const SpaceFamily& f : space_families())
    if (&f != family) others.emplace_back(f.name, f.space_keys);
  r.set_other_families_keys(c.family, std::move(others));
  family->read_case(CaseDocument{r, root}, c);
  read_output(r, r.table(root, "output", false), c);
  read_solver(r, r.table(root, "solver", false), c);
  checked_name(c.solver.preconditioner, preconditioner_names(), "[solver] preconditioner", path);
  check_petsc_options(c, "[solver] petsc_options");
  if (root.get("adapt")) {
    if (!family->local_refinement)
      r.fail("[adapt]", "not used with family = \"" + c.family + "\" (it does not refine cells locally; `knotwork adapt` "
                        "needs a family that does)");
    read_adapt(r, r.table(root, "adapt", false), c);
  }
  return c;
}

}  // namespace

CaseDescription load_case(const std::string& path) {
  // A quad mesh handed to run/converge would otherwise be blamed for TOML syntax.
  if (std::filesystem::path(path).extension() == ".obj")
    throw InputError(path + ": a quad mesh (OBJ), not a case file: a case names it in its [space] mesh "
                            "(cases/README.md), and `knotwork basis --help` says how to check it");
  // A G+Smo problem file is read as the case it describes (cases/gismo_problem.hpp).
  if (std::filesystem::path(path).extension() == ".xml") return read_case(parse_document_text(gismo_problem_as_case(path), path), path);
  return read_case(parse_document(path), path);
}

CaseDescription load_case_document(const DocumentNode& root, const std::string& name) { return read_case(root, name); }

CaseDescription load_case_text(const std::string& toml_text, const std::string& name) {
  return read_case(parse_document_text(toml_text, name), name);
}

}  // namespace knotwork
