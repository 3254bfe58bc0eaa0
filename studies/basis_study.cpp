// The basis study of a case's space: the family's checks, partition of unity and rank.
#include "basis/core/bezier_mesh_checks.hpp"
#include "cases/json_output.hpp"
#include "studies/report.hpp"
#include "studies/studies.hpp"

namespace knotwork {

Json basis_json(const CaseDescription& c, const SplineSpace& space) {
  const BezierMesh& mesh = space.mesh();
  const long rank = bezier_rank(mesh);
  Json j = Json::object();
  j.set("file", c.path).set("family", c.family).set("space", space.presentation().description())
      .set("functions", mesh.num_functions()).set("cells", mesh.num_cells());
  add_fields(j, space.presentation().basis_report());
  j.set("partition_of_unity_error", partition_of_unity_error(mesh));
  if (rank >= 0) j.set("rank", rank); else j.set_null("rank");
  j.set("notes", Json::strings(space.presentation().notes()));
  return j;
}

}  // namespace knotwork
