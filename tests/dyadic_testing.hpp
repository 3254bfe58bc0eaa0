#pragma once
// Level-0 dyadic knots on [0, 1] with equal elements and simple knots (tests of THB and LR).
#include <vector>

#include "basis/core/dyadic_knots.hpp"

namespace knotwork::testing {

inline DyadicKnots uniform_knots(int p, int elements) {
  std::vector<double> breaks;
  for (int e = 0; e <= elements; ++e) breaks.push_back(double(e) / elements);
  return DyadicKnots(p, breaks, std::vector<int>(elements - 1, 1));
}

}  // namespace knotwork::testing
