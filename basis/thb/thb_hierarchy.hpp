#pragma once
// Truncated hierarchical B-splines (Giannelli, Jüttler, Speleers 2012) on a dyadic hierarchy
// of one patch's or one volume's parameter domain: a quadtree (an octree on a volume) of cells
// over a tensor mesh, refined by halving marked leaves in every direction, optionally graded to
// keep the mesh T-admissible of class m (Buffa, Giannelli 2016: a leaf meets THB functions of
// at most m successive levels). The parametric dimension is a parameter: one code for both.
#include <array>
#include <cstdint>
#include <optional>
#include <unordered_set>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/dyadic_knots.hpp"

namespace knotwork {

struct ThbCell {
  int level = 0;
  int64_t i = 0, j = 0;  // element indices at that level, along u and v
  int64_t k = 0;         // and along w (volumes; 0 on a patch)
};

class ThbHierarchy {
 public:
  // The tensor mesh of level 0 (every cell a leaf). `admissibility` 0: no grading; m >= 2:
  // refinement also refines what keeps the mesh T-admissible of class m.
  ThbHierarchy(DyadicKnots u, DyadicKnots v, int admissibility);
  // A volume's: the tensor mesh of hexahedra of level 0, refined into octants.
  ThbHierarchy(DyadicKnots u, DyadicKnots v, DyadicKnots w, int admissibility);
  int dimension() const { return w_ ? 3 : 2; }
  // Removes level-0 cells from the domain (a domain that is the box less some of its cells,
  // e.g. the Fichera corner): they and their descendants are never cells, a function counts
  // the part of its support inside the domain only (a B-spline wholly inside removed cells is
  // none), and the faces that meet a removed cell are boundary with the id after the box's
  // sides (4 on a patch, 6 on a volume), named "hole". std::invalid_argument for a cell out of
  // range, or when every cell would be removed. Call before any refinement.
  void remove_base_cells(const std::vector<ThbCell>& cells);

  // Halves the given leaves (and, with grading, the leaves their refinement requires).
  // Returns the number of leaves halved beyond the given ones. std::invalid_argument when a
  // cell is not a leaf, or would go below the finest representable level.
  int refine(const std::vector<ThbCell>& leaves);

  // The THB basis as a BezierMesh (quadrilaterals or hexahedra), its leaves in the order of the
  // mesh's cells (depth first from each level-0 cell), and the number of functions per level.
  // A volume's boundary ids are 0..5 for u = 0, u = 1, v = 0, v = 1, w = 0, w = 1.
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
    const size_t base = size_t(u_.base_elements()) * size_t(v_.base_elements()) * (w_ ? size_t(w_->base_elements()) : 1);
    return base - holes_.size() + ((size_t(1) << dimension()) - 1) * refined;
  }
  int admissibility() const { return admissibility_; }
  bool exists(int level, int64_t i, int64_t j, int64_t k = 0) const;
  bool is_refined(int level, int64_t i, int64_t j, int64_t k = 0) const;
  // The dyadic knots along u (0), v (1) or w (2, volumes), and the cells of a level that have children.
  const DyadicKnots& knots(int direction) const { return direction == 0 ? u_ : direction == 1 ? v_ : *w_; }

  // A cell's element indices (i, j, k); k = 0 on a patch.
  using Key = std::array<int64_t, 3>;
  struct KeyHash {
    size_t operator()(const Key& k) const {
      return std::hash<uint64_t>()(uint64_t(k[0]) * 0x9E3779B97F4A7C15ull ^ uint64_t(k[1]) ^
                                   uint64_t(k[2]) * 0xC2B2AE3D27D4EB4Full);
    }
  };
  using CellSet = std::unordered_set<Key, KeyHash>;
  const CellSet& refined(int level) const {
    static const CellSet none;
    return level < static_cast<int>(refined_.size()) ? refined_[level] : none;
  }

 private:
  void refine_cell(int level, const Key& cell, int* extra);
  // Whether cell (i, j, k) of `level` lies in a removed level-0 cell.
  bool in_hole(int level, const Key& cell) const {
    return !holes_.empty() && holes_.count({cell[0] >> level, cell[1] >> level, w_ ? cell[2] >> level : 0}) > 0;
  }
  int64_t elements(int direction, int level) const { return direction < dimension() ? knots(direction).elements(level) : 1; }

  DyadicKnots u_, v_;
  std::optional<DyadicKnots> w_;
  std::unordered_set<Key, KeyHash> holes_;  // removed level-0 cells
  int admissibility_;
  std::vector<CellSet> refined_;  // per level, the cells that have children
};

}  // namespace knotwork
