#pragma once
#include <Eigen/SparseCore>
#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "basis/core/copy_reset_cache.hpp"
#include "basis/core/bezier_mesh.hpp"
#include "basis/core/bspline_basis.hpp"
#include "basis/tmesh/rectangular_partition.hpp"

namespace knotwork {

// One tensor-product B-spline with its own local knot vectors (Weller): dx+2 values in x,
// dy+2 in y. B(x, y) = N(x_knots | x) N(y_knots | y).
struct LocalBSpline {
  std::vector<double> x, y;
  bool operator==(const LocalBSpline& o) const { return x == o.x && y == o.y; }
  bool operator<(const LocalBSpline& o) const { return x != o.x ? x < o.x : y < o.y; }
};

// A knot segment (or ray, or line) to insert: x = position for vertical ones, from <= y <= to
// (horizontal: y = position, from <= x <= to), with a multiplicity in [1, degree+1].
struct KnotInsertion {
  bool vertical = true;
  double position = 0, from = 0, to = 0;
  int multiplicity = 1;
};

// True when no local knot vector repeats a value strictly inside it: every interior knot
// of the collection has multiplicity 1 (the hypothesis of Weller's Prop. 4.2).
bool interior_knots_simple(const std::vector<LocalBSpline>& splines);

// What a refinement did: the segment as inserted after any extension.
struct InsertionReport {
  KnotInsertion requested, inserted;
  bool extended = false;
  int splits = 0;  // B-splines split
};

// Why a cell is not semi-regular (Def. 3.3), or which B-spline is degenerate (Def. 3.1).
struct Violation {
  int cell = -1;          // index in partition() (-1 for collection-wide problems)
  std::string reason;     // e.g. "cell [0.25,0.5]x[0.5,0.75]: B-splines 12 and 17 share ..."
};

// A classical tensor-product spline: coefficients(i, j) multiplies N_i(x) N_j(y).
struct TensorProductSpline {
  BSplineBasis1D basis_x, basis_y;
  Eigen::MatrixXd coefficients;
  double operator()(double x, double y) const;
};

// A semi-regular collection of tensor-product B-splines over a rectangle (Weller 1994):
// local refinement by knot segments that keeps a linearly independent partition of unity.
class SemiRegularCollection {
 public:
  // All tensor-product B-splines of bi-degree (dx, dy) on open knot vectors: the starting
  // point of refinement. Interior breakpoint i has multiplicity mult_x[i-1] (default 1).
  static SemiRegularCollection tensor_product(int dx, int dy, const std::vector<double>& breaks_x,
                                              const std::vector<double>& breaks_y,
                                              const std::vector<int>& mult_x = {},
                                              const std::vector<int>& mult_y = {});

  // A collection given explicitly (e.g. read from a file), to be checked with violations().
  // The domain is the bounding box of the supports. Throws std::invalid_argument for knot
  // vectors of the wrong length or not non-decreasing.
  static SemiRegularCollection from_splines(int dx, int dy, std::vector<LocalBSpline> splines);

  int degree_x() const { return dx_; }
  int degree_y() const { return dy_; }
  // In lexicographic order of their knot vectors (the order coefficients refer to).
  const std::vector<LocalBSpline>& splines() const;
  int size() const { return static_cast<int>(set_.size()); }
  // Bounding box of the supports: x0, y0, x1, y1.
  std::array<double, 4> domain() const { return {x0_, y0_, x1_, y1_}; }

  // How insert() looks for an extension. A knot step is the next knot value, along the line,
  // of a B-spline the whole line crosses (an end between two such values splits the same
  // B-splines as an end at the nearer one). Every candidate is split and checked; the
  // first that refines and stays semi-regular is kept, at worst a full knot line.
  //  kMinimal: by increasing total number of steps (balanced and one-sided splits of each
  //    total): the shortest, but long extensions take many attempts.
  //  kDirected: after a failed attempt, the end nearer the cell that failed moves one step
  //    (both ends when nothing was split); at most one attempt per step.
  //  kGalloping: as kDirected, but an end that has to move again moves twice as far as last
  //    time, and the last jump is bisected back; a logarithmic number of attempts on long
  //    extensions. The default (measured: docs/ADAPTIVITY.md "Choosing the defaults").
  enum class Extension { kGalloping, kDirected, kMinimal };
  void set_extension(Extension e) { extension_ = e; }
  Extension extension() const { return extension_; }

