#pragma once
#include <Eigen/Core>
#include <vector>

#include "basis/tensor/tensor_patch.hpp"
#include "solver/geometry_map.hpp"

namespace knotwork {

// The NURBS geometry of a TensorDiscretization, cell by cell through its own extraction.
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

 private:
  int pu_, pv_, nu_, elements_u_;
  std::vector<int> spans_u_, spans_v_;
  std::vector<Eigen::MatrixXd> cu_, cv_;
  Eigen::MatrixX3d net_;
};

}  // namespace knotwork
