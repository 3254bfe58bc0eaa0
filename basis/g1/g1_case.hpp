#pragma once
// A case of family "g1": the G1 macro-patch space on a quad mesh; the geometry is the G1
// spline fitted to the mesh ([geometry] shape) and the problem is planar Poisson or
// Laplace-Beltrami on a closed surface ([problem] operator). See cases/README.md.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "cases/case_file.hpp"

namespace knotwork {

struct CaseDocument;

struct G1Section : CaseSection {
  std::string mesh_file;  // resolved against the case file's folder
  int faces = 0;          // of the coarse mesh (read and checked with the case)
  // Defaults chosen by measurement (docs/G1_POISSON.md, "Against a peer's C1 space"): k = 5 with
  // r = k - 2 has the same unknowns per face as the paper's k = 4, r = 1 (2k - r + 1 = 8), the
  // same dofs on every mesh, and is 10-100x more accurate in H1 at the fourth level. The shipped
  // cases keep the paper's k = 4, r = 1 by name. 0: k - 2, at least 1.
  int degree = 5, split_smoothness = 0;
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
