#include "basis/knot_segments/collection_on_partition.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <stdexcept>
#include <string>

#include "basis/tmesh/partition_topology.hpp"

namespace knotwork {

namespace {

using Box = std::array<double, 4>;

std::vector<Box> double_cells(const RectangularPartition& p) {
  std::vector<Box> out;
  for (const auto& c : p.cells()) out.push_back({c.x0.get_d(), c.y0.get_d(), c.x1.get_d(), c.y1.get_d()});
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

bool same_cells(const RectangularPartition& a, const RectangularPartition& b) {
  return double_cells(a) == double_cells(b);
}

CollectionOnPartition collection_on_partition(const RectangularPartition& partition, int dx, int dy) {
  if (dx < 1 || dy < 1) throw std::invalid_argument("degrees must be >= 1");
  const PartitionTopology topo = partition_topology(partition);
  // Every coordinate must survive the conversion to double (e.g. 1/3 does, up to rounding,
  // but two distinct rationals must not collapse to one double).
  std::map<double, mpq_class> seen;
  for (const auto& v : topo.vertices)
    for (const mpq_class* q : {&v.x, &v.y}) {
      const auto [it, fresh] = seen.emplace(q->get_d(), *q);
      if (!fresh && it->second != *q)
        throw std::invalid_argument("coordinates " + it->second.get_str() + " and " + q->get_str() +
                                    " are the same double; the collection needs them apart");
    }
  mpq_class x0 = topo.vertices.front().x, x1 = x0, y0 = topo.vertices.front().y, y1 = y0;
  for (const auto& v : topo.vertices) {
    x0 = std::min(x0, v.x), x1 = std::max(x1, v.x);
    y0 = std::min(y0, v.y), y1 = std::max(y1, v.y);
  }
  std::vector<double> bx{x0.get_d()}, by{y0.get_d()};
  struct Knot {
    KnotInsertion segment;
    std::vector<int> rests_on;  // knots (indices in `knots`) its interior ends lie on
  };
  std::vector<Knot> knots;
  std::map<int, std::vector<int>> through;  // vertex -> knots having it as an interior point
  std::vector<int> knot_index(topo.knots.size(), -1);
  for (size_t k = 0; k < topo.knots.size(); ++k) {
    const auto& K = topo.knots[k];
    if (K.kind == PartitionTopology::KnotKind::kLine) {
      (K.vertical ? bx : by).push_back(K.position.get_d());
      continue;
    }
    const auto& a = topo.vertices[K.vertices.front()];
    const auto& b = topo.vertices[K.vertices.back()];
    KnotInsertion s;
    s.vertical = K.vertical;
    s.position = K.position.get_d();
    s.from = (K.vertical ? a.y : a.x).get_d();
    s.to = (K.vertical ? b.y : b.x).get_d();
    knot_index[k] = static_cast<int>(knots.size());
    knots.push_back({s, {}});
  }
  for (size_t k = 0; k < topo.knots.size(); ++k)
    for (size_t i = 1; i + 1 < topo.knots[k].vertices.size(); ++i) through[topo.knots[k].vertices[i]].push_back(k);
  for (size_t k = 0; k < topo.knots.size(); ++k) {
    if (knot_index[k] < 0) continue;
    for (int end : {topo.knots[k].vertices.front(), topo.knots[k].vertices.back()})
      for (int other : through[end])
        if (knot_index[other] >= 0 && topo.knots[other].vertical != topo.knots[k].vertical)
          knots[knot_index[k]].rests_on.push_back(knot_index[other]);
  }
  bx.push_back(x1.get_d());
  by.push_back(y1.get_d());
  std::sort(bx.begin(), bx.end());
  std::sort(by.begin(), by.end());
  const SemiRegularCollection base = SemiRegularCollection::tensor_product(dx, dy, bx, by);

  auto length = [&](int k) { return knots[k].segment.to - knots[k].segment.from; };
  std::vector<int> longest(knots.size());
  for (size_t k = 0; k < knots.size(); ++k) longest[k] = static_cast<int>(k);
  std::stable_sort(longest.begin(), longest.end(), [&](int a, int b) { return length(a) > length(b); });
  std::vector<int> shortest(longest.rbegin(), longest.rend());
  // Ready knots (all they rest on inserted) longest first; a cycle is broken by the longest.
  std::vector<int> supported;
  std::vector<bool> done(knots.size(), false);
  while (supported.size() < knots.size()) {
    int pick = -1;
    for (int k : longest) {
      if (done[k]) continue;
      bool ready = true;
      for (int o : knots[k].rests_on) ready = ready && done[o];
      if (ready) { pick = k; break; }
    }
    if (pick < 0)
      for (int k : longest)
        if (!done[k]) { pick = k; break; }
    done[pick] = true;
    supported.push_back(pick);
  }

  std::optional<CollectionOnPartition> best;
  std::string failure;
  int best_extended = 0;
  const std::pair<const char*, const std::vector<int>*> orders[] = {
      {"supporting knots first", &supported}, {"longest first", &longest}, {"shortest first", &shortest}};
  for (const auto& [name, order] : orders) {
    CollectionOnPartition attempt{base, false, {}, name};
    int extended = 0;
    try {
      for (int k : *order) {
        attempt.insertions.push_back(attempt.collection.insert(knots[k].segment));
        extended += attempt.insertions.back().extended;
      }
    } catch (const std::runtime_error& e) {  // this order dead-ends; another may not
      failure = e.what();
      continue;
    }
    attempt.reached = same_cells(attempt.collection.partition(), partition);
    if (attempt.reached) return attempt;
    if (!best || extended < best_extended) {
      best_extended = extended;
      best = std::move(attempt);
    }
  }
  if (!best) throw std::runtime_error("no insertion order gives a semi-regular collection: " + failure);
  return std::move(*best);
}

}  // namespace knotwork
