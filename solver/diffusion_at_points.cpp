#include "solver/diffusion_at_points.hpp"

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

}  // namespace knotwork
