// The exact rank and null space under the G1 and PT-spline constructions, against a textbook
// rational Gauss-Jordan written here (a rational division per entry, no integer rows, no
// primes): on random matrices of planted rank, with long binary denominators such as a mesh
// typed with 17 digits gives, zero columns, repeated and dependent rows.
#include <catch2/catch.hpp>

#include <algorithm>
#include <random>

#include "basis/exact/sparse_rank.hpp"

using knotwork::leading_echelon;
using knotwork::leading_null_space;
using knotwork::null_space_exact;
using knotwork::rank_exact;
using knotwork::rank_modular;
using knotwork::SparseRationalRow;

namespace {

using Matrix = std::vector<std::vector<mpq_class>>;

// Reduced row echelon form by the book; returns the pivot columns.
std::vector<int> reference_rref(Matrix& A, int columns) {
  std::vector<int> pivots;
  size_t r = 0;
  for (int c = 0; c < columns && r < A.size(); ++c) {
    size_t p = r;
    while (p < A.size() && A[p][c] == 0) ++p;
    if (p == A.size()) continue;
    std::swap(A[p], A[r]);
    const mpq_class pivot = A[r][c];
    for (int j = 0; j < columns; ++j) A[r][j] /= pivot;
    for (size_t i = 0; i < A.size(); ++i) {
      if (i == r) continue;
      const mpq_class f = A[i][c];
      for (int j = 0; j < columns; ++j) A[i][j] -= f * A[r][j];
    }
    pivots.push_back(c);
    ++r;
  }
  return pivots;
}

// B (m x k) C (k x n) with random entries: rank k generically; `long_fractions` gives the
// entries denominators 2^40..2^54 and 17-digit numerators.
Matrix planted(std::mt19937_64& rng, int m, int n, int k, bool long_fractions, int zero_columns) {
  std::uniform_int_distribution<long> small(-9, 9), big(-(1L << 53), 1L << 53);
  std::uniform_int_distribution<int> shift(40, 54);
  auto entry = [&] {
    if (!long_fractions) {
      // Denominator drawn first, in its own statement (gcc's order of the former argument list;
      // argument order is unspecified, and every compiler must see the same matrices).
      const long den = 1 + std::abs(small(rng)), num = small(rng);
      mpq_class x(num, den);
      x.canonicalize();  // GMP's arithmetic assumes canonical operands
      return x;
    }
    mpq_class x(big(rng));
    x /= mpq_class(mpz_class(1) << shift(rng));
    return x;
  };
  Matrix B(m, std::vector<mpq_class>(k)), C(k, std::vector<mpq_class>(n));
  for (auto& row : B)
    for (auto& x : row) x = entry();
  for (auto& row : C)
    for (int j = 0; j < n; ++j) row[j] = j < zero_columns ? mpq_class(0) : entry();
  Matrix A(m, std::vector<mpq_class>(n, mpq_class(0)));
  for (int i = 0; i < m; ++i)
    for (int l = 0; l < k; ++l)
      for (int j = 0; j < n; ++j) A[i][j] += B[i][l] * C[l][j];
  std::shuffle(A.begin(), A.end(), rng);
  // Zero columns anywhere, not only first.
  for (auto& row : A) std::rotate(row.begin(), row.begin() + zero_columns / 2, row.end());
  return A;
}

std::vector<SparseRationalRow> sparse(const Matrix& A) {
  std::vector<SparseRationalRow> rows;
  for (const auto& row : A) {
    SparseRationalRow s;
    for (size_t j = 0; j < row.size(); ++j)
      if (row[j] != 0) s.terms.emplace_back(static_cast<long>(j), row[j]);
    rows.push_back(std::move(s));
  }
  return rows;
}

}  // namespace

TEST_CASE("Exact null space and ranks agree with a textbook rational elimination", "[exact]") {
  std::mt19937_64 rng(20261202);
  struct Shape {
    int m, n, k, zero_columns;
  };
  for (const bool long_fractions : {false, true})
    for (const Shape s : {Shape{6, 9, 4, 0}, Shape{12, 10, 7, 2}, Shape{30, 24, 11, 3}, Shape{5, 12, 5, 1},
                          Shape{20, 8, 8, 0}, Shape{3, 7, 0, 0}}) {
      CAPTURE(long_fractions, s.m, s.n, s.k);
      Matrix A = planted(rng, s.m, s.n, s.k, long_fractions, s.zero_columns);
      Matrix R = A;
      const std::vector<int> pivots = reference_rref(R, s.n);
      CHECK(static_cast<int>(pivots.size()) == s.k);  // the planted rank (generic)

      long rank = -1;
      const Matrix Z = null_space_exact(A, s.n, &rank);
      CHECK(rank == static_cast<long>(pivots.size()));
      REQUIRE(static_cast<int>(Z.size()) == s.n - s.k);
      // The same vectors as the book's: 1 at each free column in turn, minus the reduced
      // rows' entries of that column at the pivot columns.
      std::vector<bool> is_pivot(s.n, false);
      for (int c : pivots) is_pivot[c] = true;
      size_t z = 0;
      for (int f = 0; f < s.n; ++f) {
        if (is_pivot[f]) continue;
        std::vector<mpq_class> expected(s.n, mpq_class(0));
        expected[f] = 1;
        for (size_t i = 0; i < pivots.size(); ++i) expected[pivots[i]] = -R[i][f];
        CHECK(Z[z] == expected);
        ++z;
      }
      // The sparse entry point, with every nonzero split in two terms of the same column:
      // the same vectors.
      std::vector<std::vector<std::pair<int, mpq_class>>> split(A.size());
      for (size_t i = 0; i < A.size(); ++i)
        for (int j = 0; j < s.n; ++j)
          if (A[i][j] != 0) {
            const mpq_class third = A[i][j] / 3;
            split[i].emplace_back(j, third);
            split[i].emplace_back(j, A[i][j] - third);
          }
      long sparse_rank = -1;
      CHECK(null_space_exact(split, s.n, &sparse_rank) == Z);
      CHECK(sparse_rank == rank);
      // And each is in the null space, exactly.
      for (const auto& x : Z)
        for (const auto& row : A) {
          mpq_class dot = 0;
          for (int j = 0; j < s.n; ++j) dot += row[j] * x[j];
          CHECK(dot == 0);
        }

      CHECK(rank_modular(sparse(A), s.n) == s.k);
      CHECK(rank_exact(sparse(A), s.n) == s.k);
    }
}

