#pragma once
#include <string>

#include "basis/g1/g1_space.hpp"
#include "basis/g1/quad_mesh.hpp"

namespace knotwork {

// Gluing data per edge from a JSON file:
//   {"gluing": [{"edge": [i, j], "a": A, "b": B, "c": C}, ...]}
// i, j: the OBJ's 1-based vertex numbers, u = 0 at i. A, B, C: a number (a constant), a
// list of coefficients in powers of u (one polynomial on [0, 1]), or a pair of such lists
// (the pieces on [0, 1/2] and [1/2, 1]); numbers may be exact rational strings ("-1/3"),
// and decimals are read exactly (0.1 = 1/10). Every interior edge needs data; naming an
// edge that is not in the mesh, a boundary edge, or one edge twice is an error.
// Throws InputError "<file>: gluing[3].edge: ..." .
GluingData load_gluing_file(const std::string& path, const QuadMesh& mesh);

// "symmetric" (eq. 11, the paper's C^0 blend), "symmetric_c1" (the same values at the
// vertices, C^1 blend), "geometric" (eq. 8 from the mesh's edge directions) and
// "regular_fans" (eq. 8 with regular fans where their cosines are rational, the mesh's
// directions elsewhere).
bool is_named_gluing(const std::string& name);
// A named construction or else a gluing file. Throws InputError "<where>: ..." (where: the
// mesh for named data, the file otherwise).
GluingData make_gluing(const std::string& name_or_file, const QuadMesh& mesh, const std::string& mesh_name);

}  // namespace knotwork
