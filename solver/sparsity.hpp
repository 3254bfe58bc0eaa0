#pragma once
#include <Eigen/SparseCore>
#include <functional>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/mesh_part.hpp"

namespace knotwork {

// Which functions are unknowns: dof[f] in [0, num_free) or -1 (fixed by Dirichlet data).
struct DofLayout {
  std::vector<int> dof;
  std::vector<int> function_of_dof;
  int num_free() const { return static_cast<int>(function_of_dof.size()); }
};
DofLayout make_dof_layout(int num_functions, const std::vector<bool>& fixed);

// The lower triangle (row >= column) of the coupling pattern of the free dofs, as a
// compressed column-major matrix with sorted row indices and zero values: the layout
// CHOLMOD reads. Built in place, in two threaded passes (count, fill).
Eigen::SparseMatrix<double> lower_pattern_matrix(const BezierMesh& mesh, const DofLayout& layout);

// A rank's owned rows of the distributed matrix as PETSc's MATMPIAIJ keeps them: the "diagonal"
// block (columns this rank owns, numbered from its first row) and the "off-diagonal" block (the
// other columns, global numbers), each CSR with ascending columns per row. `values` holds the
// diagonal block's entries, then the off-diagonal block's, then anything its owner appends.
struct OwnedRows {
  std::vector<int> diagonal_start{0}, diagonal_cols, off_start{0}, off_cols;
  std::vector<double> values;
  long diagonal_nonzeros() const { return diagonal_start.back(); }
  long off_nonzeros() const { return off_start.back(); }
};

// Where each row's diagonal entry sits in the diagonal block's arrays.
std::vector<int> diagonal_positions(const OwnedRows& rows);

// Copies the upper triangle (column > row) of the diagonal block into its lower one, the
// block's pattern being symmetric (it is a coupling pattern): entry (j, i) := entry (i, j).
// `diagonal` is diagonal_positions(rows).
void mirror_diagonal_block(OwnedRows& rows, const std::vector<int>& diagonal);

// What one rank adds to the distributed matrix (mpirun, method = "petsc"), laid out so that its
// element loop adds straight into it (assemble_poisson) and its owned rows go to PETSc as they
// are: whole rows, both triangles, not the lower triangle CHOLMOD reads, which would have to be
// transposed and cut into PETSc's blocks after assembly.
// - Owned rows: the free dofs [first, last) of the rank's layout, whose global rows are
//   [first_row, last_row); their pattern comes from every cell of the rank's mesh (entries the
//   other ranks' cells add arrive through PETSc).
// - Halo rows: the other free dofs the rank's own cells touch, with only those cells'
//   entries (columns as the layout's dofs); they are sent to their owners.
// owned.values ends with the halo's entries, so that one array holds everything the loop adds.
struct RankRows {
  int first = 0, last = 0;
  std::vector<int> global_row;  // of every free dof of the layout, increasing
  OwnedRows owned;
  std::vector<int> halo_start, halo_cols;  // CSR over all free dofs (owned ones: empty rows)
  long halo_offset() const { return owned.diagonal_nonzeros() + owned.off_nonzeros(); }
};

// A function's couplings as coupled(function, out) appends them (the functions that share a
// cell with it, itself included, ascending): an operator's (MatrixFreePoisson::
// coupled_functions), O(1) per entry where the mesh's pattern walks every function's cells.
using CoupledFunctions = std::function<void(int, std::vector<int>&)>;

// The pattern (zero values) of what this rank adds. global_row: each free dof's global row,
// increasing, the owned rows [first_row, last_row) being a contiguous run of the free dofs;
// own_cells: the cells this rank integrates; coupled (optional): the owned rows' couplings,
// instead of the walk over the mesh's cells (the halo rows still walk this rank's cells).
// Threaded, in one pass (compress_rows).
RankRows rank_rows_pattern(const BezierMesh& mesh, const DofLayout& layout, std::vector<int> global_row, int first_row,
                           int last_row, CellRange own_cells, const CoupledFunctions* coupled = nullptr);

// The owned rows alone, no halo (a rank that writes its rows whole: nothing goes to other
// ranks), from the owned functions' couplings.
RankRows owned_rows_pattern(const DofLayout& layout, std::vector<int> global_row, int first_row, int last_row,
                            const CoupledFunctions& coupled);

}  // namespace knotwork