TEST_CASE("Echelon on the leading columns: their null space, and the rows left on the others", "[exact]") {
  // What the G1 strips need of it (basis/g1/g1_basis.cpp), against the book: the reduced
  // rows' pivots are the book's pivots of the leading columns alone; the null space of those
  // columns is the book's; the rows left are zero there, lie in the row space, and have the
  // rank the combinations vanishing on the leading columns have, rank A - rank A_leading.
  std::mt19937_64 rng(20261203);
  auto rank_of = [](Matrix M, int columns) { return static_cast<long>(reference_rref(M, columns).size()); };
  struct Shape {
    int m, n, k, zero_columns, leading;
  };
  for (const bool long_fractions : {false, true})
    for (const Shape s : {Shape{24, 32, 14, 0, 16}, Shape{12, 10, 7, 2, 5}, Shape{30, 24, 11, 3, 24},
                          Shape{8, 12, 8, 1, 0}, Shape{20, 8, 8, 0, 3}, Shape{3, 7, 0, 0, 4}}) {
      CAPTURE(long_fractions, s.m, s.n, s.k, s.leading);
      const Matrix A = planted(rng, s.m, s.n, s.k, long_fractions, s.zero_columns);
      std::vector<std::vector<std::pair<int, mpq_class>>> rows(A.size());
      for (size_t i = 0; i < A.size(); ++i)
        for (int j = 0; j < s.n; ++j)
          if (A[i][j] != 0) rows[i].emplace_back(j, A[i][j]);
      const auto E = leading_echelon(rows, s.n, s.leading);

      Matrix leading(A.size(), std::vector<mpq_class>(s.leading));
      for (size_t i = 0; i < A.size(); ++i)
        for (int j = 0; j < s.leading; ++j) leading[i][j] = A[i][j];
      Matrix R = leading;
      const std::vector<int> pivots = reference_rref(R, s.leading);
      REQUIRE(E.pivot_column == pivots);
      for (size_t i = 0; i < pivots.size(); ++i)
        for (size_t l = 0; l < pivots.size(); ++l) CHECK((E.rows[i][pivots[l]] != 0) == (i == l));
      CHECK(leading_null_space(E) == null_space_exact(leading, s.leading));

      Matrix rest, stacked = A;
      for (size_t i = pivots.size(); i < E.rows.size(); ++i) {
        std::vector<mpq_class> row(E.rows[i].begin(), E.rows[i].end());
        CHECK(std::any_of(row.begin(), row.end(), [](const mpq_class& x) { return x != 0; }));
        for (int j = 0; j < s.leading; ++j) CHECK(row[j] == 0);
        rest.push_back(row);
        stacked.push_back(row);
      }
      const long rank = rank_of(A, s.n);
      CHECK(rank_of(stacked, s.n) == rank);
      CHECK(rank_of(rest, s.n) == rank - static_cast<long>(pivots.size()));
    }
  CHECK_THROWS_AS(leading_echelon({}, 3, 4), std::invalid_argument);
}

TEST_CASE("Modular rank: a column named twice in a row counts once, with the summed coefficient", "[exact]") {
  // x0 + x1 = 0 written as 1/2 x0 + x1 + 1/2 x0, and 2 x0 + 2 x1 = 0: rank 1.
  std::vector<SparseRationalRow> rows(2);
  rows[0].terms = {{0, mpq_class(1, 2)}, {1, mpq_class(1)}, {0, mpq_class(1, 2)}};
  rows[1].terms = {{1, mpq_class(2)}, {0, mpq_class(2)}};
  std::vector<bool> independent;
  CHECK(rank_modular(rows, 2, &independent) == 1);
  CHECK(independent == std::vector<bool>{true, false});
  // Terms that cancel leave an empty row.
  rows[1].terms = {{1, mpq_class(3, 7)}, {1, mpq_class(-3, 7)}};
  CHECK(rank_modular(rows, 2) == 1);
}
