#pragma once
#include <gmpxx.h>

#include <cstdint>
#include <unordered_map>
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

// Arithmetic modulo primes below 2^61 for rows whose entries lie in a number field: the G1
// conditions with gluing data 2cos(2 pi / n) are reduced modulo a prime p = 1 (mod N), where
// the field Q(zeta_N) has an image (zeta_N -> a primitive N-th root of unity mod p). As for
// rational rows, the rank modulo p is at most the rank over the field.
// q mod prime (std::domain_error when the prime divides q's denominator), remembering the
// inverses of the denominators met (one object per thread).
class ResidueMap {
 public:
  explicit ResidueMap(uint64_t prime) : prime_(prime) {}
  uint64_t prime() const { return prime_; }
  uint64_t operator()(const mpq_class& q) const;

 private:
  uint64_t prime_;
  mutable std::unordered_map<uint64_t, uint64_t> inverses_;
};
uint64_t multiply_modulo(uint64_t a, uint64_t b, uint64_t prime);
uint64_t power_modulo(uint64_t a, uint64_t e, uint64_t prime);
// The `count` largest primes below 2^61 that are 1 modulo n (n <= 2^40), largest first.
std::vector<uint64_t> primes_congruent_to_one(uint64_t n, int count);
// A primitive n-th root of unity modulo `prime` (n must divide prime - 1).
uint64_t primitive_root_of_unity(uint64_t n, uint64_t prime);
// Rank modulo `prime` of rows given by (column, residue); a column named twice counts once.
long rank_of_residues(const std::vector<std::vector<std::pair<long, uint64_t>>>& rows, long columns, uint64_t prime);

// Null space over Q of dense rows (reduced row echelon form): one vector per free column,
// with a 1 there and the pivot columns solved for. `rank` (optional) receives the rank.
// For the small local systems of the G1 and PT-spline constructions.
std::vector<std::vector<mpq_class>> null_space_exact(std::vector<std::vector<mpq_class>> rows, int columns,
                                                     long* rank = nullptr);
// The same for sparse rows of (column, value); a column named twice in a row counts once,
// with the summed value.
std::vector<std::vector<mpq_class>> null_space_exact(const std::vector<std::vector<std::pair<int, mpq_class>>>& rows,
                                                     int columns, long* rank = nullptr);

// Integer rows (the rational rows, each times its denominators' lcm) in reduced echelon form
// on their first `leading` columns only: rows [0, pivot_column.size()) have their pivots at
// pivot_column (increasing, < leading) and are zero at the other pivot columns; the rows after
// them (none of them zero) are zero on the leading columns and span every combination of the
// input rows that is. The later columns are carried along, not eliminated. For systems whose
// leading columns split into blocks that share the later ones (the G1 edges' strips around a
// vertex): each block is reduced once and the small shared part is solved afterwards.
struct LeadingEchelon {
  int columns = 0, leading = 0;
  std::vector<int> pivot_column;
  std::vector<std::vector<mpz_class>> rows;  // dense over `columns`
};
LeadingEchelon leading_echelon(const std::vector<std::vector<std::pair<int, mpq_class>>>& rows, int columns,
                               int leading);
// The null space of the rows restricted to the leading columns (the later ones set to zero):
// the reduced-echelon basis over the leading columns, the same vectors null_space_exact gives
// for those restricted rows.
std::vector<std::vector<mpq_class>> leading_null_space(const LeadingEchelon& echelon);

}  // namespace knotwork
