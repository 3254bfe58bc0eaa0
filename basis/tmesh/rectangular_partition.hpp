#pragma once
#include <gmpxx.h>

#include <string>
#include <utility>
#include <vector>

namespace knotwork {

// An axis-aligned cell with exact rational corners: the dimension of a spline space over a
// T-mesh can change with the coordinates (dimensional instability), so coordinates stay
// exact wherever the computation is exact.
struct RationalBox {
  mpq_class x0, y0, x1, y1;
};

// Lines x = const and y = const of a partition across which a spline space is only C^0 (for
// instance the fold of a one-patch L-shape geometry): each must run from boundary to boundary.
struct C0Lines {
  std::vector<mpq_class> x, y;
  bool empty() const { return x.empty() && y.empty(); }
};

// Parses "14/9", "-3", "0.25" (a decimal is read exactly: 0.25 = 1/4) into a rational.
// Throws std::invalid_argument.
mpq_class parse_rational(const std::string& text);

// A rectangle tiled by axis-aligned cells (a T-mesh, or any rectangular partition).
class RectangularPartition {
 public:
  // Validates: positive areas, no two cells overlapping, and together exactly a rectangle.
  // Throws std::invalid_argument naming the offending cells (0-based indices).
  explicit RectangularPartition(std::vector<RationalBox> cells);

  const std::vector<RationalBox>& cells() const { return cells_; }
  // The cells, in the order given, without a copy; the partition is left empty.
  std::vector<RationalBox> take_cells() && {
    edges_.clear();
    return std::move(cells_);
  }
  int num_cells() const { return static_cast<int>(cells_.size()); }

  // A maximal common segment of two cells' boundaries. Vertical: first is left of
  // second, the segment is x = position, from <= y <= to. Horizontal: first below second.
  struct SharedEdge {
    int first, second;
    bool vertical;
    mpq_class position, from, to;
  };
  const std::vector<SharedEdge>& shared_edges() const { return edges_; }

 private:
  std::vector<RationalBox> cells_;
  std::vector<SharedEdge> edges_;
};

// A T-mesh given as a base grid and inserted segments: the tensor cells of the coordinate
// lists, then each segment (x = position from y = from to y = to when vertical) splits the
// cells it crosses. All segments cut at once, so their order does not matter: each must end
// on a cell edge or on another segment (not inside a cell) and lie inside the rectangle.
// Throws std::invalid_argument naming the segment (0-based) and the cell.
struct AxisSegment {
  bool vertical = true;
  mpq_class position, from, to;
};
std::vector<RationalBox> grid_cells(const std::vector<mpq_class>& xs, const std::vector<mpq_class>& ys);
// The open knot vector on [a, b] of degree p: a and b repeated p + 1 times around `interior`
// (which carries its own multiplicities).
std::vector<mpq_class> open_knot_vector(const std::vector<mpq_class>& interior, const mpq_class& a, const mpq_class& b,
                                        int p);
std::vector<RationalBox> insert_segments(std::vector<RationalBox> cells, const std::vector<AxisSegment>& segments);

}  // namespace knotwork
