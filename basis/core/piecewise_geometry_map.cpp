#include <algorithm>
#include <stdexcept>

#include "basis/core/geometry_map.hpp"

namespace knotwork {

PiecewiseGeometryMap::PiecewiseGeometryMap(std::vector<std::unique_ptr<GeometryMap>> pieces, std::vector<int> first_cell)
    : pieces_(std::move(pieces)), first_cell_(std::move(first_cell)) {
  if (pieces_.empty() || first_cell_.size() != pieces_.size() + 1)
    throw std::logic_error("PiecewiseGeometryMap: one first cell per piece and the end");
}

std::pair<const GeometryMap*, int> PiecewiseGeometryMap::piece_of(int cell) const {
  const auto it = std::upper_bound(first_cell_.begin(), first_cell_.end(), cell);
  const auto k = static_cast<size_t>(it - first_cell_.begin()) - 1;
  return {pieces_[k].get(), cell - first_cell_[k]};
}

void PiecewiseGeometryMap::evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const {
  const auto [map, c] = piece_of(cell);
  map->evaluate_at_rule(c, nu, nv, out);
}

void PiecewiseGeometryMap::evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                    GeometryAtPoints& out) const {
  const auto [map, c] = piece_of(cell);
  map->evaluate(c, u, v, out);
}

BezierGeometryCell PiecewiseGeometryMap::bezier_cell(int cell) const {
  const auto [map, c] = piece_of(cell);
  return map->bezier_cell(c);
}

bool PiecewiseGeometryMap::second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                              Eigen::MatrixXd& out) const {
  const auto [map, c] = piece_of(cell);
  return map->second_derivatives(c, u, v, out);
}

}  // namespace knotwork
