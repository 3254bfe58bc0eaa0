// knotwork's sparse modular rank (basis/exact/sparse_rank) against FLINT 2.9's dense ranks on
// the brute-force dimension systems of `knotwork dimension`: nmod_mat_rank modulo the same
// 61-bit prime, and fmpz_mat_rank (over Q: rows scaled to integers) on the smaller systems. Built only when libflint-dev is
// installed (it is not a dependency of knotwork: the measurement decided against it,
// docs/PERFORMANCE.md). Usage: knotwork_rank_against_flint [MAX_CELLS_PER_SIDE]
#include <flint/fmpq_mat.h>
#include <flint/nmod_mat.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "basis/exact/sparse_rank.hpp"
#include "basis/tmesh/spline_dimension.hpp"

using namespace knotwork;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The n x n uniform grid on [0, 1]^2 with a T-junction in every other cell column (a cell
// split horizontally): a T-mesh, so that the rank is not the tensor one.
RectangularPartition t_grid(int n) {
  std::vector<RationalBox> cells;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const mpq_class x0(i, n), x1(i + 1, n), y0(j, n), y1(j + 1, n);
      if (i % 2 == 1 && j % 2 == 0) {
        const mpq_class ym = (y0 + y1) / 2;
        cells.push_back({x0, y0, x1, ym});
        cells.push_back({x0, ym, x1, y1});
      } else {
        cells.push_back({x0, y0, x1, y1});
      }
    }
  for (RationalBox& b : cells) b.x0.canonicalize(), b.x1.canonicalize(), b.y0.canonicalize(), b.y1.canonicalize();
  return RectangularPartition(std::move(cells));
}

}  // namespace

int main(int argc, char** argv) {
  const int max_side = argc > 1 ? std::atoi(argv[1]) : 12;
  const int m = 3, alpha = 2;  // bicubic C^2, the case the dimension oracles are most asked for
  const mp_limb_t prime = (mp_limb_t(1) << 61) - 1;  // a Mersenne prime below 2^61
  std::printf("bicubic C^2 on a T-grid of n x n cells; seconds; ranks must agree\n");
  std::printf("%4s %8s %8s %8s %12s %12s %12s\n", "n", "rows", "columns", "rank", "knotwork", "FLINT nmod", "FLINT fmpz");
  for (int n = 4; n <= max_side; n += 4) {
    const RectangularPartition part = t_grid(n);
    const std::vector<SparseRationalRow> rows = smoothness_constraints(part, m, m, alpha, alpha);
    const long columns = static_cast<long>(part.num_cells()) * (m + 1) * (m + 1);
    auto t = std::chrono::steady_clock::now();
    const long ours = rank_modular(rows, columns);
    const double t_ours = seconds_since(t);

    ResidueMap residue(prime);
    nmod_mat_t a;
    nmod_mat_init(a, static_cast<slong>(rows.size()), columns, prime);
    for (size_t r = 0; r < rows.size(); ++r)
      for (const auto& [c, q] : rows[r].terms)
        nmod_mat_entry(a, r, c) = nmod_add(nmod_mat_entry(a, r, c), residue(q), a->mod);
    t = std::chrono::steady_clock::now();
    const long theirs = nmod_mat_rank(a);
    const double t_nmod = seconds_since(t);
    nmod_mat_clear(a);

    double t_fmpq = -1;
    long exact = -1;
    if (columns <= 2000) {
      fmpq_mat_t q;
      fmpq_mat_init(q, static_cast<slong>(rows.size()), columns);
      for (size_t r = 0; r < rows.size(); ++r)
        for (const auto& [c, v] : rows[r].terms) {
          fmpq_t x;
          fmpq_init(x);
          fmpq_set_mpq(x, v.get_mpq_t());
          fmpq_add(fmpq_mat_entry(q, r, c), fmpq_mat_entry(q, r, c), x);
          fmpq_clear(x);
        }
      // FLINT 2.9 ranks integer matrices: each row times its denominators' lcm (the same rank).
      t = std::chrono::steady_clock::now();
      fmpz_mat_t z;
      fmpz_mat_init(z, static_cast<slong>(rows.size()), columns);
      fmpq_mat_get_fmpz_mat_rowwise(z, nullptr, q);
      exact = fmpz_mat_rank(z);
      t_fmpq = seconds_since(t);
      fmpz_mat_clear(z);
      fmpq_mat_clear(q);
    }
    std::printf("%4d %8zu %8ld %8ld %12.4f %12.4f %12s%s\n", n, rows.size(), columns, ours, t_ours, t_nmod,
                t_fmpq < 0 ? "-" : std::to_string(t_fmpq).c_str(),
                ours == theirs && (exact < 0 || exact == ours) ? "" : "  RANKS DIFFER");
  }
  return 0;
}
