#include "solver/sparsity.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>

#include <omp.h>

namespace knotwork {

DofLayout make_dof_layout(int n, const std::vector<bool>& fixed) {
  DofLayout l;
  l.dof.assign(n, -1);
  for (int f = 0; f < n; ++f)
    if (!fixed[f]) {
      l.dof[f] = static_cast<int>(l.function_of_dof.size());
      l.function_of_dof.push_back(f);
    }
  return l;
}

namespace {

// The cells of every function, compressed: function f's cells (ascending) are
// cells[start[f] .. start[f + 1]).
struct FunctionCells {
  std::vector<int> start, cells;
};

FunctionCells function_cells(const BezierMesh& mesh) {
  const int nf = mesh.num_functions(), nc = mesh.num_cells();
  FunctionCells fc;
  fc.start.assign(nf + 1, 0);
  for (int c = 0; c < nc; ++c)
    for (int f : mesh.functions(c)) ++fc.start[f + 1];
  for (int f = 0; f < nf; ++f) fc.start[f + 1] += fc.start[f];
  fc.cells.resize(fc.start[nf]);
  std::vector<int> fill(fc.start.begin(), fc.start.end() - 1);
  for (int c = 0; c < nc; ++c)
    for (int f : mesh.functions(c)) fc.cells[fill[f]++] = c;
  return fc;
}

// Appends to `out` the free dofs coupled to dof j through its function's cells in
// [first_cell, last_cell), those >= lowest, ascending. A function meets each neighbour once per
// shared cell ((p+1)^2 times in the interior of a tensor mesh): a per-thread stamp (the dof last
// seen) keeps each once, so only the distinct ones are sorted.
void coupled_dofs(const BezierMesh& mesh, const DofLayout& layout, const FunctionCells& fc, int j, int lowest,
                  int first_cell, int last_cell, std::vector<int>& out, std::vector<int>& seen) {
  const size_t begin = out.size();
  const int f = layout.function_of_dof[j];
  for (int k = fc.start[f]; k < fc.start[f + 1]; ++k) {
    const int c = fc.cells[k];
    if (c < first_cell || c >= last_cell) continue;
    for (int g : mesh.functions(c)) {
      const int d = layout.dof[g];
      if (d >= lowest && seen[d] != j) {
        seen[d] = j;
        out.push_back(d);
      }
    }
  }
  std::sort(out.begin() + begin, out.end());
}

// Rows 0..n-1 of S compressed patterns listed in one pass: list(i, out, seen) appends row i's
// entries to out[0..S) (seen: a stamp vector of n, for coupled_dofs). Each thread lists a
// contiguous block of rows into its own pieces, joined in order afterwards, so nothing is
// listed twice (a count pass and a fill pass would list every row twice). start: n + 1 offsets.
struct Compressed {
  std::vector<int> start, entries;
};

template <int S, class List>
std::array<Compressed, S> compress_rows(int n, List list) {
  const int threads = omp_get_max_threads();
  std::vector<std::array<Compressed, S>> pieces(threads);
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num(), nt = omp_get_num_threads();
    const int begin = static_cast<int>(long(n) * t / nt), end = static_cast<int>(long(n) * (t + 1) / nt);
    std::array<Compressed, S> mine;  // the thread's own (in `pieces` their ends would share cache lines)
    std::array<std::vector<int>*, S> out;
    for (int k = 0; k < S; ++k) {
      mine[k].start.assign(end - begin + 1, 0);
      out[k] = &mine[k].entries;
    }
    std::vector<int> seen(n, -1);
    for (int i = begin; i < end; ++i) {
      list(i, out, seen);
      for (int k = 0; k < S; ++k) mine[k].start[i - begin + 1] = static_cast<int>(out[k]->size());
    }
    pieces[t] = std::move(mine);
  }
  std::array<Compressed, S> joined;
  for (int k = 0; k < S; ++k) {
    Compressed& c = joined[k];
    c = std::move(pieces[0][k]);  // thread 0's rows come first, as they are
    c.start.reserve(n + 1);
    for (int t = 1; t < threads; ++t) {
      const Compressed& p = pieces[t][k];
      if (p.start.empty()) continue;  // a thread the runtime did not start had no rows
      const int offset = static_cast<int>(c.entries.size());
      for (size_t i = 1; i < p.start.size(); ++i) c.start.push_back(offset + p.start[i]);
      c.entries.insert(c.entries.end(), p.entries.begin(), p.entries.end());
      pieces[t][k] = Compressed();
    }
  }
  return joined;
}

}  // namespace