  // Inserts the segment by splitting every B-spline it crosses completely (and repeating
  // until no B-spline is crossed by a knot it does not use). If the result would not be
  // non-degenerate and semi-regular, the segment is extended (extension()) until it is. A
  // segment the mesh already has is a no-op (splits = 0). Only the region whose B-splines
  // changed is re-checked, and an R-tree of the supports finds the B-splines involved, so the
  // cost grows with the refinement, not with the collection (the collection must be
  // semi-regular before). Throws std::invalid_argument for a
  // segment outside the domain or of zero length, a multiplicity outside [1, degree+1], or
  // one that overlaps an existing knot of another multiplicity.
  InsertionReport insert(const KnotInsertion& segment);

  // Refines the given cells of partition() (indices): a vertical and a horizontal segment
  // through each cell's middle, spanning the cell, extended where needed.
  std::vector<InsertionReport> refine_cells(const std::vector<int>& cells);
  // Refines each listed cell by halving it in the given direction only (kSplitX: a vertical
  // segment through the middle; kSplitY: a horizontal one; kSplitBoth: both).
  enum Split { kSplitX = 1, kSplitY = 2, kSplitBoth = 3 };
  std::vector<InsertionReport> refine_cells(const std::vector<int>& cells, const std::vector<Split>& split);

  // Multiplicity of the mesh's knot at `position` over [from, to] (0 if it is not a knot
  // there all along): what the inserted segments and the starting grid say.
  int knot_multiplicity(bool vertical, double position, double from, double to) const {
    return covering_multiplicity(vertical, position, from, to);
  }

  // The partition induced by the B-splines (cells in row order of their lower-left corners).
  RectangularPartition partition() const;
  // Def. 3.1 and Def. 3.3 checked cell by cell; empty when the collection is semi-regular.
  std::vector<Violation> violations() const;

  // Value of sum_k coefficients[k] B_k at (x, y) by Weller's evaluation (eqs. 3.4-3.5): on the
  // point's cell, d+1 univariate de Boor runs over the vectors Y^(i), then one over X (or
  // the transpose, case (b)). Throws if the point is outside or the cell is not regular.
  double evaluate(std::span<const double> coefficients, double x, double y) const;

  // The same spline as a classical tensor-product B-spline (Sec. 2): every knot extended to
  // a knot line with its maximal multiplicity, each B_k rewritten there by knot insertion.
  // For export to tools that know only tensor-product splines.
  TensorProductSpline to_tensor_product(std::span<const double> coefficients) const;

  // Every B-spline's polynomial piece on every cell of the partition, as Bernstein
  // coefficients: the BezierMesh the solver and the checks read. Boundary ids 0..3 as for
  // a patch (bottom, right, top, left).
  BezierMesh bezier_mesh() const;

  // Keep (on) or not the splits the insertions make from now on (those of attempts that were
  // undone are dropped), for prolongation_from.
  void record_splits(bool on = true);
  // The prolongation from `coarse` (this collection when record_splits was called) to this
  // one: P (this collection's B-splines x coarse's, in splines() order) with coarse B-spline
  // j = sum_i P(i, j) B-spline i. A coarse B-spline kept is itself; a split one is expanded by
  // the knot insertions recorded (B = a B_left + b B_right per split) until its pieces are this
  // collection's. std::logic_error when the splits were not recorded, or a piece is neither
  // split nor kept.
  Eigen::SparseMatrix<double> prolongation_from(const SemiRegularCollection& coarse) const;

