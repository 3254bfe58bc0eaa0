#pragma once
#include <gmpxx.h>

#include <map>
#include <vector>

#include "basis/rectangular_partition.hpp"

namespace knotwork {

// LR B-splines (Dokken, Lyche, Pettersen 2013), only as far as knotwork needs them: to build
// LR-meshes on which they are linearly dependent and show that the PT-spline basis of the
// same T-mesh is not. Interior knots have multiplicity 1, boundary knots m+1 (resp. n+1).
struct LrBSpline {
  std::vector<mpq_class> x, y;  // m + 2 and n + 2 local knots
  mpq_class weight = 1;         // the weights make the LR B-splines a partition of unity
};

class LrMesh {
 public:
  // The tensor mesh of the coordinate lists and its tensor-product B-splines.
  LrMesh(const std::vector<mpq_class>& xs, const std::vector<mpq_class>& ys, int m, int n);

  // Inserts a meshline (merged with the collinear meshlines it touches), then splits every
  // B-spline whose support a meshline traverses without being one of its knot lines, until
  // none is left (the LR refinement). Throws std::invalid_argument if the merged meshline
  // traverses the support of no B-spline (the result would not be an LR-mesh) or leaves the
  // rectangle.
  void insert(const AxisSegment& segment);

  int m() const { return m_; }
  int n() const { return n_; }
  const std::vector<LrBSpline>& splines() const { return splines_; }
  const std::vector<AxisSegment>& inserted() const { return inserted_; }
  // The T-mesh: the tensor cells cut by the inserted meshlines.
  std::vector<RationalBox> cells() const;

 private:
  bool traverses(bool vertical, const mpq_class& at, const mpq_class& from, const mpq_class& to) const;
  void refine();

  int m_, n_;
  std::vector<mpq_class> xs_, ys_;
  std::map<mpq_class, std::vector<std::pair<mpq_class, mpq_class>>> lines_[2];  // [vertical]: position -> intervals
  std::vector<LrBSpline> splines_;
  std::vector<AxisSegment> inserted_;
};

}  // namespace knotwork
