#pragma once
#include <string>
#include <vector>

#include "basis/knot_segments/semi_regular_collection.hpp"

namespace knotwork {

// What `knotwork basis` checks of a knot-segment collection beyond partition of unity and
// rank: semi-regularity (Def. 3.1, 3.3), and, for simple interior knots over a partition,
// the dimension of S(d-1) by brute force and by Weller's Prop. 4.2 (-1 when not counted).
struct CollectionChecks {
  std::vector<std::string> violations;
  long dimension_formula = -1, dimension_bruteforce = -1;
};
// Throws std::length_error when the partition is too large for the brute-force count.
CollectionChecks check_collection(const SemiRegularCollection& collection, bool simple_knots);

// "vertical x = 0.375, y in [0, 0.75]"
std::string describe_insertion(const KnotInsertion& s);

// Every function's local knot vectors as JSON (the format `basis --export` writes and
// [space] collection reads). Throws InputError naming --export when it cannot be written.
void export_collection(const std::string& file, const std::string& source, const SemiRegularCollection& collection);

}  // namespace knotwork