 private:
  struct Piece {
    double from, to;
    int multiplicity;
  };
  // What one insertion attempt changed, to check it locally and to undo it.
  // A B-spline split at `at` across x (vertical) or y, into the halves the knot inserted there
  // makes (recorded for prolongation_from).
  struct SplitRecord {
    LocalBSpline from;
    bool vertical;
    double at;
  };
  struct Change {
    std::vector<LocalBSpline> removed;
    std::set<const LocalBSpline*> added;  // elements of set_ (nodes do not move)
    std::vector<SplitRecord> splits;      // when recording
  };
  bool recording_ = false;
  std::vector<SplitRecord> splits_;  // of the insertions kept since record_splits
  // The supports of set_'s B-splines in an R-tree, so that an insertion finds the B-splines a
  // line crosses and those near a changed region without scanning all of them. Built on the
  // first insertion, kept up to date by the splits and their undoing; a copy starts without
  // one (it would point into the other collection's set).
  struct SupportIndex;
  int dx_ = 2, dy_ = 2;
  Extension extension_ = Extension::kGalloping;
  // No B-spline jumps over a line (tensor starts, and what insert() builds); an explicit
  // collection that does is refined checking every line, as insert() did before.
  bool stable_ = true;
  std::set<LocalBSpline> set_;
  // splines() lists set_ lazily; the lock makes concurrent const calls safe (the threaded
  // assembly and estimator may reach it). Copies share the lock, which only serializes.
  mutable std::vector<LocalBSpline> cache_;
  mutable bool cache_valid_ = false;
  mutable std::shared_ptr<std::mutex> cache_lock_ = std::make_shared<std::mutex>();
  double x0_ = 0, x1_ = 1, y0_ = 0, y1_ = 1;
  // Every knot line/segment of the mesh so far, per orientation and position.
  std::map<double, std::vector<Piece>> vlines_, hlines_;
  mutable CopyResetCache<SupportIndex> index_;
  SupportIndex& index() const;
  // B-splines whose support meets the closed box x0, y0, x1, y1 (a superset of those whose
  // interior does), in the R-tree's order: nothing downstream depends on it (the splits reach
  // the same B-splines in any order, cells are checked in the partition's order, Def. 3.3
  // sorts), which test_semi_regular's copy test checks against a freshly packed tree.
  std::vector<const LocalBSpline*> meeting(double x0, double y0, double x1, double y1) const;
  void erase_spline(std::set<LocalBSpline>::const_iterator it);
  // The inserted element, or nullptr when the collection has it already.
  const LocalBSpline* insert_spline(const LocalBSpline& b);
  void add_line(const KnotInsertion& s);
  // Largest multiplicity the lines at `position` give on all of [lo, hi] (min over the
  // interval of the max over the pieces covering each point); 0 if some part is uncovered.
  int covering_multiplicity(bool vertical, double position, double lo, double hi) const;
  static int covering_multiplicity(const std::vector<Piece>& pieces, double lo, double hi);
  // Whether `b` crosses the line at `position` (its `pieces`) without using it as often.
  static bool jumps(const LocalBSpline& b, bool vertical, double position, const std::vector<Piece>& pieces);
  // The first line of one direction that `b` jumps over (false if none).
  bool jumped_line(const LocalBSpline& b, bool vertical, double& position) const;
  // Splits B-splines (starting from `start`, those `inserted` crosses) until none is crossed by
  // a line it does not use. With stable_, `start` is checked at the inserted line only.
  void split_until_stable(std::vector<LocalBSpline> start, const KnotInsertion& inserted, Change& change);
  // Def. 3.3 on the cells inside the supports that changed; empty when they are fine.
  // `where` (if given) receives the failing cell x0, y0, x1, y1; with the inserted `segment`,
  // the supports at its ends are checked first.
  std::string local_violation(const Change& change, std::array<double, 4>* where = nullptr,
                              const KnotInsertion* segment = nullptr) const;
  // Def. 3.3 on the cells inside the supports of `splines`.
  std::string violation_in(const std::vector<const LocalBSpline*>& splines, std::array<double, 4>* where) const;
  void undo(const Change& change);
};

}  // namespace knotwork
