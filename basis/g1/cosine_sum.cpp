// Exact sums of cosines of rational multiples of pi (the symmetric gluing values at
// valences 5, 7, 8, ...) and their images modulo primes with a root of unity: what lets the
// G1 dimension of such data be a sparse modular rank instead of a dense SVD.
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "basis/exact/sparse_rank.hpp"
#include "basis/g1/g1_space.hpp"

namespace knotwork {

CosineSum CosineSum::two_cos_pi(long p, long q) {
  if (q <= 0) throw std::invalid_argument("CosineSum::two_cos_pi: denominator must be positive");
  mpq_class r(p, q);
  r.canonicalize();
  // r modulo 2, in [0, 2)
  mpz_class whole;
  mpz_fdiv_q(whole.get_mpz_t(), r.get_num_mpz_t(), r.get_den_mpz_t());
  if (whole % 2 != 0) whole -= 1;
  r -= whole;
  CosineSum s;
  s.cosines[r] = 1;
  return s;
}

double CosineSum::value() const {
  double v = rational.get_d();
  for (const auto& [r, c] : cosines) v += c.get_d() * 2 * std::cos(M_PI * r.get_d());
  return v;
}

long CosineSum::denominators_lcm() const {
  long m = 1;
  for (const auto& [r, c] : cosines) m = std::lcm(m, r.get_den().get_si());
  return m;
}

uint64_t CosineSum::residue(const ResidueMap& residue_of, uint64_t zeta, long M) const {
  const uint64_t prime = residue_of.prime();
  uint64_t v = residue_of(rational);
  const uint64_t order = 2 * static_cast<uint64_t>(M);
  for (const auto& [r, c] : cosines) {
    if (M % r.get_den().get_si() != 0) throw std::invalid_argument("CosineSum::residue: M is not a common denominator");
    // pi r = 2 pi (r M) / (2M): zeta^(rM) + zeta^(-rM), with 0 <= rM < 2M.
    const uint64_t e = static_cast<uint64_t>(r.get_num().get_si() * (M / r.get_den().get_si())) % order;
    const uint64_t z = power_modulo(zeta, e, prime), w = power_modulo(zeta, (order - e) % order, prime);
    const uint64_t term = multiply_modulo(residue_of(c), (z + w) % prime, prime);
    v = (v + term) % prime;
  }
  return v;
}

CosineSum CosineSum::operator-() const {
  CosineSum s = *this;
  s *= -1;
  return s;
}

CosineSum& CosineSum::operator+=(const CosineSum& o) {
  rational += o.rational;
  for (const auto& [r, c] : o.cosines) {
    mpq_class& x = cosines[r];
    x += c;
    if (x == 0) cosines.erase(r);
  }
  return *this;
}

CosineSum& CosineSum::operator*=(const mpq_class& x) {
  rational *= x;
  if (x == 0) cosines.clear();
  for (auto& [r, c] : cosines) c *= x;
  return *this;
}

PiecewisePolynomial PiecewisePolynomial::from_algebraic(std::array<std::vector<CosineSum>, 2> pieces) {
  PiecewisePolynomial p;
  for (int h = 0; h < 2; ++h) {
    if (pieces[h].empty()) pieces[h].push_back(CosineSum(0));
    for (const auto& x : pieces[h]) p.pieces[h].push_back(x.value());
  }
  p.algebraic = std::move(pieces);
  return p;
}

uint64_t PiecewisePolynomial::residue(const mpq_class& u, const ResidueMap& residue_of, uint64_t zeta, long M) const {
  const uint64_t prime = residue_of.prime();
  const int h = u < mpq_class(1, 2) ? 0 : 1;
  const uint64_t x = residue_of(u);
  uint64_t v = 0;
  if (exact) {
    const auto& c = (*exact)[h];
    for (size_t i = c.size(); i-- > 0;) v = (multiply_modulo(v, x, prime) + residue_of(c[i])) % prime;
  } else if (algebraic) {
    const auto& c = (*algebraic)[h];
    for (size_t i = c.size(); i-- > 0;) v = (multiply_modulo(v, x, prime) + c[i].residue(residue_of, zeta, M)) % prime;
  } else {
    throw std::logic_error("PiecewisePolynomial::residue: floating-point data have no residue");
  }
  return v;
}

bool GluingData::algebraic() const {
  for (const auto& e : edges)
    if (e)
      for (const PiecewisePolynomial* p : {&e->a, &e->b, &e->c})
        if (!p->exact && !p->algebraic) return false;
  return true;
}

long GluingData::cosine_denominators_lcm() const {
  long m = 1;
  for (const auto& e : edges)
    if (e)
      for (const PiecewisePolynomial* p : {&e->a, &e->b, &e->c})
        if (p->algebraic)
          for (const auto& piece : *p->algebraic)
            for (const auto& x : piece) m = std::lcm(m, x.denominators_lcm());
  return m;
}

}  // namespace knotwork
