#pragma once
// G+Smo problem files: `knotwork run problem.xml`. A problem file holds, as G+Smo's pde/
// examples lay it out, the domain (<MultiPatch> and its <Geometry> patches), the source
// (<Function id="1">), the boundary conditions (<boundaryConditions id="2">: its own
// <Function index="k"> list and <bc type="Dirichlet|Neumann" function="k"> over named
// boundaries or "patch side" pairs, patches by position from 0), the exact solution
// (<Function id="3">, optional) and assembler options (<OptionList id="4">: quA, quB).
#include <string>

namespace knotwork {

// The file as the TOML case knotwork reads (load_case reads an .xml case through this):
// [geometry] file is the file itself; [space] the tensor family at the patches' highest
// degree, B-splines (G+Smo's examples build polynomial bases), 32 elements per knot span (their
// 5 uniform refinements), the boundary rule as the interior one; [problem] the source, the
// exact solution, one Dirichlet or Neumann datum per side, and homogeneous Neumann on sides
// no <bc> names (G+Smo's natural condition). A Neumann function of two components is the
// flux vector (data F.n), of one the flux. Throws InputError naming the file and line.
std::string gismo_problem_as_case(const std::string& path);

}  // namespace knotwork
