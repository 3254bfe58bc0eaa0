#pragma once
#include <gmpxx.h>

#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "basis/core/copy_reset_cache.hpp"
#include "basis/tmesh/rectangular_partition.hpp"

namespace knotwork {

// LR B-splines (Dokken, Lyche, Pettersen 2013), as far as knotwork needs them: to build
// LR-meshes on which they are linearly dependent (and show that the PT-spline basis of the
// same T-mesh is not), and as the local B-splines of the minimal PT-spline extension
// (pt_minimal_extension.cpp). Inserted meshlines are simple knots; boundary knots have
// multiplicity m+1 (resp. n+1), the C^0 lines of the initial tensor mesh m (resp. n).
struct LrBSpline {
  std::vector<mpq_class> x, y;  // m + 2 and n + 2 local knots
  mpq_class weight = 1;         // the weights make the LR B-splines a partition of unity
};

class LrMesh {
 public:
  // The tensor mesh of the coordinate lists and its tensor-product B-splines. The lines of
  // `c0` must be among the interior coordinates (std::invalid_argument otherwise).
  LrMesh(const std::vector<mpq_class>& xs, const std::vector<mpq_class>& ys, int m, int n, const C0Lines& c0 = {});

  // Inserts a meshline (merged with the collinear meshlines it touches), then splits every
  // B-spline whose support a meshline traverses without being one of its knot lines, until
  // none is left (the LR refinement). Throws std::invalid_argument if the merged meshline
  // traverses the support of no B-spline (the result would not be an LR-mesh) or leaves the
  // rectangle.
  void insert(const AxisSegment& segment);
  // The same, but returns false (and leaves the mesh as it was) instead of throwing when the
  // merged meshline traverses no support.
  bool try_insert(const AxisSegment& segment);
  // Whether a meshline (or the boundary) passes through the point `along` of the line
  // x = at (vertical) or y = at.
  bool has_line_through(bool vertical, const mpq_class& at, const mpq_class& along) const;

  int m() const { return m_; }
  int n() const { return n_; }
  const std::vector<LrBSpline>& splines() const;
  const std::vector<AxisSegment>& inserted() const { return inserted_; }
  // The T-mesh: the tensor cells cut by the inserted meshlines.
  std::vector<RationalBox> cells() const;

  // A B-spline's local knots in x and in y (the index's payload; splines() lists them with weights).
  using Knots = std::pair<std::vector<mpq_class>, std::vector<mpq_class>>;

 private:
  bool traverses(bool vertical, const mpq_class& at, const mpq_class& from, const mpq_class& to) const;
  // Splits the B-splines of `work` (and their pieces) until no meshline traverses a support.
  void refine(std::vector<Knots> work);

  void index_add(const Knots& k);
  void index_remove(const Knots& k);
  int m_, n_;
  std::vector<mpq_class> xs_, ys_;
  // Where the B-splines are, so that a meshline meets only those near it: their supports in
  // the one R-tree (basis/core/box_index.hpp), built on first use; a copy of the mesh builds its
  // own.
  struct SupportIndex;
  mutable CopyResetCache<SupportIndex> index_;
  SupportIndex& index() const;
  std::map<mpq_class, std::vector<std::pair<mpq_class, mpq_class>>> lines_[2];  // [vertical]: position -> intervals
  std::map<Knots, mpq_class> splines_;  // knots -> weight
  // splines() lists splines_ lazily; the lock makes concurrent const calls safe. Copies
  // share the lock, which only serializes.
  mutable std::vector<LrBSpline> listed_;
  mutable bool listed_stale_ = true;
  mutable std::shared_ptr<std::mutex> listed_lock_ = std::make_shared<std::mutex>();
  std::vector<AxisSegment> inserted_;
};

// The B-spline with local knots t as a combination of the B-splines of the knot vector `fine`
// (which must contain t as a multiset, between t's ends): (index of the first knot of the
// fine B-spline in `fine`, coefficient), by knot insertion. Throws std::invalid_argument when
// t is not in `fine`.
std::vector<std::pair<int, mpq_class>> refine_bspline(const std::vector<mpq_class>& t,
                                                      const std::vector<mpq_class>& fine);

}  // namespace knotwork
