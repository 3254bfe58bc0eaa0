// The THB basis cell by cell: a depth-first walk of the quadtree (octree) carries, from a cell
// to its children, the coefficients of every function alive on the cell in that level's B-splines;
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

using Key = ThbHierarchy::Key;

// What a level knows of one of its B-splines (by first knot index along u, v and w).
struct FunctionStatus {
  bool in_level = false;  // its support lies in the region of cells of this level or finer
  bool in_finer = false;  // ... in the region of the next level (refined): truncated away
  int id = -1;            // its THB index when active (in_level and not in_finer)
};

using StatusMap = std::unordered_map<Key, FunctionStatus, ThbHierarchy::KeyHash>;


struct CellOut {
  BezierCell cell;
  std::vector<int> ids;
  Eigen::MatrixXd extraction;
  size_t extraction_hash;  // PooledExtractions::hash, computed in the parallel walk
  ThbCell leaf;
};

}  // namespace

ThbHierarchy::ThbHierarchy(DyadicKnots u, DyadicKnots v, int admissibility)
    : u_(std::move(u)), v_(std::move(v)), admissibility_(admissibility) {
  if (admissibility != 0 && admissibility < 2)
    throw std::invalid_argument("admissibility must be 0 (no grading) or a class m >= 2");
}

ThbHierarchy::ThbHierarchy(DyadicKnots u, DyadicKnots v, DyadicKnots w, int admissibility)
    : ThbHierarchy(std::move(u), std::move(v), admissibility) {
  w_.emplace(std::move(w));
}

void ThbHierarchy::remove_base_cells(const std::vector<ThbCell>& cells) {
  if (!refined_.empty()) throw std::logic_error("ThbHierarchy::remove_base_cells after refinement");
  for (const ThbCell& c : cells) {
    if (c.level != 0 || !exists(0, c.i, c.j, c.k))
      throw std::invalid_argument("cell (" + std::to_string(c.level) + ", " + std::to_string(c.i) + ", " + std::to_string(c.j) +
                                  ", " + std::to_string(c.k) + ") is not a cell of level 0");
    holes_.insert({c.i, c.j, w_ ? c.k : 0});
  }
  if (num_leaves() == 0) throw std::invalid_argument("every cell of the domain is removed");
}

bool ThbHierarchy::exists(int level, int64_t i, int64_t j, int64_t k) const {
  if (i < 0 || j < 0 || k < 0 || i >= u_.elements(level) || j >= v_.elements(level) || k >= elements(2, level)) return false;
  if (in_hole(level, {i, j, k})) return false;
  if (level == 0) return true;
  if (level - 1 >= static_cast<int>(refined_.size())) return false;
  return refined_[level - 1].count({i >> 1, j >> 1, w_ ? k >> 1 : 0}) > 0;
}

bool ThbHierarchy::is_refined(int level, int64_t i, int64_t j, int64_t k) const {
  return level < static_cast<int>(refined_.size()) && refined_[level].count({i, j, k}) > 0;
}

int ThbHierarchy::refine(const std::vector<ThbCell>& leaves) {
  for (const ThbCell& c : leaves)
    if (!exists(c.level, c.i, c.j, c.k) || is_refined(c.level, c.i, c.j, c.k))
      throw std::invalid_argument("cell (" + std::to_string(c.level) + ", " + std::to_string(c.i) + ", " +
                                  std::to_string(c.j) + (w_ ? ", " + std::to_string(c.k) : std::string()) +
                                  ") is not a leaf of the hierarchy");
  int extra = 0;
  for (const ThbCell& c : leaves)
    if (!is_refined(c.level, c.i, c.j, c.k)) refine_cell(c.level, {c.i, c.j, c.k}, &extra);
  return extra;
}

