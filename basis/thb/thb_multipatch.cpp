#include "basis/thb/thb_multipatch.hpp"

#include "basis/thb/thb_prolongation.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace knotwork {

namespace {

// A cell of one level near a patch side, in the side's terms: its index along the side (t
// increasing) and its distance from the side in cells (0: touching it).
struct SidePosition {
  int64_t along = 0, depth = 0;
};

SidePosition side_position(const ThbHierarchy& h, int level, int side, int64_t i, int64_t j) {
  const int64_t nu = h.knots(0).elements(level), nv = h.knots(1).elements(level);
  switch (side) {
    case 1: return {j, i};
    case 2: return {j, nu - 1 - i};
    case 3: return {i, j};
    default: return {i, nv - 1 - j};
  }
}

std::pair<int64_t, int64_t> cell_at(const ThbHierarchy& h, int level, int side, SidePosition s) {
  const int64_t nu = h.knots(0).elements(level), nv = h.knots(1).elements(level);
  switch (side) {
    case 1: return {s.depth, s.along};
    case 2: return {nu - 1 - s.depth, s.along};
    case 3: return {s.along, s.depth};
    default: return {s.along, nv - 1 - s.depth};
  }
}

int64_t elements_along(const ThbHierarchy& h, int level, int side) { return h.knots(side <= 2 ? 1 : 0).elements(level); }

}  // namespace

ThbMultiPatch::ThbMultiPatch(MultiPatch domain, std::vector<ThbHierarchy> patches)
    : domain_(std::move(domain)), patches_(std::move(patches)) {
  if (static_cast<int>(patches_.size()) != domain_.num_patches())
    throw std::invalid_argument("one THB hierarchy per patch is needed");
}

int ThbMultiPatch::levels() const {
  int l = 0;
  for (const ThbHierarchy& h : patches_) l = std::max(l, h.levels());
  return l;
}

size_t ThbMultiPatch::num_leaves() const {
  size_t n = 0;
  for (const ThbHierarchy& h : patches_) n += h.num_leaves();
  return n;
}

int ThbMultiPatch::refine(const std::vector<ThbPatchCell>& leaves) {
  std::vector<std::vector<ThbCell>> per_patch(patches_.size());
  for (const ThbPatchCell& c : leaves) {
    if (c.patch < 0 || c.patch >= static_cast<int>(patches_.size()))
      throw std::invalid_argument("patch " + std::to_string(c.patch) + " does not exist");
    per_patch[c.patch].push_back(c.cell);
  }
  int extra = 0;
  for (size_t p = 0; p < patches_.size(); ++p) extra += patches_[p].refine(per_patch[p]);
  return extra + close_across_interfaces();
}

// The band is degree + 1 cells deep: a function of a level that reaches the interface lives on
// at most that many cells of the level across it, and whether it is active, or truncated by the
// next level, depends only on those cells. Levels are closed coarsest first, so that the mirror
// image of a band cell exists when it is reached (its parent's mirror image was refined at the
// level before). Grading may refine more on either side: repeated until nothing changes.
int ThbMultiPatch::close_across_interfaces() {
  int extra = 0;
  for (bool changed = true; changed;) {
    changed = false;
    for (const PatchInterface& f : domain_.interfaces)
      for (int direction = 0; direction < 2; ++direction) {
        const PatchSideRef from = direction == 0 ? f.a : f.b, to = direction == 0 ? f.b : f.a;
        for (int level = 0; level + 1 < patches_[from.patch].levels(); ++level) {
          ThbHierarchy& src = patches_[from.patch];
          ThbHierarchy& dst = patches_[to.patch];
          const int64_t band = std::max(src.knots(0).degree(), src.knots(1).degree()) + 1;
          const int64_t n = elements_along(src, level, from.side);
          if (elements_along(dst, level, to.side) != n) break;  // build() names the mismatch
          // A copy: src and dst may be one patch (an interface between two of its sides).
          const std::vector<ThbHierarchy::Key> cells(src.refined(level).begin(), src.refined(level).end());
          std::vector<ThbCell> halve;
          for (const auto& [i, j, k] : cells) {
            SidePosition s = side_position(src, level, from.side, i, j);
            if (s.depth >= band) continue;
            if (f.reversed) s.along = n - 1 - s.along;
            const auto [ti, tj] = cell_at(dst, level, to.side, s);
            if (!dst.exists(level, ti, tj))
              throw std::logic_error("THB across an interface: the mirror image of a band cell of level " +
                                     std::to_string(level) + " does not exist");
            if (!dst.is_refined(level, ti, tj)) halve.push_back({level, ti, tj});
          }
          std::sort(halve.begin(), halve.end(), [](const ThbCell& x, const ThbCell& y) {
            return std::pair(x.i, x.j) < std::pair(y.i, y.j);
          });
          halve.erase(std::unique(halve.begin(), halve.end(),
                                  [](const ThbCell& x, const ThbCell& y) { return x.i == y.i && x.j == y.j; }),
                      halve.end());
          for (const ThbCell& c : halve)
            if (!dst.is_refined(c.level, c.i, c.j)) extra += 1 + dst.refine({c});
          changed = changed || !halve.empty();
        }
      }
  }
  return extra;
}

