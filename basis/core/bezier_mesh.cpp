#include "basis/core/bezier_mesh.hpp"
#include "basis/core/pooled_extractions.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <map>
#include <stdexcept>
#include <string_view>

namespace knotwork {

// The cells are a large share of a big tensor mesh's memory (4096^2 cells: 1.5 GB at 88 bytes).
static_assert(sizeof(BezierCell) <= 88, "BezierCell grew beyond 88 bytes: pack it or measure the memory it costs");

int BezierMesh::add_extraction(Eigen::MatrixXd matrix) {
  pool_.push_back(std::move(matrix));
  return static_cast<int>(pool_.size()) - 1;
}

size_t PooledExtractions::hash(const Eigen::MatrixXd& matrix) {
  return std::hash<std::string_view>()(
      std::string_view(reinterpret_cast<const char*>(matrix.data()), sizeof(double) * matrix.size()));
}

int PooledExtractions::add(Eigen::MatrixXd matrix, size_t hash) {
  for (auto [it, end] = ids_.equal_range(hash); it != end; ++it) {
    const Eigen::MatrixXd& kept = mesh_.pooled_extraction(it->second);
    if (kept.rows() == matrix.rows() && kept.cols() == matrix.cols() &&
        std::memcmp(kept.data(), matrix.data(), sizeof(double) * matrix.size()) == 0)
      return it->second;
  }
  const int id = mesh_.add_extraction(std::move(matrix));
  ids_.emplace(hash, id);
  return id;
}

void BezierMesh::add_cell(const BezierCell& cell, std::span<const int> functions,
                          int extraction) {
  const Eigen::MatrixXd& C = pool_.at(extraction);
  if (C.rows() != static_cast<Eigen::Index>(functions.size()) || C.cols() != cell.num_bernstein())
    throw std::logic_error("BezierMesh::add_cell: extraction matrix size does not match");
  if ((cell.dimension == 2) != (cell.degree_w == 0) || (cell.dimension != 2 && cell.dimension != 3))
    throw std::logic_error("BezierMesh::add_cell: a cell is a quadrilateral (degree_w = 0) or a hexahedron");
  if (!cells_.empty() && cell.dimension != cells_.front().dimension)
    throw std::logic_error("BezierMesh::add_cell: quadrilaterals and hexahedra in one mesh");
  cells_.push_back(cell);
  extraction_of_cell_.push_back(extraction);
  // Offsets are ints (half the index memory): refuse, rather than wrap, beyond 2^31 ids.
  if (ids_.size() + functions.size() > static_cast<size_t>(std::numeric_limits<int>::max()))
    throw std::length_error("BezierMesh: more than 2^31 - 1 (cell, function) pairs; the mesh is too large");
  ids_.insert(ids_.end(), functions.begin(), functions.end());
  offsets_.push_back(static_cast<int>(ids_.size()));
  max_active_ = std::max(max_active_, static_cast<int>(functions.size()));
  max_degree_ = std::max({max_degree_, cell.degree_u, cell.degree_v, int{cell.degree_w}});
}

void rational_cell_extraction(const BezierMesh& mesh, int c, Eigen::VectorXd& wb,
                              Eigen::MatrixXd& C_hat) {
  const Eigen::MatrixXd& C = mesh.extraction(c);
  if (!mesh.is_rational()) {
    wb.setOnes(C.cols());
    C_hat = C;
    return;
  }
  const auto ids = mesh.functions(c);
  thread_local Eigen::VectorXd w;
  w.resize(static_cast<Eigen::Index>(ids.size()));
  for (size_t i = 0; i < ids.size(); ++i) w[i] = mesh.weights()[ids[i]];
  wb.noalias() = C.transpose() * w;
  C_hat.noalias() = w.asDiagonal() * C * wb.cwiseInverse().asDiagonal();
}

std::vector<CellInterface> interfaces_from_parameter_boxes(const BezierMesh& mesh) {
  if (mesh.num_cells() > 0 && mesh.cell(0).dimension == 3) return face_interfaces_from_parameter_boxes(mesh);
  struct End {
    double from, to;
    int cell;
  };
  // Per line position: cells ending there (their high side) and cells starting there.
  std::map<double, std::vector<End>> vert_low, vert_high, hor_low, hor_high;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& b = mesh.cell(c);
    if (b.boundary[kSideRight] < 0) vert_low[b.u1].push_back({b.v0, b.v1, c});
    if (b.boundary[kSideLeft] < 0) vert_high[b.u0].push_back({b.v0, b.v1, c});
    if (b.boundary[kSideTop] < 0) hor_low[b.v1].push_back({b.u0, b.u1, c});
    if (b.boundary[kSideBottom] < 0) hor_high[b.v0].push_back({b.u0, b.u1, c});
  }
  std::vector<CellInterface> out;
  auto match = [&](std::map<double, std::vector<End>>& low, std::map<double, std::vector<End>>& high, bool vertical) {
    for (auto& [at, lows] : low) {
      auto& highs = high[at];
      auto by_from = [](const End& a, const End& b) { return a.from < b.from; };
      std::sort(lows.begin(), lows.end(), by_from);
      std::sort(highs.begin(), highs.end(), by_from);
      size_t i = 0, j = 0;
      while (i < lows.size() && j < highs.size()) {
        const double from = std::max(lows[i].from, highs[j].from), to = std::min(lows[i].to, highs[j].to);
        if (to > from) {
          const End& a = lows[i];
          const End& b = highs[j];
          // In each cell's reference coordinate along the side.
          out.push_back({a.cell, vertical ? kSideRight : kSideTop, (from - a.from) / (a.to - a.from),
                         (to - a.from) / (a.to - a.from), b.cell, vertical ? kSideLeft : kSideBottom,
                         (from - b.from) / (b.to - b.from), (to - b.from) / (b.to - b.from)});
        }
        if (lows[i].to < highs[j].to)
          ++i;
        else
          ++j;
      }
    }
  };
  match(vert_low, vert_high, true);
  match(hor_low, hor_high, false);
  return out;
}

}  // namespace knotwork