void ThbHierarchy::refine_cell(int level, const Key& cell, int* extra) {
  const int d = dimension();
  int finest = std::min(u_.max_level(), v_.max_level());
  if (w_) finest = std::min(finest, w_->max_level());
  if (level + 1 > finest)
    throw std::invalid_argument("a cell of level " + std::to_string(level) +
                                " cannot be halved: its children would be narrower than double precision resolves "
                                "in the parameter domain");
  const int m = admissibility_;
  const int k = level - m + 2;  // the level whose support extension of this cell is graded
  if (m >= 2 && k >= 1) {
    // Per direction, the elements of level k that the support extension covers: [lo, hi).
    int64_t lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    for (int x = 0; x < d; ++x) {
      const DyadicKnots& K = knots(x);
      const int64_t f = K.first_function(k, cell[x] >> (level - k));
      lo[x] = K.support(k, f).first;
      hi[x] = K.support(k, f + K.degree()).second;
    }
    // The leaves of level k-1 that meet the extension are halved first. In a graded mesh every
    // cell of level k-1 there exists (Buffa, Giannelli 2016); one that does not is a bug here.
    const auto parent = [&](int x, int64_t e) { return x < d ? e >> 1 : int64_t(0); };
    for (int64_t a = parent(0, lo[0]); a <= parent(0, hi[0] - 1); ++a)
      for (int64_t b = parent(1, lo[1]); b <= parent(1, hi[1] - 1); ++b)
        for (int64_t c = parent(2, lo[2]); c <= parent(2, hi[2] - 1); ++c) {
          if (in_hole(k - 1, {a, b, c})) continue;  // outside the domain: nothing to grade
          if (!exists(k - 1, a, b, c)) throw std::logic_error("THB grading: the mesh is not T-admissible");
          if (!is_refined(k - 1, a, b, c)) {
            refine_cell(k - 1, {a, b, c}, extra);
            ++*extra;
          }
        }
  }
  if (static_cast<int>(refined_.size()) <= level) refined_.resize(level + 1);
  refined_[level].insert(cell);
}