Eigen::SparseMatrix<double> lower_pattern_matrix(const BezierMesh& mesh, const DofLayout& layout) {
  // For each column the sorted set of coupled dofs below the diagonal, in two threaded passes
  // (count, fill) straight into Eigen's arrays: the threads share the first touch of their
  // memory, which costs more than listing the columns (compress_rows would copy them in).
  const FunctionCells fc = function_cells(mesh);
  const int nc = mesh.num_cells();
  const int n = layout.num_free();
  Eigen::SparseMatrix<double> A(n, n);
  int* outer = A.outerIndexPtr();
  outer[0] = 0;
#pragma omp parallel
  {
    std::vector<int> rows, seen(n, -1);
#pragma omp for schedule(static)
    for (int j = 0; j < n; ++j) {
      rows.clear();
      coupled_dofs(mesh, layout, fc, j, j, 0, nc, rows, seen);
      outer[j + 1] = static_cast<int>(rows.size());
    }
  }
  for (int j = 0; j < n; ++j) outer[j + 1] += outer[j];
  A.resizeNonZeros(outer[n]);
  int* inner = A.innerIndexPtr();
  double* values = A.valuePtr();
#pragma omp parallel
  {
    std::vector<int> rows, seen(n, -1);
#pragma omp for schedule(static)
    for (int j = 0; j < n; ++j) {
      rows.clear();
      coupled_dofs(mesh, layout, fc, j, j, 0, nc, rows, seen);
      std::copy(rows.begin(), rows.end(), inner + outer[j]);
      std::fill(values + outer[j], values + outer[j + 1], 0.0);
    }
  }
  return A;
}

std::vector<int> diagonal_positions(const OwnedRows& o) {
  const int n = static_cast<int>(o.diagonal_start.size()) - 1;
  std::vector<int> at(n);
  for (int i = 0; i < n; ++i) {
    const int* begin = o.diagonal_cols.data() + o.diagonal_start[i];
    const int* end = o.diagonal_cols.data() + o.diagonal_start[i + 1];
    const int* diagonal = std::lower_bound(begin, end, i);
    if (diagonal == end || *diagonal != i) throw std::logic_error("diagonal_positions: a row without its diagonal entry");
    at[i] = static_cast<int>(diagonal - o.diagonal_cols.data());
  }
  return at;
}

void mirror_diagonal_block(OwnedRows& o, const std::vector<int>& diagonal) {
  const int n = static_cast<int>(o.diagonal_start.size()) - 1;
  // Row j's lower entries (j, i), i ascending, are the upper entries (i, j) of the rows i < j,
  // met in row order: one cursor per row, from just after its diagonal.
  std::vector<int> cursor(n);
  for (int i = 0; i < n; ++i) cursor[i] = diagonal[i] + 1;
  for (int j = 0; j < n; ++j)
    for (int q = o.diagonal_start[j]; q < diagonal[j]; ++q) {
      const int i = o.diagonal_cols[q];
      const int source = cursor[i]++;
      if (source >= o.diagonal_start[i + 1] || o.diagonal_cols[source] != j)
        throw std::logic_error("mirror_diagonal_block: the diagonal block's pattern is not symmetric");
      o.values[q] = o.values[source];
    }
}

namespace {

// The owned dofs [first, last) of `global_row` (increasing), whose rows are [first_row, last_row).
void find_owned(RankRows& r, int first_row, int last_row) {
  const std::vector<int>& g = r.global_row;
  r.first = static_cast<int>(std::lower_bound(g.begin(), g.end(), first_row) - g.begin());
  r.last = static_cast<int>(std::lower_bound(g.begin(), g.end(), last_row) - g.begin());
  if (r.last - r.first != last_row - first_row)
    throw std::logic_error("rank rows: this rank's mesh does not hold all of its rows");
}

// Owned row d's columns from its function's couplings (coupled: ascending functions, itself
// included): ascending functions are ascending dofs and rows, the owned ones for the diagonal
// block (numbered from `first`), the others for the off-diagonal one (as global rows).
void owned_row_from_couplings(const DofLayout& layout, const RankRows& r, int d, const CoupledFunctions& coupled,
                              std::vector<int>& functions, std::vector<int>& diagonal, std::vector<int>& off) {
  functions.clear();
  coupled(layout.function_of_dof[d], functions);
  for (int f : functions) {
    const int c = layout.dof[f];
    if (c < 0) continue;
    if (c >= r.first && c < r.last) diagonal.push_back(c - r.first);
    else off.push_back(r.global_row[c]);
  }
}

}  // namespace

