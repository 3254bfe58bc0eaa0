#include "basis/exact/sparse_rank.hpp"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_map>

namespace knotwork {

namespace {

class DenominatorMultipleOfPrime : public std::runtime_error {
 public:
  DenominatorMultipleOfPrime() : std::runtime_error("a denominator is a multiple of the prime") {}
};

// ---- arithmetic modulo an odd prime below 2^61, in Montgomery form ----
// A value x is held as x 2^64 mod p: a product is then reduced with two multiplications
// instead of a 128-bit division (which was a third of the rank's time). Zero stays zero, so
// the elimination's zero tests are unchanged.
struct ModP {
  uint64_t p = 0, neg_inverse = 0, one = 0, r_squared = 0;
  explicit ModP(uint64_t prime) : p(prime) {
    uint64_t inverse = p;  // Newton's iteration for p^-1 mod 2^64 (p odd): 6 steps give 64 bits
    for (int i = 0; i < 6; ++i) inverse *= 2 - p * inverse;
    neg_inverse = 0 - inverse;
    one = static_cast<uint64_t>((static_cast<__uint128_t>(1) << 64) % p);
    r_squared = static_cast<uint64_t>(static_cast<__uint128_t>(one) * one % p);
  }
  uint64_t reduce(__uint128_t t) const {  // t 2^-64 mod p, for t < p 2^64
    const uint64_t m = static_cast<uint64_t>(t) * neg_inverse;
    const uint64_t r = static_cast<uint64_t>((t + static_cast<__uint128_t>(m) * p) >> 64);
    return r >= p ? r - p : r;
  }
  uint64_t mul(uint64_t a, uint64_t b) const { return reduce(static_cast<__uint128_t>(a) * b); }
  uint64_t add(uint64_t a, uint64_t b) const { const uint64_t s = a + b; return s >= p ? s - p : s; }
  uint64_t sub(uint64_t a, uint64_t b) const { return a >= b ? a - b : a + p - b; }
  uint64_t pow(uint64_t a, uint64_t e) const {
    uint64_t r = one;
    for (; e; e >>= 1, a = mul(a, a))
      if (e & 1) r = mul(r, a);
    return r;
  }
  uint64_t inv(uint64_t a) const { return pow(a, p - 2); }
  uint64_t of(const mpz_class& z) const {  // z mod p, in Montgomery form
    mpz_class r;
    mpz_fdiv_r_ui(r.get_mpz_t(), z.get_mpz_t(), p);
    return mul(r.get_ui(), r_squared);
  }
  uint64_t of(const mpq_class& q) const {
    const uint64_t d = of(q.get_den());
    if (d == 0) throw DenominatorMultipleOfPrime();
    return mul(of(q.get_num()), inverse_of_denominator(d));
  }

