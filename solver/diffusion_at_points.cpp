#include "solver/diffusion_at_points.hpp"

#include <stdexcept>

namespace knotwork {

DiffusionAtPoints::DiffusionAtPoints(const std::vector<Expression>& diffusion) {
  for (const Expression& e : diffusion) entries_.emplace_back(e);
}

Eigen::Matrix2d DiffusionAtPoints::operator()(double x, double y) {
  if (entries_.empty()) return Eigen::Matrix2d::Identity();
  if (entries_.size() == 1) return entries_[0](x, y) * Eigen::Matrix2d::Identity();
  const double a12 = entries_[1](x, y);
  Eigen::Matrix2d a;
  a << entries_[0](x, y), a12, a12, entries_[2](x, y);
  return a;
}

Eigen::Matrix3d DiffusionAtPoints::operator()(double x, double y, double z) {
  if (entries_.empty()) return Eigen::Matrix3d::Identity();
  if (entries_.size() == 1) return entries_[0](x, y, z) * Eigen::Matrix3d::Identity();
  if (entries_.size() != 6) throw std::logic_error("DiffusionAtPoints: a planar coefficient matrix evaluated in space");
  double a[6];
  for (int i = 0; i < 6; ++i) a[i] = entries_[i](x, y, z);
  Eigen::Matrix3d m;
  m << a[0], a[1], a[2], a[1], a[3], a[4], a[2], a[4], a[5];
  return m;
}

}  // namespace knotwork
