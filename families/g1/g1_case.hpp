#pragma once
// A case of family "g1": the G1 macro-patch space on a quad mesh; the geometry is the G1
// spline fitted to the mesh ([geometry] shape) and the problem is planar Poisson or
// Laplace-Beltrami on a closed surface ([problem] operator). See cases/README.md.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "cases/case_file.hpp"

namespace knotwork {

struct CaseDocument;
class QuadMesh;

// The split smoothness of a case that does not name one: k - 2, at least 1.
constexpr int default_split_smoothness(int degree) { return degree > 3 ? degree - 2 : 1; }

struct G1Section : CaseSection {
  std::string mesh_file;  // resolved against the case file's folder ([space] mesh or [geometry] file)
  // The coarse quad mesh made from a geometry file of bilinear patches, as read and checked
  // with the case; empty for an OBJ mesh (read again from mesh_file).
  std::shared_ptr<const QuadMesh> coarse;
  int faces = 0;          // of the coarse mesh (read and checked with the case)
  // Defaults chosen by measurement (docs/G1_POISSON.md, "The default is k = 5"): k = 5 with
  // r = k - 2 has the same unknowns per face as the paper's k = 4, r = 1 (2k - r + 1 = 8), the
  // same dofs on every mesh, and 9.6-99x smaller H1 errors at the fourth level. The shipped
  // cases keep the paper's k = 4, r = 1 by name.
  int degree = 5, split_smoothness = default_split_smoothness(5);
  bool split_smoothness_given = false;  // else it follows the degree, also under --degree
  std::string gluing = "analysis_suitable";  // a construction (gluing_file.hpp) or a JSON file (resolved)
  int refine = 0;                    // subdivisions before solving (converge adds one per level)
  bool c0 = false;                   // [space] smoothness = "c0": the plain C0 multipatch baseline
  std::string shape = "bilinear";    // "bilinear" | "sphere" | "torus"
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 1, major_radius = 2, minor_radius = 1;  // sphere; torus around the z axis
  bool surface = false;  // operator = "laplace_beltrami" (problem: -Laplace_Beltrami(u) + reaction u = f)
  std::unique_ptr<CaseSection> clone() const override { return std::make_unique<G1Section>(*this); }
};

inline G1Section& g1_section(CaseDescription& c) { return family_section<G1Section>(c); }
inline const G1Section& g1_section(const CaseDescription& c) { return family_section<G1Section>(c); }

// The keys [space] takes.
const std::vector<std::string>& g1_space_keys();

void read_g1_case(const CaseDocument& doc, CaseDescription& c);

}  // namespace knotwork
