#pragma once
// LR B-splines (Dokken, Lyche, Pettersen 2013) on a patch's parameter domain, for adaptive
// analysis (Johannessen, Kvamsdal, Dokken 2014): meshlines inserted in batches, every B-spline
// whose support a meshline traverses split by knot insertion until none is, the elements of
// the LR mesh, their Bézier extraction, and the check for linear dependence (which LR meshes
// can have). Coordinates are integers on a dyadic grid 2^40 finer than level 0, so knots are
// exact, hashable and cheap; basis/tmesh/lr_spline is the exact-rational LR mesh of the
// PT-spline studies, far too slow for 10^5 functions.
#include <Eigen/SparseCore>
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/dyadic_knots.hpp"

namespace knotwork {

class DyadicLrMesh {
 public:
  static constexpr int kMaxDegree = 8;
  static constexpr int kGridLevel = 40;
  struct Element {
    std::array<int64_t, 2> from, to;  // grid coordinates along u and v
  };
  struct Function {
    std::array<std::array<int64_t, kMaxDegree + 2>, 2> knots{};  // degree+2 used per direction
    bool operator==(const Function& o) const { return knots == o.knots; }
  };
  struct FunctionHash {
    size_t operator()(const Function& f) const;
  };
  enum class Strategy { kMinimalSpan, kFullSpan, kStructuredMesh };
  struct Segment {
    int direction;  // 0: the line u = at (vertical), 1: v = at
    int64_t at, from, to;
  };

  // The tensor mesh of level 0 and its B-splines.
  DyadicLrMesh(DyadicKnots u, DyadicKnots v);

  // Refines the given elements (indices into elements()) by `strategy`: minimal span halves
  // each element by its two midlines, each as long as the shortest support containing the
  // element; full span makes them as long as all those supports together; structured mesh
  // halves every knot interval of every B-spline whose support contains a marked element.
  // Meshlines that reach a side are extended where needed to keep the B-splines' traces there
  // linearly independent. Returns the number of meshlines inserted. std::invalid_argument when an element is too
  // small to be halved on the grid.
  int refine(const std::vector<int>& elements, Strategy strategy);

  // Inserts meshlines one by one, in the given order (merged with collinear ones they touch),
  // each splitting the B-splines it traverses; with `keep_traces`, then extends what reaches a
  // side as refine() does. std::invalid_argument names the first segment that leaves the
  // domain or (merged) traverses the support of no B-spline: the mesh would not be an LR mesh.
  void insert(const std::vector<Segment>& segments, bool keep_traces = true);
  // Grid coordinate of a parameter value; std::invalid_argument unless it is k / 2^m (m <= 30)
  // of a level-0 element, up to 1e-12 relative (the rounding of decimal input).
  int64_t grid(int direction, double parameter) const;

  const std::vector<Element>& elements() const { return elements_; }
  int num_functions() const { return static_cast<int>(functions_.size()); }
  int degree(int direction) const { return knots_[direction].degree(); }
  double parameter(int direction, int64_t x) const { return knots_[direction].breakpoint(kGridLevel, x); }

  // The B-splines as a BezierMesh, cells in the order of elements(), functions numbered in
  // the order of their knot vectors (which does not depend on the order of insertion).
  BezierMesh bezier_mesh() const;

  // Linear dependence. An element is overloaded when more than (p+1)(q+1) B-splines live on
  // it, a B-spline when all its elements are; only overloaded B-splines can take part in a
  // linear relation (on an element with exactly (p+1)(q+1) of them they are a basis of the
  // polynomials there). The overloaded ones, if any, are then ranked by their Bézier
  // coefficients (dense QR, relative threshold 1e-10), group by group of B-splines that share
  // elements, when no group has more than `max_checked`.
  struct Dependence {
    int overloaded = 0;   // overloaded B-splines (0: independent, proven)
    int dependent = -1;   // their nullity (-1: not ranked, too many)
    int element = -1;     // an element in the support of a linear relation (when dependent > 0)
  };
  // `mesh` is this mesh's bezier_mesh().
  static Dependence dependence(const BezierMesh& mesh, int max_checked = 2000);

  // Keep (on) or not the splits refine() and insert() make from now on, for prolongation_from.
  void record_splits(bool on = true);
  // The prolongation from `coarse` (this mesh when record_splits was called) to this mesh: P
  // (this bezier_mesh()'s functions x coarse's) with coarse function j = sum_i P(i, j) function
  // i. Each coarse B-spline is expanded by the knot insertions the refinement made (B = a B_left
  // + b B_right per split, the weights aside) until its pieces are this mesh's B-splines.
  // std::logic_error when the splits were not recorded, or a piece is not one of them.
  Eigen::SparseMatrix<double> prolongation_from(const DyadicLrMesh& coarse) const;

  // Meshlines added beyond those of the strategy, to keep the boundary traces independent.
  int extended() const { return extended_; }
  // The meshlines inserted so far, in order (grid coordinates).
  const std::vector<Segment>& inserted() const { return inserted_; }
  // The B-splines: knots (grid coordinates) and weights.
  const std::unordered_map<Function, double, FunctionHash>& functions() const { return functions_; }

 private:
  void add_line(const Segment& s);
  // B-spline f with the knot x inserted along direction d: its first and its last p + 2 knots
  // (f = a left + b right, split_weights; the split and its replay make them here).
  std::array<Function, 2> halves(const Function& f, int d, int64_t x) const;
  bool covers(int direction, int64_t at, int64_t from, int64_t to) const;
  // Splits the B-splines that the meshlines traverse, after `added` joined them: only a
  // B-spline whose support one of those meets can need it (the others were split against every
  // older line), so only those are looked at.
  void split_functions(const std::vector<Segment>& added);
  // Splits the elements that the meshlines inserted from inserted_[first_inserted] on cut.
  void split_elements(size_t first_inserted);
  std::vector<Segment> boundary_extensions() const;
  void keep_traces_independent();
  // The functions in the order of their knots, and the ones living on each element (indices
  // into that list); computed on first use after a change.
  struct Incidence {
    std::vector<Function> sorted;
    std::vector<double> weights;  // of the sorted functions
    std::vector<std::vector<int>> on;
  };
  const Incidence& incidence() const;

  std::array<DyadicKnots, 2> knots_;
  std::array<int, 2> p_;
  std::array<int64_t, 2> end_;
  std::array<std::map<int64_t, std::vector<std::pair<int64_t, int64_t>>>, 2> lines_;  // merged intervals
  std::unordered_map<Function, double, FunctionHash> functions_;                   // knots -> weight
  std::vector<Element> elements_;
  std::vector<Segment> inserted_;
  int extended_ = 0;
  mutable std::shared_ptr<const Incidence> incidence_;  // null after a change
  bool recording_ = false;  // record_splits
  // B[from] = a B[left] + b B[right], [left, right] = halves(from, direction, at), in the order made: appending is all
  // that splitting pays (a refinement of the L-shape at p = 3 makes 4e5 splits); the pieces are
  // made again when replayed, which keeps a split at 192 bytes instead of 480.
  struct Split {
    Function from;
    int direction;
    int64_t at;
    double a, b;
  };
  std::vector<Split> splits_;
};

}  // namespace knotwork
