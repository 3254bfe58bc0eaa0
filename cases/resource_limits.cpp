#include "cases/resource_limits.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// CHOLMOD's factor of a volume's stiffness (docs/VOLUMES.md, measured on cubes of 5 000 to
// 195 000 unknowns): nnz(L) = a N^(5/3), with AMD a = 0.39, 1.14, 1.82 and 2.5 for p = 1..4
// (below 0.8 p), with METIS a = 0.17, 0.54-0.57, 1.31 and 2.0 (below 0.55 p); the run's peak
// memory 11.4-14.7 bytes per factor entry (values, indices, supernodal workspace).
constexpr double kVolumeFillAmd = 0.8;
constexpr double kVolumeFillMetis = 0.55;
constexpr double kVolumeFactorEntryBytes = 16;
// Measured (docs/VOLUMES.md): 89-105 bytes per entry at p = 2 from 39 000 to 2.2M unknowns,
// 78-81 at p = 3 and 70-74 at p = 4; with a margin.
constexpr double kVolumeAmgEntryBytes = 130;

}  // namespace

double galerkin_bytes(double cells, double functions, int p, int q) {
  const double per_cell = double(p + 1) * (q + 1);
  const double coupling = double(2 * p + 1) * (2 * q + 1) / 2;
  const double nnz = functions * coupling;
  const double factor = nnz * std::max(1.0, std::log2(std::max(functions, 2.0)));
  return cells * per_cell * 4 + nnz * 12 * 3 + factor * 8;
}

double volume_galerkin_bytes(double cells, double functions, const std::array<int, 3>& degree, bool metis) {
  double per_cell = 1, coupling = 0.5, mean_degree = 0;
  for (int p : degree) per_cell *= p + 1, coupling *= 2 * p + 1, mean_degree += p / 3.0;
  const double nnz = functions * coupling;
  const double factor = (metis ? kVolumeFillMetis : kVolumeFillAmd) * mean_degree * std::pow(std::max(functions, 2.0), 5.0 / 3.0);
  return cells * per_cell * 4 + nnz * 12 * 3 + std::max(factor, nnz) * kVolumeFactorEntryBytes;
}

double volume_iterative_bytes(double cells, double functions, const std::array<int, 3>& degree,
                              const std::string& preconditioner, bool user_amg_options) {
  double per_cell = 1, coupling = 0.5;
  for (int p : degree) per_cell *= p + 1, coupling *= 2 * p + 1;
  const double nnz = functions * coupling;
  // BoomerAMG in 3D, the whole run's peak per stored matrix entry (lower triangle; cubes,
  // docs/VOLUMES.md): with the options a volume starts from (kBoomerAmgVolumeOptions) at most
  // kVolumeAmgEntryBytes; with hypre's defaults, which a user's petsc_options may bring back,
  // 172, 174, 188 and 231 at 39 000 to 941 000 unknowns (p = 2), growing: 260 covers them.
  if (preconditioner != "jacobi") return cells * per_cell * 4 + nnz * (user_amg_options ? 260 : kVolumeAmgEntryBytes);
  return cells * per_cell * 4 + nnz * 12 * 3 + functions * 8 * 8;
}

double volume_structured_bytes(double functions, const std::array<int, 3>& degree, double preconditioner) {
  double coupling = 0.5;
  for (int p : degree) coupling *= 2 * p + 1;
  // Measured (docs/PERFORMANCE.md, "Volumes"): the whole run's peak was 20-28 bytes per stored
  // matrix entry with CG and the fast diagonalization, from 80 000 to 8.2M unknowns (p = 2, 3),
  // the most at the smallest sizes, where the program's own 0.05-0.1 GB weighs; 30 per entry
  // and 0.1 GB cover them.
  return 1e8 + functions * coupling * 30 + preconditioner;
}

double volume_matrix_free_bytes(double functions, double boundary_faces, const std::array<int, 3>& degree,
                                double preconditioner) {
  double per_cell = 1;
  for (int p : degree) per_cell *= p + 1;
  // The mesh (a cell and its functions' numbers per hexahedron), the vectors and the error
  // pass per function; the Dirichlet projection's triplets, boundary matrix and factor per
  // boundary face, a transient of the set-up. Calibrated on the cube (docs/PERFORMANCE.md,
  // "Volumes: CG without a matrix", peaks remeasured 2026-12-07 after the projection stopped
  // copying its entries: 1.36-1.58 times them), with a margin.
  return 1e8 + functions * (120 + 8 * per_cell) + boundary_faces * 50 * per_cell * per_cell / double(degree[2] + 1) / double(degree[2] + 1) + preconditioner;
}

double iterative_bytes(double cells, double functions, int p, int q, double preconditioner, bool with_matrix) {
  const double per_cell = double(p + 1) * (q + 1);
  const double coupling = double(2 * p + 1) * (2 * q + 1) / 2;
  // Without a matrix half as much per coupling: the mesh and the rest that the three matrix
  // copies cover (measured at 4096^2, p = 2: 434 bytes per function assembled, 344 without).
  return cells * per_cell * 4 + functions * coupling * 12 * (with_matrix ? 3 : 1.5) + functions * 8 * 8 + preconditioner;
}

double algebraic_preconditioner_bytes(const std::string& name, double functions, int p, int q) {
  if (name == "jacobi") return functions * 8;
  return functions * double(2 * p + 1) * (2 * q + 1) * 12 * 3;  // BoomerAMG
}

void check_memory(const std::string& where, double bytes, const std::string& what) {
  const double physical = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
  if (!(physical > 0) || bytes <= 0.9 * physical) return;
  char msg[300];
  std::snprintf(msg, sizeof msg, ": about %.0f GB needed for %s, more than this machine's %.0f GB", bytes / 1e9,
                what.c_str(), physical / 1e9);
  throw InputError(where + msg);
}

}  // namespace knotwork
