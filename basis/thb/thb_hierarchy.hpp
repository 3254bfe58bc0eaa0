#pragma once
// Truncated hierarchical B-splines (Giannelli, Jüttler, Speleers 2012) on a dyadic hierarchy
// of one patch's parameter domain: a quadtree of cells over a tensor mesh, refined by halving
// marked leaves in both directions, optionally graded to keep the mesh T-admissible of class m
// (Buffa, Giannelli 2016: a leaf meets THB functions of at most m successive levels).
#include <array>
#include <cstdint>
#include <unordered_set>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/dyadic_knots.hpp"

namespace knotwork {

struct ThbCell {
  int level = 0;
  int64_t i = 0, j = 0;  // element indices at that level, along u and v
};

class ThbHierarchy {
 public:
  // The tensor mesh of level 0 (every cell a leaf). `admissibility` 0: no grading; m >= 2:
  // refinement also refines what keeps the mesh T-admissible of class m.
  ThbHierarchy(DyadicKnots u, DyadicKnots v, int admissibility);

  // Halves the given leaves (and, with grading, the leaves their refinement requires).
  // Returns the number of leaves halved beyond the given ones. std::invalid_argument when a
  // cell is not a leaf, or would go below the finest representable level.
  int refine(const std::vector<ThbCell>& leaves);

  // The THB basis as a BezierMesh, its leaves in the order of the mesh's cells (depth first
  // from each level-0 cell), and the number of functions per level.
  struct Basis {
    BezierMesh mesh;
    std::vector<ThbCell> leaves;
    std::vector<int> functions_per_level;
  };
  Basis build() const;

  int levels() const { return static_cast<int>(refined_.size()) + 1; }
  // The number of leaves (cells of the mesh), without building anything.
  size_t num_leaves() const {
    size_t refined = 0;
    for (const CellSet& s : refined_) refined += s.size();
    return size_t(u_.base_elements()) * size_t(v_.base_elements()) + 3 * refined;
  }
  int admissibility() const { return admissibility_; }
  bool exists(int level, int64_t i, int64_t j) const;
  bool is_refined(int level, int64_t i, int64_t j) const;
  // The dyadic knots along u (0) or v (1), and the cells of a level that have children.
  const DyadicKnots& knots(int direction) const { return direction == 0 ? u_ : v_; }

  struct KeyHash {
    size_t operator()(const std::pair<int64_t, int64_t>& k) const {
      return std::hash<uint64_t>()(uint64_t(k.first) * 0x9E3779B97F4A7C15ull ^ uint64_t(k.second));
    }
  };
  using CellSet = std::unordered_set<std::pair<int64_t, int64_t>, KeyHash>;
  const CellSet& refined(int level) const {
    static const CellSet none;
    return level < static_cast<int>(refined_.size()) ? refined_[level] : none;
  }

 private:
  void refine_cell(int level, int64_t i, int64_t j, int* extra);

  DyadicKnots u_, v_;
  int admissibility_;
  std::vector<CellSet> refined_;  // per level, the cells that have children
};

}  // namespace knotwork
