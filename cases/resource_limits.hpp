#pragma once
// Refusals before work that could not finish on this machine: every family estimates the
// memory its space and solve need and calls check_memory before allocating anything.
#include <array>
#include <string>

namespace knotwork {

// Memory of the Galerkin pipeline for `cells` cells of bi-degree (p, q) and `functions`
// functions: cell function lists, the matrix (lower triangle, a copy per thread during
// assembly) and the Cholesky factor, estimated as nnz(A) log2(n) entries (measured with AMD
// on 2D IGA matrices: 0.73-0.75 log2(n), docs/records/performance-2026-11-22-to-12-04.md; the estimate keeps a margin).
double galerkin_bytes(double cells, double functions, int p, int q);

// The same for `cells` hexahedra of degrees (p, q, r) and a direct solve ordered by METIS or
// (`metis` false) AMD: the factor of a 3D problem fills in far more than in 2D (measured
// N^(5/3), constants in resource_limits.cpp); and for CG with "boomeramg" or "jacobi" on the
// assembled matrix (`user_amg_options`: the user's petsc_options may undo the 3D options, so
// BoomerAMG is counted as with hypre's defaults).
double volume_galerkin_bytes(double cells, double functions, const std::array<int, 3>& degree, bool metis);
double volume_iterative_bytes(double cells, double functions, const std::array<int, 3>& degree,
                              const std::string& preconditioner, bool user_amg_options);

// The same for CG with a structured preconditioner on a volume's assembled matrix (the fast
// diagonalization), whose own storage is `preconditioner` bytes.
double volume_structured_bytes(double functions, const std::array<int, 3>& degree, double preconditioner);
// CG without a matrix on a volume that is one affine map (its operator applied by mode
// products), `boundary_faces` faces of hexahedra on the boundary.
double volume_matrix_free_bytes(double functions, double boundary_faces, const std::array<int, 3>& degree,
                                double preconditioner);

// Memory of the iterative path (CG): the same cell lists and matrix as galerkin_bytes, no
// factor, CG's vectors, and `preconditioner` bytes for the preconditioner's own storage
// (preconditioner_bytes); with_matrix false: K applied without one ([solver] matrix).
double iterative_bytes(double cells, double functions, int p, int q, double preconditioner, bool with_matrix = true);

// The storage of an algebraic preconditioner for `functions` functions of bi-degree (p, q):
// "boomeramg" hypre's copy of the whole matrix and a hierarchy of about twice its size,
// "jacobi" a vector. (A structured one's is its owner's to say.)
double algebraic_preconditioner_bytes(const std::string& name, double functions, int p, int q);

// Throws InputError "<where>: about X GB needed for <what>, more than this machine's Y GB"
// when `bytes` exceeds 90% of the physical memory.
void check_memory(const std::string& where, double bytes, const std::string& what);

}  // namespace knotwork