 private:
  // The rows' denominators are few (the same sample points and data recur): their inverses,
  // 120 products each, are remembered (they were most of the rank's time).
  mutable std::unordered_map<uint64_t, uint64_t> inverses_;
  uint64_t inverse_of_denominator(uint64_t d) const {
    if (d == one) return one;
    const auto [it, added] = inverses_.try_emplace(d, 0);
    if (added) it->second = inv(d);
    return it->second;
  }
};

const std::vector<std::pair<long, mpq_class>>& terms_of(const SparseRationalRow& row) { return row.terms; }
const std::vector<std::pair<long, uint64_t>>& terms_of(const std::vector<std::pair<long, uint64_t>>& row) { return row; }

// Incremental sparse row echelon form: each new row is reduced by the pivots whose
// leading column it meets, until it is zero (dependent) or becomes a new pivot.
template <class Field, class Rows>
long sparse_rank(const Rows& rows, long columns, const Field& F, std::vector<bool>* independent = nullptr) {
  using Value = typename Field::Value;
  using Row = std::vector<std::pair<long, Value>>;  // sorted by column, leading entry 1
  std::vector<int> pivot_of(columns, -1);
  std::vector<Row> pivots;
  Row row, merged;
  if (independent) independent->assign(rows.size(), false);
  for (size_t index = 0; index < rows.size(); ++index) {
    row.clear();
    for (const auto& [col, q] : terms_of(rows[index])) {
      Value v = F.of(q);
      if (!F.zero(v)) row.emplace_back(col, v);
    }
    std::sort(row.begin(), row.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    // A column named twice counts once, with the summed coefficient.
    size_t out = 0;
    for (size_t i = 0; i < row.size(); ++i) {
      if (out > 0 && row[out - 1].first == row[i].first) row[out - 1].second = F.add(row[out - 1].second, row[i].second);
      else row[out++] = row[i];
    }
    row.resize(out);
    row.erase(std::remove_if(row.begin(), row.end(), [&](const auto& e) { return F.zero(e.second); }), row.end());
    while (!row.empty()) {
      const long lead = row.front().first;
      const int pv = pivot_of[lead];
      if (pv < 0) {  // new pivot, normalized to a leading 1
        const Value inv = F.inv(row.front().second);
        for (auto& [col, v] : row) v = F.mul(v, inv);
        pivot_of[lead] = static_cast<int>(pivots.size());
        pivots.push_back(row);
        if (independent) (*independent)[index] = true;
        break;
      }
      const Value factor = row.front().second;
      const Row& p = pivots[pv];
      merged.clear();
      size_t a = 0, b = 0;
      while (a < row.size() || b < p.size()) {
        if (b == p.size() || (a < row.size() && row[a].first < p[b].first)) merged.push_back(row[a++]);
        else if (a == row.size() || p[b].first < row[a].first) {
          merged.emplace_back(p[b].first, F.neg(F.mul(factor, p[b].second)));
          ++b;
        } else {
          const Value v = F.sub(row[a].second, F.mul(factor, p[b].second));
          if (!F.zero(v)) merged.emplace_back(row[a].first, v);
          ++a;
          ++b;
        }
      }
      row.swap(merged);
    }
  }
  return static_cast<long>(pivots.size());
}

struct ModularField {
  using Value = uint64_t;
  ModP m;
  Value of(const mpq_class& q) const { return m.of(q); }
  Value of(uint64_t residue) const { return m.mul(residue % m.p, m.r_squared); }
  bool zero(Value v) const { return v == 0; }
  Value inv(Value v) const { return m.inv(v); }
  Value mul(Value a, Value b) const { return m.mul(a, b); }
  Value sub(Value a, Value b) const { return m.sub(a, b); }
  Value add(Value a, Value b) const { return m.add(a, b); }
  Value neg(Value a) const { return m.sub(0, a); }
};

struct RationalField {
  using Value = mpq_class;
  Value of(const mpq_class& q) const { return q; }
  bool zero(const Value& v) const { return v == 0; }
  Value inv(const Value& v) const { return 1 / v; }
  Value mul(const Value& a, const Value& b) const { return a * b; }
  Value sub(const Value& a, const Value& b) const { return a - b; }
  Value add(const Value& a, const Value& b) const { return a + b; }
  Value neg(const Value& a) const { return -a; }
};

}  // namespace

// Primes below 2^61 (Miller-Rabin with the first 12 prime bases, deterministic below 3e24).
// A prime that divides a denominator of the rows cannot reduce them: the next one is used.
constexpr uint64_t kPrimes[] = {(1ULL << 61) - 1, 2305843009213693921ULL, 2305843009213693907ULL,
                                2305843009213693723ULL, 2305843009213693693ULL};

long rank_modular(const std::vector<SparseRationalRow>& rows, long columns, std::vector<bool>* independent) {
  // The first two primes at once (they are independent eliminations; usually both apply).
  {
    long second = -1;
    bool second_failed = false;
    std::thread other([&] {
      try {
        second = sparse_rank(rows, columns, ModularField{ModP(kPrimes[1])}, nullptr);
      } catch (const DenominatorMultipleOfPrime&) {
        second_failed = true;
      }
    });
    long first = -1;
    bool first_failed = false;
    try {
      first = sparse_rank(rows, columns, ModularField{ModP(kPrimes[0])}, independent);
    } catch (const DenominatorMultipleOfPrime&) {
      first_failed = true;
    }
    other.join();
    if (!first_failed && !second_failed) {
      if (first != second)
        throw std::runtime_error("modular ranks disagree (" + std::to_string(first) + " vs " + std::to_string(second) +
                                 "): use the exact method");
      return first;
    }
  }
  // A prime divided a denominator: the primes one after the other, the next ones included.
  long ranks[2];
  int found = 0;
  for (uint64_t p : kPrimes) {
    try {
      ranks[found] = sparse_rank(rows, columns, ModularField{ModP(p)}, found == 0 ? independent : nullptr);
      if (++found == 2) break;
    } catch (const DenominatorMultipleOfPrime&) {  // try the next prime
    }
  }
  if (found < 2) throw std::runtime_error("modular rank: the denominators are multiples of the primes; use the exact method");
  if (ranks[0] != ranks[1])
    throw std::runtime_error("modular ranks disagree (" + std::to_string(ranks[0]) + " vs " + std::to_string(ranks[1]) +
                             "): use the exact method");
  return ranks[0];
}

long rank_exact(const std::vector<SparseRationalRow>& rows, long columns, std::vector<bool>* independent) {
  return sparse_rank(rows, columns, RationalField{}, independent);
}

long rank_reliable(const std::vector<SparseRationalRow>& rows, long columns, std::vector<bool>* independent,
                   bool* exact) {
  if (exact) *exact = false;
  try {
    return rank_modular(rows, columns, independent);
  } catch (const std::runtime_error&) {  // the primes disagree, or none could be used
  }
  if (exact) *exact = true;
  return rank_exact(rows, columns, independent);
}

uint64_t ResidueMap::operator()(const mpq_class& q) const {
  const uint64_t d = mpz_fdiv_ui(q.get_den_mpz_t(), prime_);
  if (d == 0) throw std::domain_error("the prime " + std::to_string(prime_) + " divides the denominator of " + q.get_str());
  uint64_t inverse = 1;
  if (d != 1) {
    const auto [it, added] = inverses_.try_emplace(d, 0);
    if (added) it->second = power_modulo(d, prime_ - 2, prime_);
    inverse = it->second;
  }
  return multiply_modulo(mpz_fdiv_ui(q.get_num_mpz_t(), prime_), inverse, prime_);
}

uint64_t multiply_modulo(uint64_t a, uint64_t b, uint64_t prime) {
  return static_cast<uint64_t>(static_cast<__uint128_t>(a) * b % prime);
}

uint64_t power_modulo(uint64_t a, uint64_t e, uint64_t prime) {
  uint64_t r = 1 % prime;
  for (a %= prime; e; e >>= 1, a = multiply_modulo(a, a, prime))
    if (e & 1) r = multiply_modulo(r, a, prime);
  return r;
}

namespace {

// Deterministic Miller-Rabin below 3.3e24 (the first 12 primes as bases).
bool is_prime(uint64_t n) {
  if (n < 2) return false;
  for (uint64_t p : {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37})
    if (n % p == 0) return n == p;
  uint64_t d = n - 1;
  int s = 0;
  for (; d % 2 == 0; d /= 2) ++s;
  for (uint64_t a : {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37}) {
    uint64_t x = power_modulo(a, d, n);
    if (x == 1 || x == n - 1) continue;
    bool composite = true;
    for (int i = 1; i < s && composite; ++i) {
      x = multiply_modulo(x, x, n);
      composite = x != n - 1;
    }
    if (composite) return false;
  }
  return true;
}

std::vector<uint64_t> prime_factors(uint64_t n) {
  std::vector<uint64_t> out;
  for (uint64_t p = 2; p * p <= n; ++p)
    if (n % p == 0) {
      out.push_back(p);
      while (n % p == 0) n /= p;
    }
  if (n > 1) out.push_back(n);
  return out;
}

}  // namespace

std::vector<uint64_t> primes_congruent_to_one(uint64_t n, int count) {
  if (n == 0 || n > (1ULL << 40)) throw std::invalid_argument("primes_congruent_to_one: modulus out of range");
  std::vector<uint64_t> out;
  for (uint64_t m = ((1ULL << 61) - 2) / n; m > 0 && static_cast<int>(out.size()) < count; --m)
    if (is_prime(m * n + 1)) out.push_back(m * n + 1);
  return out;
}

uint64_t primitive_root_of_unity(uint64_t n, uint64_t prime) {
  if (n == 0 || (prime - 1) % n != 0)
    throw std::invalid_argument("primitive_root_of_unity: " + std::to_string(n) + " does not divide p - 1");
  const std::vector<uint64_t> factors = prime_factors(n);
  for (uint64_t x = 2; x < prime; ++x) {
    const uint64_t z = power_modulo(x, (prime - 1) / n, prime);
    bool primitive = true;
    for (uint64_t q : factors) primitive = primitive && power_modulo(z, n / q, prime) != 1;
    if (primitive) return z;
  }
  throw std::logic_error("primitive_root_of_unity: none found");
}

long rank_of_residues(const std::vector<std::vector<std::pair<long, uint64_t>>>& rows, long columns, uint64_t prime) {
  return sparse_rank(rows, columns, ModularField{ModP(prime)});
}

namespace {

// Rational rows as integer rows: each row times the lcm of its denominators. Straight into
// integer rows, with no dense rational matrix (its entries' allocations were a quarter of a G1
// build on a mesh with 17-digit coordinates).
std::vector<std::vector<mpz_class>> integer_rows(const std::vector<std::vector<std::pair<int, mpq_class>>>& rows,
                                                 int columns) {
  std::vector<std::vector<mpz_class>> A(rows.size(), std::vector<mpz_class>(columns));
  mpz_class lcm, scale;
  for (size_t i = 0; i < rows.size(); ++i) {
    lcm = 1;
    for (const auto& [j, x] : rows[i]) mpz_lcm(lcm.get_mpz_t(), lcm.get_mpz_t(), x.get_den_mpz_t());
    for (const auto& [j, x] : rows[i]) {
      if (j < 0 || j >= columns) throw std::invalid_argument("null_space_exact: column out of range");
      mpz_divexact(scale.get_mpz_t(), lcm.get_mpz_t(), x.get_den_mpz_t());
      mpz_addmul(A[i][j].get_mpz_t(), scale.get_mpz_t(), x.get_num_mpz_t());
    }
  }
  return A;
}

// Gauss-Jordan on integer rows over the columns [0, leading): a row is updated in place,
// p * row - q * pivot row, and divided by the gcd of its entries, so there is no rational
// arithmetic (a gcd per product) and no temporary per entry. Afterwards the first rows have
// their pivots at pivot_col (increasing) and are zero at the other pivot columns; the rows
// after them are zero on [0, leading). The reduced echelon form is unique, so the result is
// the one rational elimination gives, 4x faster measured on the G1 vertex systems.
void reduce_leading(std::vector<std::vector<mpz_class>>& A, int columns, int leading, std::vector<int>& pivot_col) {
  mpz_class g, p, q;
  auto remove_content = [&](std::vector<mpz_class>& row) {
    g = 0;
    for (const mpz_class& x : row)
      if (x != 0) {
        mpz_gcd(g.get_mpz_t(), g.get_mpz_t(), x.get_mpz_t());
        if (g == 1) return;
      }
    if (g > 1)
      for (mpz_class& x : row)
        if (x != 0) mpz_divexact(x.get_mpz_t(), x.get_mpz_t(), g.get_mpz_t());
  };
  pivot_col.clear();
  size_t r = 0;
  for (int c = 0; c < leading && r < A.size(); ++c) {
    size_t best = A.size();  // the smallest pivot in size keeps the numbers small
    for (size_t i = r; i < A.size(); ++i)
      if (A[i][c] != 0 && (best == A.size() || mpz_cmpabs(A[i][c].get_mpz_t(), A[best][c].get_mpz_t()) < 0)) best = i;
    if (best == A.size()) continue;
    std::swap(A[best], A[r]);
    p = A[r][c];
    for (size_t i = 0; i < A.size(); ++i) {
      if (i == r || A[i][c] == 0) continue;
      q = A[i][c];
      // Row r is zero left of c (its earlier pivot columns were eliminated, and the other
      // columns had no pivot in the rows from r on); row i is scaled by p everywhere.
      for (int j = 0; j < columns; ++j) {
        if (A[i][j] != 0) A[i][j] *= p;
        if (j >= c && A[r][j] != 0) mpz_submul(A[i][j].get_mpz_t(), q.get_mpz_t(), A[r][j].get_mpz_t());
      }
      remove_content(A[i]);
    }
    pivot_col.push_back(c);
    ++r;
  }
}

// The reduced-echelon null vectors of the first `leading` columns: one per free column
// f < leading, 1 there, 0 at the other free columns, the pivots solved for.
std::vector<std::vector<mpq_class>> free_column_vectors(const std::vector<std::vector<mpz_class>>& A, int leading,
                                                        const std::vector<int>& pivot_col) {
  std::vector<bool> is_pivot(leading, false);
  for (int c : pivot_col) is_pivot[c] = true;
  std::vector<std::vector<mpq_class>> basis;
  for (int f = 0; f < leading; ++f) {
    if (is_pivot[f]) continue;
    std::vector<mpq_class> x(leading, mpq_class(0));
    x[f] = 1;
    for (size_t i = 0; i < pivot_col.size(); ++i)
      if (A[i][f] != 0) {
        x[pivot_col[i]] = mpq_class(-A[i][f], A[i][pivot_col[i]]);
        x[pivot_col[i]].canonicalize();
      }
    basis.push_back(std::move(x));
  }
  return basis;
}

std::vector<std::vector<mpq_class>> integer_null_space(std::vector<std::vector<mpz_class>> A, int columns, long* rank) {
  std::vector<int> pivot_col;
  reduce_leading(A, columns, columns, pivot_col);
  if (rank) *rank = static_cast<long>(pivot_col.size());
  return free_column_vectors(A, columns, pivot_col);
}

}  // namespace

std::vector<std::vector<mpq_class>> null_space_exact(std::vector<std::vector<mpq_class>> rows, int columns, long* rank) {
  std::vector<std::vector<mpz_class>> A(rows.size(), std::vector<mpz_class>(columns));
  for (size_t i = 0; i < rows.size(); ++i) {
    mpz_class lcm = 1;
    for (int j = 0; j < columns; ++j)
      if (rows[i][j] != 0) mpz_lcm(lcm.get_mpz_t(), lcm.get_mpz_t(), rows[i][j].get_den_mpz_t());
    for (int j = 0; j < columns; ++j)
      if (rows[i][j] != 0) {
        mpz_divexact(A[i][j].get_mpz_t(), lcm.get_mpz_t(), rows[i][j].get_den_mpz_t());
        A[i][j] *= rows[i][j].get_num();
      }
  }
  rows.clear();
  return integer_null_space(std::move(A), columns, rank);
}

std::vector<std::vector<mpq_class>> null_space_exact(const std::vector<std::vector<std::pair<int, mpq_class>>>& rows,
                                                     int columns, long* rank) {
  return integer_null_space(integer_rows(rows, columns), columns, rank);
}

LeadingEchelon leading_echelon(const std::vector<std::vector<std::pair<int, mpq_class>>>& rows, int columns,
                               int leading) {
  if (leading < 0 || leading > columns) throw std::invalid_argument("leading_echelon: leading columns out of range");
  LeadingEchelon out;
  out.columns = columns;
  out.leading = leading;
  out.rows = integer_rows(rows, columns);
  reduce_leading(out.rows, columns, leading, out.pivot_column);
  // Rows that vanished entirely say nothing.
  const auto zero = [](const std::vector<mpz_class>& row) {
    return std::all_of(row.begin(), row.end(), [](const mpz_class& x) { return x == 0; });
  };
  out.rows.erase(std::remove_if(out.rows.begin() + static_cast<long>(out.pivot_column.size()), out.rows.end(), zero),
                 out.rows.end());
  return out;
}

std::vector<std::vector<mpq_class>> leading_null_space(const LeadingEchelon& echelon) {
  return free_column_vectors(echelon.rows, echelon.leading, echelon.pivot_column);
}

}  // namespace knotwork
