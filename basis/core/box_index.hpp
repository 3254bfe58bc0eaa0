#pragma once
// The one spatial index of knotwork: axis-aligned boxes with a payload in Boost.Geometry's
// R-tree (packed bulk load, insert, remove, queries). The knot-segment collections, the LR
// family's elements and the exact LR refinement's supports all use it. Include it only where
// the index is used: Boost.Geometry is a heavy header.
#include <boost/geometry.hpp>  // the R-tree needs the strategies
#include <boost/geometry/index/rtree.hpp>
#include <iterator>
#include <utility>
#include <vector>

namespace knotwork {

// Coordinate: double or an integer type (the LR family's dyadic grid). Payload: a small value
// (an index, a pointer) that, with the box, identifies an entry for remove().
template <class Coordinate, class Payload>
class BoxIndex {
 public:
  using Point = boost::geometry::model::point<Coordinate, 2, boost::geometry::cs::cartesian>;
  using Box = boost::geometry::model::box<Point>;
  using Entry = std::pair<Box, Payload>;

  static Box box(Coordinate x0, Coordinate y0, Coordinate x1, Coordinate y1) { return Box(Point(x0, y0), Point(x1, y1)); }

  BoxIndex() = default;
  // Packed (bulk) load: faster to build and to query than inserting one at a time.
  explicit BoxIndex(const std::vector<Entry>& entries) : tree_(entries.begin(), entries.end()) {}

  void insert(const Box& b, const Payload& p) { tree_.insert(Entry(b, p)); }
  // Removes the entry with this box and payload (true if there was one).
  bool remove(const Box& b, const Payload& p) { return tree_.remove(Entry(b, p)) > 0; }

  // Queries are const and may run from several threads at once (inserts and removes may not).
  // The payloads of the boxes that meet the closed box b (touching counts).
  void intersecting(const Box& b, std::vector<Payload>& out) const {
    std::vector<Entry> found;
    tree_.query(boost::geometry::index::intersects(b), std::back_inserter(found));
    payloads(found, out);
  }
  // The payloads of the boxes inside the closed box b.
  void covered_by(const Box& b, std::vector<Payload>& out) const {
    std::vector<Entry> found;
    tree_.query(boost::geometry::index::covered_by(b), std::back_inserter(found));
    payloads(found, out);
  }
  size_t size() const { return tree_.size(); }

 private:
  static void payloads(const std::vector<Entry>& found, std::vector<Payload>& out) {
    out.clear();
    out.reserve(found.size());
    for (const Entry& e : found) out.push_back(e.second);
  }
  boost::geometry::index::rtree<Entry, boost::geometry::index::linear<16>> tree_;
};

}  // namespace knotwork