RankRows owned_rows_pattern(const DofLayout& layout, std::vector<int> global_row, int first_row, int last_row,
                            const CoupledFunctions& coupled) {
  RankRows r;
  r.global_row = std::move(global_row);
  find_owned(r, first_row, last_row);
  std::array<Compressed, 2> p =
      compress_rows<2>(r.last - r.first, [&](int k, std::array<std::vector<int>*, 2>& out, std::vector<int>&) {
        thread_local std::vector<int> functions;
        owned_row_from_couplings(layout, r, r.first + k, coupled, functions, *out[0], *out[1]);
      });
  OwnedRows& o = r.owned;
  o.diagonal_start = std::move(p[0].start);
  o.off_start = std::move(p[1].start);
  o.diagonal_cols = std::move(p[0].entries);
  o.off_cols = std::move(p[1].entries);
  r.halo_start.assign(layout.num_free() + 1, 0);
  o.values.assign(r.halo_offset(), 0.0);
  return r;
}

RankRows rank_rows_pattern(const BezierMesh& mesh, const DofLayout& layout, std::vector<int> global_row, int first_row,
                           int last_row, CellRange own_cells, const CoupledFunctions* coupled) {
  const FunctionCells fc = function_cells(mesh);
  const int n = layout.num_free();
  RankRows r;
  r.global_row = std::move(global_row);
  const std::vector<int>& g = r.global_row;
  find_owned(r, first_row, last_row);
  const int first_cell = own_cells.first, last_cell = own_cells.last < 0 ? mesh.num_cells() : own_cells.last;
  const auto is_owned = [&](int d) { return d >= r.first && d < r.last; };
  // Three patterns over all free dofs: the diagonal block's and the off-diagonal block's
  // (empty but on owned rows) and the halo's (empty on owned rows).
  std::array<Compressed, 3> p =
      compress_rows<3>(n, [&](int d, std::array<std::vector<int>*, 3>& out, std::vector<int>& seen) {
        if (!is_owned(d)) {
          coupled_dofs(mesh, layout, fc, d, 0, first_cell, last_cell, *out[2], seen);
          return;
        }
        if (coupled) {
          thread_local std::vector<int> functions;
          owned_row_from_couplings(layout, r, d, *coupled, functions, *out[0], *out[1]);
          return;
        }
        std::vector<int>& off = *out[1];
        const size_t begin = off.size();
        coupled_dofs(mesh, layout, fc, d, 0, 0, mesh.num_cells(), off, seen);
        // Ascending: the columns before `first`, the owned ones, the ones after `last`. The
        // owned ones move to the diagonal block (numbered from `first`), the others keep their
        // place as global rows.
        const auto lo = std::lower_bound(off.begin() + begin, off.end(), r.first);
        const auto hi = std::lower_bound(lo, off.end(), r.last);
        for (auto c = lo; c != hi; ++c) out[0]->push_back(*c - r.first);
        const auto kept = std::copy(hi, off.end(), lo);
        off.erase(kept, off.end());
        for (auto c = off.begin() + begin; c != off.end(); ++c) *c = g[*c];
      });
  OwnedRows& o = r.owned;
  o.diagonal_start.assign(p[0].start.begin() + r.first, p[0].start.begin() + r.last + 1);
  o.off_start.assign(p[1].start.begin() + r.first, p[1].start.begin() + r.last + 1);
  o.diagonal_cols = std::move(p[0].entries);
  o.off_cols = std::move(p[1].entries);
  r.halo_start = std::move(p[2].start);
  r.halo_cols = std::move(p[2].entries);
  o.values.assign(r.halo_offset() + r.halo_start[n], 0.0);
  return r;
}

}  // namespace knotwork