ThbMultiPatch::Basis ThbMultiPatch::build() const {
  Basis out;
  std::vector<std::vector<ThbCell>> leaves;
  std::vector<std::vector<int>> per_level;
  for (const ThbHierarchy& h : patches_) {
    ThbHierarchy::Basis b = h.build();
    out.patch_meshes.push_back(std::move(b.mesh));
    leaves.push_back(std::move(b.leaves));
    per_level.push_back(std::move(b.functions_per_level));
  }
  std::vector<const BezierMesh*> meshes;
  for (const BezierMesh& m : out.patch_meshes) meshes.push_back(&m);
  out.glued = glue_patches(domain_, meshes);
  for (size_t p = 0; p < leaves.size(); ++p)
    for (const ThbCell& c : leaves[p]) out.leaves.push_back({static_cast<int>(p), c});
  out.patch_leaves = std::move(leaves);
  // A patch numbers its functions level by level; a glued function has one level (its
  // mirror images are of the same level).
  std::vector<int> level_of(out.glued.mesh.num_functions(), -1);
  out.functions_per_level.assign(levels(), 0);
  for (size_t p = 0; p < per_level.size(); ++p) {
    int f = 0;
    for (size_t l = 0; l < per_level[p].size(); ++l)
      for (int k = 0; k < per_level[p][l]; ++k, ++f) {
        int& g = level_of[out.glued.global_function[p][f]];
        if (g < 0) ++out.functions_per_level[l];
        g = static_cast<int>(l);
      }
  }
  out.patch_functions_per_level = std::move(per_level);
  return out;
}

Eigen::SparseMatrix<double> ThbMultiPatch::prolongation(const Basis& coarse, const Basis& fine) const {
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<bool> done(fine.glued.mesh.num_functions(), false);
  for (size_t p = 0; p < patches_.size(); ++p) {
    const Eigen::SparseMatrix<double> local =
        thb_prolongation(patches_[p], coarse.patch_meshes[p], coarse.patch_leaves[p], fine.patch_meshes[p],
                         fine.patch_leaves[p], fine.patch_functions_per_level[p]);
    const Eigen::SparseMatrix<double, Eigen::RowMajor> rows = local;
    for (int f = 0; f < rows.outerSize(); ++f) {
      const int g = fine.glued.global_function[p][f];
      if (done[g]) continue;  // taken from an earlier patch
      done[g] = true;
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(rows, f); it; ++it)
        entries.emplace_back(g, coarse.glued.global_function[p][it.col()], it.value());
    }
  }
  Eigen::SparseMatrix<double> P(fine.glued.mesh.num_functions(), coarse.glued.mesh.num_functions());
  P.setFromTriplets(entries.begin(), entries.end());
  return P;
}

}  // namespace knotwork
