#include "basis/exact/sparse_rank.hpp"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>

namespace knotwork {

namespace {

class DenominatorMultipleOfPrime : public std::runtime_error {
 public:
  DenominatorMultipleOfPrime() : std::runtime_error("a denominator is a multiple of the prime") {}
};

// ---- arithmetic modulo a prime below 2^61 ----
struct ModP {
  uint64_t p;
  uint64_t mul(uint64_t a, uint64_t b) const { return static_cast<uint64_t>((__uint128_t)a * b % p); }
  uint64_t add(uint64_t a, uint64_t b) const { const uint64_t s = a + b; return s >= p ? s - p : s; }
  uint64_t sub(uint64_t a, uint64_t b) const { return a >= b ? a - b : a + p - b; }
  uint64_t pow(uint64_t a, uint64_t e) const {
    uint64_t r = 1;
    for (; e; e >>= 1, a = mul(a, a))
      if (e & 1) r = mul(r, a);
    return r;
  }
  uint64_t inv(uint64_t a) const { return pow(a, p - 2); }
  uint64_t of(const mpz_class& z) const {
    mpz_class r;
    mpz_fdiv_r_ui(r.get_mpz_t(), z.get_mpz_t(), p);
    return r.get_ui();
  }
  uint64_t of(const mpq_class& q) const {
    const uint64_t d = of(q.get_den());
    if (d == 0) throw DenominatorMultipleOfPrime();
    return mul(of(q.get_num()), inv(d));
  }
};

using Constraint = SparseRationalRow;

// Incremental sparse row echelon form: each new row is reduced by the pivots whose
// leading column it meets, until it is zero (dependent) or becomes a new pivot.
template <class Field>
long sparse_rank(const std::vector<Constraint>& rows, long columns, const Field& F,
                 std::vector<bool>* independent = nullptr) {
  using Value = typename Field::Value;
  using Row = std::vector<std::pair<long, Value>>;  // sorted by column, leading entry 1
  std::vector<int> pivot_of(columns, -1);
  std::vector<Row> pivots;
  Row row, merged;
  if (independent) independent->assign(rows.size(), false);
  for (size_t index = 0; index < rows.size(); ++index) {
    const Constraint& c = rows[index];
    row.clear();
    for (const auto& [col, q] : c.terms) {
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
        second = sparse_rank(rows, columns, ModularField{{kPrimes[1]}}, nullptr);
      } catch (const DenominatorMultipleOfPrime&) {
        second_failed = true;
      }
    });
    long first = -1;
    bool first_failed = false;
    try {
      first = sparse_rank(rows, columns, ModularField{{kPrimes[0]}}, independent);
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
      ranks[found] = sparse_rank(rows, columns, ModularField{{p}}, found == 0 ? independent : nullptr);
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

std::vector<std::vector<mpq_class>> null_space_exact(std::vector<std::vector<mpq_class>> A, int columns, long* rank) {
  std::vector<int> pivot_col;
  size_t r = 0;
  for (int c = 0; c < columns && r < A.size(); ++c) {
    size_t p = r;
    while (p < A.size() && A[p][c] == 0) ++p;
    if (p == A.size()) continue;
    std::swap(A[p], A[r]);
    const mpq_class inv = 1 / A[r][c];
    for (int j = c; j < columns; ++j) A[r][j] *= inv;
    for (size_t i = 0; i < A.size(); ++i) {
      if (i == r || A[i][c] == 0) continue;
      const mpq_class f = A[i][c];
      for (int j = c; j < columns; ++j)
        if (A[r][j] != 0) A[i][j] -= f * A[r][j];
    }
    pivot_col.push_back(c);
    ++r;
  }
  if (rank) *rank = static_cast<long>(r);
  std::vector<bool> is_pivot(columns, false);
  for (int c : pivot_col) is_pivot[c] = true;
  std::vector<std::vector<mpq_class>> basis;
  for (int f = 0; f < columns; ++f) {
    if (is_pivot[f]) continue;
    std::vector<mpq_class> x(columns, mpq_class(0));
    x[f] = 1;
    for (size_t i = 0; i < pivot_col.size(); ++i) x[pivot_col[i]] = -A[i][f];
    basis.push_back(std::move(x));
  }
  return basis;
}

}  // namespace knotwork
