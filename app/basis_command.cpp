// `knotwork basis`: a case file's space through the family interface (partition of unity,
// rank and the family's own checks), or a family's own mode (cases/basis_tool.hpp).
#include <cstdio>

#include "app/commands.hpp"
#include "studies/pipeline.hpp"
#include "studies/report.hpp"
#include "studies/studies.hpp"
#include "basis/core/bezier_mesh_checks.hpp"
#include "cases/json_output.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// A case file: its space through the family interface; the family adds its own checks.
int basis_of_case(const BasisRequest& o) {
  const CaseDescription c = load_case(o.file);
  const std::unique_ptr<SplineSpace> space = build_space(c);
  const BezierMesh& mesh = space->mesh();
  if (!o.export_file.empty()) space->presentation().export_functions(o.export_file, c.path);
  if (o.json) {
    std::printf("%s\n", basis_json(c, *space).dump().c_str());
    return 0;
  }
  const std::vector<ReportField> fields = space->presentation().basis_report();
  const double pu = partition_of_unity_error(mesh);
  const long rank = bezier_rank(mesh);
  std::printf("knotwork basis %s\n  space      %s\n  functions  %d on %d cells\n", c.path.c_str(),
              space->presentation().description().c_str(), mesh.num_functions(), mesh.num_cells());
  for (const auto& n : space->presentation().notes()) std::printf("  note       %s\n", n.c_str());
  print_field_lines(fields, 10);
  std::printf("  partition of unity  max error %.3e\n", pu);
  if (rank >= 0) std::printf("  rank       %ld (%s)\n", rank, rank == mesh.num_functions() ? "linearly independent" : "DEPENDENT");
  else std::printf("  rank       not computed (too large for the dense rank check)\n");
  if (!o.export_file.empty()) std::printf("  output     %s\n", o.export_file.c_str());
  return 0;
}

}  // namespace

int basis_command(const BasisRequest& request, const std::vector<std::unique_ptr<BasisTool>>& tools) {
  const BasisTool* chosen = nullptr;
  for (const auto& t : tools)
    if (t->requested()) {
      if (chosen) throw InputError("basis: " + chosen->selector() + " and " + t->selector() + " are different tools; give one");
      chosen = t.get();
    }
  if (!chosen) {
    std::string inputs = "a case file";
    for (const auto& t : tools) inputs += ", " + t->selector();
    if (request.file.empty()) throw InputError("basis: give one input: " + inputs);
    // A G+Smo problem file is a case (load_case reads it); the tools' files are TOML or JSON.
    const bool xml = request.file.size() > 4 && request.file.compare(request.file.size() - 4, 4, ".xml") == 0;
    for (const auto& t : tools)
      if (!xml && t->claims(request.file)) { chosen = t.get(); break; }
  }
  for (const auto& t : tools)
    if (t.get() != chosen) t->refuse_unused_options();
  if (chosen) return chosen->run(request);
  if (!request.vtk_file.empty()) throw InputError("--vtk: not written for a case file's space (run the case for ParaView output)");
  if (!request.show.empty()) throw InputError("--show: only with --vtk");
  return basis_of_case(request);
}

}  // namespace knotwork
