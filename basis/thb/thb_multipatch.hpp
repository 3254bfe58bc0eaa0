#pragma once
// THB-splines on a multipatch domain, C0-conforming across its interfaces. One hierarchy per
// patch; every refinement is closed so that, at every level, the cells within degree + 1 cells
// of an interface are refined on one side exactly when their mirror images on the other side
// are. The functions that reach an interface from one side are then the mirror images of those
// from the other, truncated alike, and glue_patches identifies them by their traces (refusing,
// not guessing, if they ever differ). Refinement stays local: the closure only reaches across
// an interface where the marked cells touch its band.
#include <vector>

#include "basis/core/glue_patches.hpp"
#include "basis/core/multipatch.hpp"
#include "basis/thb/thb_hierarchy.hpp"

namespace knotwork {

struct ThbPatchCell {
  int patch = 0;
  ThbCell cell;
};

class ThbMultiPatch {
 public:
  // `patches[k]` is the level-0 hierarchy of domain.patches[k]; the interfaces' level-0 cells
  // must match (glue_patches refuses them in build() otherwise).
  ThbMultiPatch(MultiPatch domain, std::vector<ThbHierarchy> patches);

  // Halves the given leaves, then what grading and the interfaces require. Returns the number
  // of leaves halved beyond the given ones. std::invalid_argument as ThbHierarchy::refine.
  int refine(const std::vector<ThbPatchCell>& leaves);

  struct Basis {
    std::vector<BezierMesh> patch_meshes;          // each patch's THB space, numbered locally
    GluedPatches glued;                            // the conforming space; its cells in patch order
    std::vector<ThbPatchCell> leaves;              // the glued mesh's cells as leaves
    std::vector<int> functions_per_level;          // of the glued space
    std::vector<std::vector<ThbCell>> patch_leaves;         // per patch, its mesh's cells as leaves
    std::vector<std::vector<int>> patch_functions_per_level;  // per patch, of its own space
  };
  // GeometryError naming the interface when the two sides' spaces do not glue.
  Basis build() const;

  int levels() const;
  // The prolongation from `coarse` (this object's basis before its last refine) to `fine` (its
  // basis now): thb_prolongation on each patch, read in the glued numbering. A glued function is
  // the same on every patch it reaches, so its row is taken from any one of them.
  Eigen::SparseMatrix<double> prolongation(const Basis& coarse, const Basis& fine) const;
  size_t num_leaves() const;
  const std::vector<ThbHierarchy>& patches() const { return patches_; }

 private:
  int close_across_interfaces();

  MultiPatch domain_;
  std::vector<ThbHierarchy> patches_;
};

}  // namespace knotwork
