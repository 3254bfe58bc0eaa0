#pragma once
#include <Eigen/Core>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "basis/tensor/tensor_patch.hpp"
#include "basis/core/geometry_map.hpp"

namespace knotwork {

// The NURBS geometry of a TensorDiscretization. At quadrature points (the hot path) it
// evaluates the patch as given, of its own (low) degree, one direction at a time; elsewhere
// (arbitrary points, Bezier cells, second derivatives) through the Bezier extraction of the
// geometry refined onto the space's elements. The tests hold the two routes to each other.
class NurbsGeometryMap final : public GeometryMap {
 public:
  explicit NurbsGeometryMap(const TensorDiscretization& d);
  void evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const override;
  void evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                GeometryAtPoints& out) const override;
  BezierGeometryCell bezier_cell(int cell) const override;
  bool second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                          Eigen::MatrixXd& out) const override;
  // Homogeneous Bezier control points (w x, w y, w) of a cell, one row per Bernstein.
  void homogeneous_bezier(int cell, Eigen::MatrixX3d& out) const;
  // evaluate_at_rule on element (eu, ev) of the whole space, whether or not this map's mesh (a
  // part) holds it: it reads only the patch as given.
  void evaluate_element_at_rule(int eu, int ev, int nu, int nv, GeometryAtPoints& out) const;

 private:
  int pu_, pv_, nu_, elements_u_, first_row_, net_first_row_;
  std::vector<int> spans_u_, spans_v_;
  std::vector<Eigen::MatrixXd> cu_, cv_;
  Eigen::MatrixX3d net_;
  // The patch as given: its bases, homogeneous net (w x, w y, w) numbered i + n j, and per
  // element of the space the patch's span and the element's parameter interval.
  BSplineBasis1D patch_u_, patch_v_;
  Eigen::MatrixX3d patch_net_;
  struct Interval {
    int span;
    double from, length;
  };
  std::vector<Interval> intervals_u_, intervals_v_;
  // The patch's B-splines at an n-point Gauss rule of every element, per direction: made on
  // first use of a rule (thread-safe) and kept; each thread remembers its last lookup.
  struct RuleTables {
    std::vector<Eigen::MatrixXd> value, derivative;  // per element: points x (degree + 1)
  };
  const RuleTables& tables(bool along_u, int n) const;
  mutable std::mutex mutex_;
  mutable std::map<std::pair<bool, int>, std::unique_ptr<RuleTables>> tables_;
  unsigned long serial_;
};

}  // namespace knotwork
