#pragma once
// The share of a mesh one process works on, shared by the spaces that build themselves in parts
// and the distributed solver (types of the bottom layer: docs/ARCHITECTURE.md).

#include <vector>

namespace knotwork {

// The cells [first, last) of a mesh (last < 0: to the end): one rank's share of a distributed
// assembly (contiguous blocks of the cell order, as PetIGA partitions a tensor mesh).
struct CellRange {
  int first = 0, last = -1;
};

// One rank's part of a space its family built distributed (under mpirun, method = "petsc"):
// a BezierMesh of the cells this rank needs, with its own function numbers (global number =
// global(local)). The rank integrates and writes the cells `owned` and owns the
// matrix rows of the global functions [first_owned_function, last_owned_function); every cell
// on which one of those lives is in the mesh (the others are the halo its rows need). The
// owned cells of all ranks tile the global mesh, the owned functions of all ranks tile
// [0, global_functions).
struct MeshPart {
  CellRange owned;
  int function_offset = 0;
  // Or, when not empty, each local function's global number (increasing): a part whose
  // functions are not one run of the global numbering (a multipatch space's).
  std::vector<int> global_function;
  int global(int local) const { return global_function.empty() ? local + function_offset : global_function[local]; }
  int first_owned_function = 0, last_owned_function = 0;
  int global_functions = 0, global_cells = 0;
};

}  // namespace knotwork
