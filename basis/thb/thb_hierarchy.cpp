// The THB basis cell by cell: a depth-first walk of the quadtree carries, from a cell to its
// children, the coefficients of every function alive on the cell in that level's B-splines;
// at each level the coarser functions are truncated (coefficients of B-splines whose support
// lies in the refined region dropped) and the level's active B-splines join. A leaf's
// extraction is then its functions' coefficients times the level's Bézier extraction. The
// work is local to each root's subtree: no function is ever expanded over the whole domain.
#include "basis/thb/thb_hierarchy.hpp"

#include <omp.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "basis/core/pooled_extractions.hpp"

namespace knotwork {

namespace {

using Key = std::pair<int64_t, int64_t>;

// What a level knows of one of its B-splines (by first knot index along u and v).
struct FunctionStatus {
  bool in_level = false;  // its support lies in the region of cells of this level or finer
  bool in_finer = false;  // ... in the region of the next level (refined): truncated away
  int id = -1;            // its THB index when active (in_level and not in_finer)
};

using StatusMap = std::unordered_map<Key, FunctionStatus, ThbHierarchy::KeyHash>;

// One function alive on a cell: its coefficients in the cell level's B-splines (degree_u+1 by
// degree_v+1, the B-splines from first_function of the cell's elements on).
struct Alive {
  int id;
  Eigen::MatrixXd coefficients;
};

struct CellOut {
  BezierCell cell;
  std::vector<int> ids;
  Eigen::MatrixXd extraction;
  ThbCell leaf;
};

}  // namespace

ThbHierarchy::ThbHierarchy(DyadicKnots u, DyadicKnots v, int admissibility)
    : u_(std::move(u)), v_(std::move(v)), admissibility_(admissibility) {
  if (admissibility != 0 && admissibility < 2)
    throw std::invalid_argument("admissibility must be 0 (no grading) or a class m >= 2");
}

bool ThbHierarchy::exists(int level, int64_t i, int64_t j) const {
  if (i < 0 || j < 0 || i >= u_.elements(level) || j >= v_.elements(level)) return false;
  if (level == 0) return true;
  if (level - 1 >= static_cast<int>(refined_.size())) return false;
  return refined_[level - 1].count({i >> 1, j >> 1}) > 0;
}

bool ThbHierarchy::is_refined(int level, int64_t i, int64_t j) const {
  return level < static_cast<int>(refined_.size()) && refined_[level].count({i, j}) > 0;
}

int ThbHierarchy::refine(const std::vector<ThbCell>& leaves) {
  for (const ThbCell& c : leaves)
    if (!exists(c.level, c.i, c.j) || is_refined(c.level, c.i, c.j))
      throw std::invalid_argument("cell (" + std::to_string(c.level) + ", " + std::to_string(c.i) + ", " +
                                  std::to_string(c.j) + ") is not a leaf of the hierarchy");
  int extra = 0;
  for (const ThbCell& c : leaves)
    if (!is_refined(c.level, c.i, c.j)) refine_cell(c.level, c.i, c.j, &extra);
  return extra;
}

void ThbHierarchy::refine_cell(int level, int64_t i, int64_t j, int* extra) {
  if (level + 1 > std::min(u_.max_level(), v_.max_level()))
    throw std::invalid_argument("a cell of level " + std::to_string(level) +
                                " cannot be halved: its children would be narrower than double precision resolves "
                                "in the parameter domain");
  const int m = admissibility_;
  const int k = level - m + 2;  // the level whose support extension of this cell is graded
  if (m >= 2 && k >= 1) {
    const int64_t iu = i >> (level - k), jv = j >> (level - k);
    const int64_t fu = u_.first_function(k, iu), fv = v_.first_function(k, jv);
    const int64_t u0 = u_.support(k, fu).first, u1 = u_.support(k, fu + u_.degree()).second;
    const int64_t v0 = v_.support(k, fv).first, v1 = v_.support(k, fv + v_.degree()).second;
    // The leaves of level k-1 that meet the extension are halved first. In a graded mesh every
    // cell of level k-1 there exists (Buffa, Giannelli 2016); one that does not is a bug here.
    for (int64_t a = u0 >> 1; a <= (u1 - 1) >> 1; ++a)
      for (int64_t b = v0 >> 1; b <= (v1 - 1) >> 1; ++b) {
        if (!exists(k - 1, a, b)) throw std::logic_error("THB grading: the mesh is not T-admissible");
        if (!is_refined(k - 1, a, b)) {
          refine_cell(k - 1, a, b, extra);
          ++*extra;
        }
      }
  }
  if (static_cast<int>(refined_.size()) <= level) refined_.resize(level + 1);
  refined_[level].insert({i, j});
}

ThbHierarchy::Basis ThbHierarchy::build() const {
  const int p = u_.degree(), q = v_.degree();
  const int L = levels();
  // The cells of every level.
  std::vector<std::vector<Key>> cells(L);
  for (int64_t i = 0; i < u_.elements(0); ++i)
    for (int64_t j = 0; j < v_.elements(0); ++j) cells[0].push_back({i, j});
  for (int l = 0; l + 1 < L; ++l) {
    std::vector<Key> parents(refined_[l].begin(), refined_[l].end());
    std::sort(parents.begin(), parents.end());
    for (const Key& c : parents)
      for (int di = 0; di < 2; ++di)
        for (int dj = 0; dj < 2; ++dj) cells[l + 1].push_back({2 * c.first + di, 2 * c.second + dj});
  }
  // The status of every B-spline of every level that is alive on a cell of that level.
  std::vector<StatusMap> status(L);
  Basis out;
  out.functions_per_level.assign(L, 0);
  int next_id = 0;
  for (int l = 0; l < L; ++l) {
    std::vector<Key> active;
    for (const Key& c : cells[l]) {
      const int64_t fu = u_.first_function(l, c.first), fv = v_.first_function(l, c.second);
      for (int a = 0; a <= p; ++a)
        for (int b = 0; b <= q; ++b) {
          auto [it, fresh] = status[l].try_emplace({fu + a, fv + b});
          if (!fresh) continue;
          const auto su = u_.support(l, fu + a), sv = v_.support(l, fv + b);
          FunctionStatus& s = it->second;
          s.in_level = s.in_finer = true;
          for (int64_t x = su.first; x < su.second && s.in_level; ++x)
            for (int64_t y = sv.first; y < sv.second && s.in_level; ++y) {
              if (!exists(l, x, y)) s.in_level = s.in_finer = false;
              else if (!is_refined(l, x, y)) s.in_finer = false;
            }
          if (s.in_level && !s.in_finer) active.push_back({fu + a, fv + b});
        }
    }
    std::sort(active.begin(), active.end());
    for (const Key& k : active) status[l][k].id = next_id++;
    out.functions_per_level[l] = static_cast<int>(active.size());
  }
  // One-dimensional tables, per level: Bézier extraction of each element in use, and the
  // refinement from each element's parent (levels >= 1).
  struct Tables {
    std::unordered_map<int64_t, Eigen::MatrixXd> extraction, refinement;
  };
  std::vector<std::array<Tables, 2>> tables(L);
  for (int l = 0; l < L; ++l) {
    std::array<std::vector<int64_t>, 2> elements;
    for (const Key& c : cells[l]) {
      elements[0].push_back(c.first);
      elements[1].push_back(c.second);
    }
    for (int d = 0; d < 2; ++d) {
      std::sort(elements[d].begin(), elements[d].end());
      elements[d].erase(std::unique(elements[d].begin(), elements[d].end()), elements[d].end());
      const DyadicKnots& K = d == 0 ? u_ : v_;
      for (int64_t e : elements[d]) {
        tables[l][d].extraction.emplace(e, K.extraction(l, e));
        if (l > 0) tables[l][d].refinement.emplace(e, K.refinement(l - 1, e));
      }
    }
  }
  // The walk, one subtree per level-0 cell.
  const int roots = static_cast<int>(cells[0].size());
  std::vector<std::vector<CellOut>> per_root(roots);
  std::vector<std::string> failure(omp_get_max_threads());
#pragma omp parallel for schedule(dynamic, 1)
  for (int r = 0; r < roots; ++r) {
    // Products into kept arrays: evaluated as written, every small product allocated two
    // temporaries, a fifth of the build on the adaptive L-shape.
    Eigen::MatrixXd half, product;
    try {
      struct Frame {
        int level;
        Key cell;
        std::vector<Alive> alive;
      };
      // The active B-splines of a frame's level that live on its cell join it.
      auto join_active = [&](Frame& f) {
        const int64_t fu = u_.first_function(f.level, f.cell.first), fv = v_.first_function(f.level, f.cell.second);
        for (int a = 0; a <= p; ++a)
          for (int b = 0; b <= q; ++b)
            if (const FunctionStatus& s = status[f.level].at({fu + a, fv + b}); s.id >= 0) {
              Eigen::MatrixXd X = Eigen::MatrixXd::Zero(p + 1, q + 1);
              X(a, b) = 1;
              f.alive.push_back({s.id, std::move(X)});
            }
      };
      std::vector<Frame> stack(1, Frame{0, cells[0][r], {}});
      join_active(stack.back());
      while (!stack.empty()) {
        Frame f = std::move(stack.back());
        stack.pop_back();
        const int l = f.level;
        const auto [i, j] = f.cell;
        if (!is_refined(l, i, j)) {
          const Eigen::MatrixXd& Eu = tables[l][0].extraction.at(i);
          const Eigen::MatrixXd& Ev = tables[l][1].extraction.at(j);
          CellOut o;
          o.leaf = {l, i, j};
          o.cell.u0 = u_.breakpoint(l, i);
          o.cell.u1 = u_.breakpoint(l, i + 1);
          o.cell.v0 = v_.breakpoint(l, j);
          o.cell.v1 = v_.breakpoint(l, j + 1);
          o.cell.degree_u = p;
          o.cell.degree_v = q;
          if (j == 0) o.cell.boundary[kSideBottom] = 0;
          if (i + 1 == u_.elements(l)) o.cell.boundary[kSideRight] = 1;
          if (j + 1 == v_.elements(l)) o.cell.boundary[kSideTop] = 2;
          if (i == 0) o.cell.boundary[kSideLeft] = 3;
          o.extraction.resize(static_cast<int>(f.alive.size()), (p + 1) * (q + 1));
          for (size_t k = 0; k < f.alive.size(); ++k) {
            half.noalias() = Eu.transpose() * f.alive[k].coefficients;
            product.noalias() = half * Ev;
            o.extraction.row(static_cast<int>(k)) = Eigen::Map<const Eigen::RowVectorXd>(product.data(), product.size());
            o.ids.push_back(f.alive[k].id);
          }
          per_root[r].push_back(std::move(o));
          continue;
        }
        // Children pushed in reverse so that they are visited in the order (0,0), (1,0), (0,1), (1,1).
        for (int c = 3; c >= 0; --c) {
          const int64_t ci = 2 * i + (c & 1), cj = 2 * j + (c >> 1);
          const Eigen::MatrixXd& Ru = tables[l + 1][0].refinement.at(ci);
          const Eigen::MatrixXd& Rv = tables[l + 1][1].refinement.at(cj);
          const int64_t fu = u_.first_function(l + 1, ci), fv = v_.first_function(l + 1, cj);
          // Which of the child level's B-splines truncate (support in the refined region).
          Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic> truncated(p + 1, q + 1);
          for (int a = 0; a <= p; ++a)
            for (int b = 0; b <= q; ++b) truncated(a, b) = status[l + 1].at({fu + a, fv + b}).in_level;
          Frame child{l + 1, {ci, cj}, {}};
          for (const Alive& g : f.alive) {
            half.noalias() = Ru.transpose() * g.coefficients;
            Eigen::MatrixXd Y(p + 1, q + 1);
            Y.noalias() = half * Rv;
            bool any = false;
            for (int a = 0; a <= p; ++a)
              for (int b = 0; b <= q; ++b) {
                if (truncated(a, b)) Y(a, b) = 0;
                any = any || Y(a, b) != 0;
              }
            if (any) child.alive.push_back({g.id, std::move(Y)});
          }
          join_active(child);
          stack.push_back(std::move(child));
        }
      }
    } catch (const std::exception& e) {
      failure[omp_get_thread_num()] = e.what();
    }
  }
  for (const std::string& f : failure)
    if (!f.empty()) throw std::runtime_error("THB basis: " + f);
  size_t cells_total = 0, ids_total = 0;
  for (const auto& v : per_root) {
    cells_total += v.size();
    for (const CellOut& o : v) ids_total += o.ids.size();
  }
  out.mesh.reserve(static_cast<int>(cells_total), static_cast<long>(ids_total));
  out.mesh.set_num_functions(next_id);
  out.mesh.set_boundary_names({"bottom", "right", "top", "left"});
  out.leaves.reserve(cells_total);
  // Identical extraction matrices (most cells away from level changes) are pooled.
  PooledExtractions pooled(out.mesh);
  for (auto& v : per_root)
    for (CellOut& o : v) {
      out.mesh.add_cell(o.cell, o.ids, pooled.add(std::move(o.extraction)));
      out.leaves.push_back(o.leaf);
    }
  return out;
}

}  // namespace knotwork
