#pragma once
#include <gmpxx.h>

#include <utility>
#include <vector>

namespace knotwork {

// One linear condition sum over (column, coefficient) = 0 with exact coefficients.
struct SparseRationalRow {
  std::vector<std::pair<long, mpq_class>> terms;
};

// Rank of the rows by sparse Gaussian elimination modulo two unrelated primes below 2^61
// (the next of a short list when one divides a denominator of the rows). Rank mod p <= rank
// over Q, with equality unless p divides some minor; the two must agree (std::runtime_error
// otherwise: then use rank_exact). If `independent` is given, it receives
// for each row whether it is independent (mod the first prime) of the rows before it: those
// rows are independent over Q too, whatever the primes.
long rank_modular(const std::vector<SparseRationalRow>& rows, long columns, std::vector<bool>* independent = nullptr);

// Rank over Q by sparse elimination with GMP rationals (exact; slower). `independent` as above.
long rank_exact(const std::vector<SparseRationalRow>& rows, long columns, std::vector<bool>* independent = nullptr);

// rank_modular, or rank_exact when the two primes disagree (coordinates can make a prime
// unlucky: a T-mesh whose dimension jumps at special coordinates, moved off them by a
// multiple of the prime, is special modulo that prime only). `exact` (optional) says which.
long rank_reliable(const std::vector<SparseRationalRow>& rows, long columns, std::vector<bool>* independent = nullptr,
                   bool* exact = nullptr);

// Null space over Q of dense rows (reduced row echelon form): one vector per free column,
// with a 1 there and the pivot columns solved for. `rank` (optional) receives the rank.
// For the small local systems of the G1 and PT-spline constructions.
std::vector<std::vector<mpq_class>> null_space_exact(std::vector<std::vector<mpq_class>> rows, int columns,
                                                     long* rank = nullptr);

}  // namespace knotwork