ThbHierarchy::Basis ThbHierarchy::build() const {
  const int d = dimension();
  const int p = u_.degree(), q = v_.degree(), r = w_ ? w_->degree() : 0;
  const int nb = (q + 1) * (r + 1);  // columns of a function's coefficients: b + (q+1) c
  const int block = (p + 1) * nb;     // a function's coefficients on a cell
  const int children = 1 << d;
  const int L = levels();
  // The cells of every level.
  std::vector<std::vector<Key>> cells(L);
  for (int64_t i = 0; i < u_.elements(0); ++i)
    for (int64_t j = 0; j < v_.elements(0); ++j)
      for (int64_t k = 0; k < elements(2, 0); ++k)
        if (!in_hole(0, {i, j, k})) cells[0].push_back({i, j, k});
  for (int l = 0; l + 1 < L; ++l) {
    std::vector<Key> parents(refined_[l].begin(), refined_[l].end());
    std::sort(parents.begin(), parents.end());
    for (const Key& c : parents)
      for (int di = 0; di < 2; ++di)
        for (int dj = 0; dj < 2; ++dj)
          for (int dk = 0; dk < (w_ ? 2 : 1); ++dk) cells[l + 1].push_back({2 * c[0] + di, 2 * c[1] + dj, w_ ? 2 * c[2] + dk : 0});
  }
  // The first function of a cell's elements along each direction (0 along an absent w).
  const auto first_functions = [&](int l, const Key& c) {
    return Key{u_.first_function(l, c[0]), v_.first_function(l, c[1]), w_ ? w_->first_function(l, c[2]) : 0};
  };
  // The status of every B-spline of every level that is alive on a cell of that level: the
  // levels apart, in parallel (they only read the hierarchy), then numbered level by level.
  std::vector<StatusMap> status(L);
  std::vector<std::vector<Key>> active(L);
#pragma omp parallel for schedule(dynamic, 1)
  for (int l = 0; l < L; ++l) {
    for (const Key& cell : cells[l]) {
      const Key f = first_functions(l, cell);
      for (int a = 0; a <= p; ++a)
        for (int b = 0; b <= q; ++b)
          for (int c = 0; c <= r; ++c) {
            const Key function{f[0] + a, f[1] + b, f[2] + c};
            auto [it, fresh] = status[l].try_emplace(function);
            if (!fresh) continue;
            std::pair<int64_t, int64_t> support[3] = {u_.support(l, function[0]), v_.support(l, function[1]), {0, 1}};
            if (w_) support[2] = w_->support(l, function[2]);
            FunctionStatus& s = it->second;
            s.in_level = s.in_finer = true;
            for (int64_t x = support[0].first; x < support[0].second && s.in_level; ++x)
              for (int64_t y = support[1].first; y < support[1].second && s.in_level; ++y)
                for (int64_t z = support[2].first; z < support[2].second && s.in_level; ++z) {
                  if (in_hole(l, {x, y, z})) continue;  // the support counts inside the domain only
                  if (!exists(l, x, y, z)) s.in_level = s.in_finer = false;
                  else if (!is_refined(l, x, y, z)) s.in_finer = false;
                }
            if (s.in_level && !s.in_finer) active[l].push_back(function);
          }
    }
    std::sort(active[l].begin(), active[l].end());
  }
  Basis out;
  out.functions_per_level.assign(L, 0);
  int next_id = 0;
  for (int l = 0; l < L; ++l) {
    for (const Key& k : active[l]) status[l][k].id = next_id++;
    out.functions_per_level[l] = static_cast<int>(active[l].size());
  }
  // One-dimensional tables, per level: Bézier extraction of each element in use, and the
  // refinement from each element's parent (levels >= 1).
  struct Tables {
    std::unordered_map<int64_t, Eigen::MatrixXd> extraction, refinement;
  };
  std::vector<std::array<Tables, 3>> tables(L);
  for (int l = 0; l < L; ++l) {
    std::array<std::vector<int64_t>, 3> used;
    for (const Key& c : cells[l])
      for (int x = 0; x < d; ++x) used[x].push_back(c[x]);
    for (int x = 0; x < d; ++x) {
      std::sort(used[x].begin(), used[x].end());
      used[x].erase(std::unique(used[x].begin(), used[x].end()), used[x].end());
      const DyadicKnots& K = knots(x);
      for (int64_t e : used[x]) {
        tables[l][x].extraction.emplace(e, K.extraction(l, e));
        if (l > 0) tables[l][x].refinement.emplace(e, K.refinement(l - 1, e));
      }
    }
  }
  // The factor acting on a coefficient block's columns (b + (q+1) c): the v table on a patch,
  // the Kronecker product of the w and v tables on a volume.
  const auto across = [&](const Eigen::MatrixXd& along_v, const Eigen::MatrixXd* along_w, Eigen::MatrixXd& out_factor) {
    if (!along_w) return &along_v;
    out_factor.resize(along_w->rows() * along_v.rows(), along_w->cols() * along_v.cols());
    for (Eigen::Index c = 0; c < along_w->rows(); ++c)
      for (Eigen::Index c2 = 0; c2 < along_w->cols(); ++c2)
        out_factor.block(c * along_v.rows(), c2 * along_v.cols(), along_v.rows(), along_v.cols()) = (*along_w)(c, c2) * along_v;
    return static_cast<const Eigen::MatrixXd*>(&out_factor);
  };
  // The walk, one subtree per level-0 cell.
  const int roots = static_cast<int>(cells[0].size());
  std::vector<std::vector<CellOut>> per_root(roots);
  std::vector<std::string> failure(omp_get_max_threads());
#pragma omp parallel for schedule(dynamic, 1)
  for (int root = 0; root < roots; ++root) {
    // Products into kept arrays: evaluated as written, every small product allocated two
    // temporaries, a fifth of the build on the adaptive L-shape.
    Eigen::MatrixXd half, product, kron;
    // The level's B-splines on a frame's cell (their status, looked up once per cell).
    std::vector<const FunctionStatus*> on_cell(static_cast<size_t>(block));
    const auto look_up = [&](int l, const Key& cell) {
      const Key first = first_functions(l, cell);
      for (int a = 0; a <= p; ++a)
        for (int c = 0; c <= r; ++c)
          for (int b = 0; b <= q; ++b) on_cell[a + (p + 1) * (b + (q + 1) * c)] = &status[l].at({first[0] + a, first[1] + b, first[2] + c});
    };
    try {
      // The functions alive on a frame's cell: ids, and their coefficients in the cell level's
      // B-splines, `block` numbers each ((p+1) x (q+1)(r+1), column b + (q+1) c; the B-splines
      // from first_function of the cell's elements on), one after the other: one allocation per
      // frame instead of one per function (a tenth of the build).
      struct Frame {
        int level;
        Key cell;
        std::vector<int> ids;
        std::vector<double> coefficients;
      };
      // The active B-splines of the frame's level that live on its cell join it (on_cell looked up).
      auto join_active = [&](Frame& f) {
        for (int a = 0; a <= p; ++a)
          for (int c = 0; c <= r; ++c)
            for (int b = 0; b <= q; ++b)
              if (const int k = a + (p + 1) * (b + (q + 1) * c); on_cell[k]->id >= 0) {
                f.ids.push_back(on_cell[k]->id);
                f.coefficients.resize(f.coefficients.size() + block, 0.0);
                f.coefficients[f.coefficients.size() - block + k] = 1;
              }
      };
      const auto coefficients_of = [&](const Frame& f, size_t a) {
        return Eigen::Map<const Eigen::MatrixXd>(f.coefficients.data() + a * block, p + 1, nb);
      };
      std::vector<Frame> stack(1, Frame{0, cells[0][root], {}, {}});
      look_up(0, cells[0][root]);
      join_active(stack.back());
      while (!stack.empty()) {
        Frame f = std::move(stack.back());
        stack.pop_back();
        const int l = f.level;
        const auto [i, j, k] = f.cell;
        if (!is_refined(l, i, j, k)) {
          const Eigen::MatrixXd& Eu = tables[l][0].extraction.at(i);
          const Eigen::MatrixXd* Evw = across(tables[l][1].extraction.at(j), w_ ? &tables[l][2].extraction.at(k) : nullptr, kron);
          CellOut o;
          o.leaf = {l, i, j, k};
          o.cell.u0 = u_.breakpoint(l, i);
          o.cell.u1 = u_.breakpoint(l, i + 1);
          o.cell.v0 = v_.breakpoint(l, j);
          o.cell.v1 = v_.breakpoint(l, j + 1);
          o.cell.degree_u = p;
          o.cell.degree_v = q;
          if (w_) {
            o.cell.dimension = 3;
            o.cell.degree_w = static_cast<std::int16_t>(r);
            o.cell.w0 = w_->breakpoint(l, k);
            o.cell.w1 = w_->breakpoint(l, k + 1);
            // u = 0, u = 1, v = 0, v = 1, w = 0, w = 1: as G+Smo and GeoPDEs number a volume's sides.
            if (i == 0) o.cell.boundary[kSideLeft] = 0;
            if (i + 1 == u_.elements(l)) o.cell.boundary[kSideRight] = 1;
            if (j == 0) o.cell.boundary[kSideBottom] = 2;
            if (j + 1 == v_.elements(l)) o.cell.boundary[kSideTop] = 3;
            if (k == 0) o.cell.boundary[kSideFront] = 4;
            if (k + 1 == w_->elements(l)) o.cell.boundary[kSideBack] = 5;
          } else {
            if (j == 0) o.cell.boundary[kSideBottom] = 0;
            if (i + 1 == u_.elements(l)) o.cell.boundary[kSideRight] = 1;
            if (j + 1 == v_.elements(l)) o.cell.boundary[kSideTop] = 2;
            if (i == 0) o.cell.boundary[kSideLeft] = 3;
          }
          if (!holes_.empty()) {  // the faces that meet a removed cell: boundary "hole"
            const std::int16_t hole = w_ ? 6 : 4;
            const std::pair<CellSide, Key> neighbours[6] = {
                {kSideLeft, {i - 1, j, k}},  {kSideRight, {i + 1, j, k}}, {kSideBottom, {i, j - 1, k}},
                {kSideTop, {i, j + 1, k}},   {kSideFront, {i, j, k - 1}}, {kSideBack, {i, j, k + 1}}};
            for (int n = 0; n < 2 * d; ++n) {
              const auto& [side, at] = neighbours[n];
              if (at[0] >= 0 && at[1] >= 0 && at[2] >= 0 && at[0] < u_.elements(l) && at[1] < v_.elements(l) &&
                  at[2] < elements(2, l) && in_hole(l, at))
                o.cell.boundary[side] = hole;
            }
          }
          o.extraction.resize(static_cast<int>(f.ids.size()), (p + 1) * nb);
          for (size_t a = 0; a < f.ids.size(); ++a) {
            half.noalias() = Eu.transpose() * coefficients_of(f, a);
            product.noalias() = half * *Evw;
            o.extraction.row(static_cast<int>(a)) = Eigen::Map<const Eigen::RowVectorXd>(product.data(), product.size());
          }
          o.ids = std::move(f.ids);
          o.extraction_hash = PooledExtractions::hash(o.extraction);
          per_root[root].push_back(std::move(o));
          continue;
        }
        // Children pushed in reverse so that they are visited in the order (0,0), (1,0), (0,1),
        // (1,1) (then the same at the far w on a volume).
        for (int child = children - 1; child >= 0; --child) {
          const Key ck{2 * i + (child & 1), 2 * j + ((child >> 1) & 1), w_ ? 2 * k + (child >> 2) : 0};
          const Eigen::MatrixXd& Ru = tables[l + 1][0].refinement.at(ck[0]);
          const Eigen::MatrixXd* Rvw =
              across(tables[l + 1][1].refinement.at(ck[1]), w_ ? &tables[l + 1][2].refinement.at(ck[2]) : nullptr, kron);
          // The child level's B-splines on the child; those whose support is in the refined
          // region (in_level) truncate the coarser functions.
          look_up(l + 1, ck);
          Frame next{l + 1, ck, {}, {}};
          next.ids.reserve(f.ids.size() + block);
          next.coefficients.reserve((f.ids.size() + block) * block);
          for (size_t g = 0; g < f.ids.size(); ++g) {
            half.noalias() = Ru.transpose() * coefficients_of(f, g);
            const size_t at = next.coefficients.size();
            next.coefficients.resize(at + block);
            Eigen::Map<Eigen::MatrixXd> Y(next.coefficients.data() + at, p + 1, nb);
            Y.noalias() = half * *Rvw;
            bool any = false;
            for (int b = 0; b < nb; ++b)
              for (int a = 0; a <= p; ++a) {
                if (on_cell[a + (p + 1) * b]->in_level) Y(a, b) = 0;
                any = any || Y(a, b) != 0;
              }
            if (any) next.ids.push_back(f.ids[g]);
            else next.coefficients.resize(at);
          }
          join_active(next);
          stack.push_back(std::move(next));
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
  std::vector<std::string> names = w_ ? std::vector<std::string>{"1", "2", "3", "4", "5", "6"}
                                      : std::vector<std::string>{"bottom", "right", "top", "left"};
  if (!holes_.empty()) names.push_back("hole");
  out.mesh.set_boundary_names(std::move(names));
  out.leaves.reserve(cells_total);
  // Identical extraction matrices (most cells away from level changes) are pooled.
  PooledExtractions pooled(out.mesh);
  for (auto& v : per_root)
    for (CellOut& o : v) {
      out.mesh.add_cell(o.cell, o.ids, pooled.add(std::move(o.extraction), o.extraction_hash));
      out.leaves.push_back(o.leaf);
    }
  return out;
}

}  // namespace knotwork
