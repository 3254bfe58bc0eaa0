#include "basis/tensor/tensor_patch.hpp"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>

namespace knotwork {

namespace {

struct DirectionPlan {
  BSplineBasis1D space, geometry;
};

DirectionPlan plan_direction(const BSplineBasis1D& g, int p, int r, int elements, bool rational,
                             const std::vector<double>& extra, const char* name) {
  const int pg = g.degree();
  if (p < 1) throw std::invalid_argument(std::string("degree in ") + name + " must be >= 1");
  if (r < 0 || r > p - 1)
    throw std::invalid_argument(std::string("continuity in ") + name + " must be in [0, degree-1] = [0, " +
                                std::to_string(p - 1) + "], got " + std::to_string(r));
  if (rational && p < pg)
    throw std::invalid_argument(
        std::string("degree ") + std::to_string(p) + " in " + name + " is below the geometry degree " +
        std::to_string(pg) + ": an isoparametric NURBS space needs degree >= " + std::to_string(pg) +
        "; set rational = false to use B-splines of degree " + std::to_string(p) +
        " on the exact geometry");
  const auto bp = g.breakpoints();
  const auto mult = g.multiplicities();
  std::vector<double> ks(p + 1, bp.front()), kg(std::max(p, pg) + 1, bp.front());
  for (size_t i = 0; i + 1 < bp.size(); ++i) {
    if (i > 0) {  // original interior knot: keep min(its continuity, r)
      const int c_old = pg - mult[i];
      ks.insert(ks.end(), p - std::min(c_old, r), bp[i]);
      kg.insert(kg.end(), p >= pg ? p - std::min(c_old, r) : mult[i], bp[i]);
    }
    for (int e = 1; e < elements; ++e) {
      const double t = bp[i] + (bp[i + 1] - bp[i]) * e / elements;
      ks.insert(ks.end(), p - r, t);
      kg.insert(kg.end(), p >= pg ? p - r : 1, t);
    }
  }
  std::vector<double> added;
  for (double t : extra) {
    if (!(std::isfinite(t) && t > bp.front() && t < bp.back()))
      throw std::invalid_argument(std::string("extra knot ") + std::to_string(t) + " in " + name +
                                  " is not inside the parameter domain (" + std::to_string(bp.front()) + ", " +
                                  std::to_string(bp.back()) + ")");
    if (std::find(ks.begin(), ks.end(), t) != ks.end() || std::find(added.begin(), added.end(), t) != added.end())
      continue;  // already a knot: nothing to refine
    added.push_back(t);
    ks.insert(ks.end(), p - r, t);
    kg.insert(kg.end(), p >= pg ? p - r : 1, t);
  }
  std::sort(ks.begin(), ks.end());
  std::sort(kg.begin(), kg.end());
  ks.insert(ks.end(), p + 1, bp.back());
  kg.insert(kg.end(), std::max(p, pg) + 1, bp.back());
  return {BSplineBasis1D(p, std::move(ks)), BSplineBasis1D(std::max(p, pg), std::move(kg))};
}

// Indices of identical (to 1e-13) matrices, so the 2D pool holds each product once.
std::vector<int> deduplicate(const std::vector<Eigen::MatrixXd>& ms, std::vector<int>& representative) {
  std::vector<int> id(ms.size());
  for (size_t i = 0; i < ms.size(); ++i) {
    id[i] = -1;
    for (size_t r = 0; r < representative.size(); ++r)
      if ((ms[representative[r]] - ms[i]).cwiseAbs().maxCoeff() < 1e-13) {
        id[i] = static_cast<int>(r);
        break;
      }
    if (id[i] < 0) {
      id[i] = static_cast<int>(representative.size());
      representative.push_back(static_cast<int>(i));
    }
  }
  return id;
}

// The extraction of a tensor-product cell: the Kronecker product of its univariate ones (u
// fastest), row a + p_u b [+ p_u p_v c], column likewise.
Eigen::MatrixXd kronecker(std::span<const Eigen::MatrixXd* const> factors) {
  Eigen::MatrixXd C = *factors[0];
  for (size_t d = 1; d < factors.size(); ++d) {
    const Eigen::MatrixXd& f = *factors[d];
    const Eigen::Index pc = C.rows(), pf = f.rows();
    Eigen::MatrixXd next(pc * pf, pc * pf);
    for (Eigen::Index a = 0; a < pf; ++a)
      for (Eigen::Index i = 0; i < pc; ++i)
        for (Eigen::Index b = 0; b < pf; ++b)
          for (Eigen::Index j = 0; j < pc; ++j) next(i + pc * a, j + pc * b) = C(i, j) * f(a, b);
    C.swap(next);
  }
  return C;
}

}  // namespace

namespace {

std::array<DirectionPlan, 2> plan_patch(const NurbsPatch& patch, const TensorSpaceOptions& o) {
  patch.validate();
  const int ru = o.continuity[0] < 0 ? o.degree[0] - 1 : o.continuity[0];
  const int rv = o.continuity[1] < 0 ? o.degree[1] - 1 : o.continuity[1];
  if (o.elements_per_span[0] < 1 || o.elements_per_span[1] < 1)
    throw std::invalid_argument("elements must be >= 1");
  return {plan_direction(patch.basis_u, o.degree[0], ru, o.elements_per_span[0], o.rational, o.extra_knots[0], "u"),
          plan_direction(patch.basis_v, o.degree[1], rv, o.elements_per_span[1], o.rational, o.extra_knots[1], "v")};
}

}  // namespace

std::array<BSplineBasis1D, 2> tensor_space_bases(const NurbsPatch& patch, const TensorSpaceOptions& options) {
  const auto plan = plan_patch(patch, options);
  return {plan[0].space, plan[1].space};
}

Eigen::MatrixX3d refined_homogeneous_net(const NurbsPatch& patch, const BSplineBasis1D& geometry_u,
                                         const BSplineBasis1D& geometry_v, int first_row, int rows) {
  const Eigen::SparseMatrix<double> Tu = refinement_matrix(patch.basis_u, geometry_u);
  const Eigen::SparseMatrix<double, Eigen::RowMajor> Tv_all = refinement_matrix(patch.basis_v, geometry_v);
  if (rows < 0) rows = geometry_v.num_functions() - first_row;
  if (first_row < 0 || first_row + rows > geometry_v.num_functions())
    throw std::logic_error("refined_homogeneous_net: net rows outside the geometry's");
  const int nu = patch.basis_u.num_functions(), nv = patch.basis_v.num_functions();
  const int gu = geometry_u.num_functions();
  const Eigen::SparseMatrix<double> Tv = Tv_all.middleRows(first_row, rows);
  Eigen::MatrixX3d net(static_cast<Eigen::Index>(gu) * rows, 3);
  // Equal weights (a polynomial map) stay equal: T w = w_0 T 1 = w_0 by the partition of unity.
  // Computed, they would carry the refinement's rounding, which grows with the knots inserted
  // (67 eps at degree 4 and 1000 elements), and the map would pass for a rational one.
  const bool equal_weights = (patch.weights.array() == patch.weights[0]).all();
  if (equal_weights) net.col(2).setConstant(patch.weights[0]);
  for (int k = 0; k < (equal_weights ? 2 : 3); ++k) {
    Eigen::VectorXd h(static_cast<Eigen::Index>(nu) * nv);
    for (Eigen::Index i = 0; i < h.size(); ++i)
      h[i] = k < 2 ? patch.weights[i] * patch.control_points(i, k) : patch.weights[i];
    const Eigen::MatrixXd H = Eigen::Map<const Eigen::MatrixXd>(h.data(), nu, nv);
    const Eigen::MatrixXd Hv = (Tv * H.transpose()).transpose();  // refined along v: nu x rows
    // Written in place (no gu x rows temporary: 134 MB per column at 4096^2).
    Eigen::Map<Eigen::MatrixXd>(net.col(k).data(), gu, rows).noalias() = Tu * Hv;
  }
  return net;
}

void add_tensor_cells(BezierMesh& mesh, std::span<const BSplineBasis1D> bases, int slab_from, int slab_to,
                      int offset) {
  const int dim = static_cast<int>(bases.size());
  if (dim != 2 && dim != 3) throw std::logic_error("add_tensor_cells: 2 or 3 directions");
  // A 2D grid is one layer of a 3D one: one element along w, of degree 0, on span 0.
  std::array<std::vector<int>, 3> spans{std::vector<int>{}, std::vector<int>{}, std::vector<int>{0}}, distinct,
      representative;
  std::array<std::vector<Eigen::MatrixXd>, 3> extraction;
  std::array<int, 3> degree{0, 0, 0}, functions{1, 1, 1}, elements{1, 1, 1};
  std::array<int, 3> stride{0, 0, 0};  // of the pool index over distinct extractions
  int pool_size = 1;
  for (int k = 0; k < dim; ++k) {
    spans[k] = bases[k].element_spans();
    extraction[k] = bezier_extraction(bases[k]);
    distinct[k] = deduplicate(extraction[k], representative[k]);
    degree[k] = bases[k].degree();
    functions[k] = bases[k].num_functions();
    elements[k] = static_cast<int>(spans[k].size());
    stride[k] = pool_size;
    pool_size *= static_cast<int>(representative[k].size());
  }
  const int last = dim - 1;  // the slabs run along the last direction
  if (slab_from < 0 || slab_to > elements[last] || slab_from >= slab_to)
    throw std::logic_error("add_tensor_cells: slabs outside the grid");
  // The pool's matrix of each tuple of distinct univariate extractions, made on first use.
  std::vector<int> pool_index(pool_size, -1);
  const std::array<int, 3> bernstein{degree[0] + 1, degree[1] + 1, degree[2] + 1};
  std::vector<int> ids(bernstein[0] * bernstein[1] * bernstein[2]);
  long cells = slab_to - slab_from;
  for (int k = 0; k < last; ++k) cells *= elements[k];
  mesh.reserve(static_cast<int>(cells), cells * static_cast<long>(ids.size()));
  mesh.set_boundary_names(dim == 2 ? std::vector<std::string>{"bottom", "right", "top", "left"}
                                   : std::vector<std::string>{"1", "2", "3", "4", "5", "6"});
  // A side's boundary id: 2D bottom, right, top, left; 3D u = 0, u = 1, v = 0, v = 1, w = 0,
  // w = 1 (the order G+Smo and GeoPDEs number a volume's sides in).
  constexpr std::array<CellSide, 3> side_low{kSideLeft, kSideBottom, kSideFront}, side_high{kSideRight, kSideTop, kSideBack};
  const auto boundary_id = [dim](int k, bool high) {
    if (dim == 3) return 2 * k + (high ? 1 : 0);
    return k == 0 ? (high ? 1 : 3) : (high ? 2 : 0);
  };
  std::array<int, 3> from{0, 0, 0}, to = elements, e{0, 0, 0};
  from[last] = slab_from;
  to[last] = slab_to;
  const Eigen::MatrixXd* factors[3];
  for (e[2] = from[2]; e[2] < to[2]; ++e[2])
    for (e[1] = from[1]; e[1] < to[1]; ++e[1])
      for (e[0] = from[0]; e[0] < to[0]; ++e[0]) {
        int key = 0;
        for (int k = 0; k < dim; ++k) key += stride[k] * distinct[k][e[k]];
        int& pooled = pool_index[key];
        if (pooled < 0) {
          for (int k = 0; k < dim; ++k) factors[k] = &extraction[k][representative[k][distinct[k][e[k]]]];
          pooled = mesh.add_extraction(kronecker({factors, static_cast<size_t>(dim)}));
        }
        BezierCell cell;
        cell.dimension = static_cast<std::int8_t>(dim);
        double* box[3][2] = {{&cell.u0, &cell.u1}, {&cell.v0, &cell.v1}, {&cell.w0, &cell.w1}};
        int* index[3] = {&cell.index_u, &cell.index_v, &cell.index_w};
        for (int k = 0; k < dim; ++k) {
          const std::vector<double>& knots = bases[k].knots();
          *index[k] = e[k];
          *box[k][0] = knots[spans[k][e[k]]];
          *box[k][1] = knots[spans[k][e[k]] + 1];
          if (e[k] == 0) cell.boundary[side_low[k]] = static_cast<std::int16_t>(boundary_id(k, false));
          if (e[k] == elements[k] - 1) cell.boundary[side_high[k]] = static_cast<std::int16_t>(boundary_id(k, true));
        }
        cell.degree_u = degree[0];
        cell.degree_v = degree[1];
        cell.degree_w = static_cast<std::int16_t>(degree[2]);
        for (int c = 0; c < bernstein[2]; ++c)
          for (int b = 0; b < bernstein[1]; ++b)
            for (int a = 0; a < bernstein[0]; ++a)
              ids[a + bernstein[0] * (b + bernstein[1] * c)] =
                  (spans[0][e[0]] - degree[0] + a) +
                  functions[0] * ((spans[1][e[1]] - degree[1] + b) + functions[1] * (spans[2][e[2]] - degree[2] + c)) -
                  offset;
        mesh.add_cell(cell, ids, pooled);
      }
}

namespace {

// One rank's share of the layers of elements along the last direction (rows along v on a patch,
// slabs along w on a volume), whose univariate basis has element spans `spans`, degree `q` and
// `functions` functions. Function layer j lives on the elements whose span s has s - q <= j <= s:
// a rank owns the function layers that start on its own element layers, and holds the layers
// below its own where they also live. `what`, `how` and `more` word the refusal of fewer layers
// than ranks.
struct LayerShare {
  int from = 0, to = 0, function_from = 0, function_to = 0;  // held
  int own_from = 0, own_to = 0, owned_from = 0, owned_to = 0;  // owned
  int functions = 0;
  // The MeshPart of the share: `per_layer` functions and `cells_per_layer` cells in each layer.
  MeshPart part(int per_layer, int cells_per_layer, int element_layers) const {
    MeshPart p;
    p.owned = CellRange{(own_from - from) * cells_per_layer, (own_to - from) * cells_per_layer};
    p.function_offset = per_layer * function_from;
    p.first_owned_function = per_layer * owned_from;
    p.last_owned_function = per_layer * owned_to;
    p.global_functions = per_layer * functions;
    p.global_cells = cells_per_layer * element_layers;
    return p;
  }
};

LayerShare share_layers(const std::vector<int>& spans, int q, int functions, RowShare share, const std::string& what,
                        const std::string& how, const std::string& more) {
  const long n = static_cast<long>(spans.size());
  if (n < share.ranks)
    throw std::invalid_argument("the mesh has " + std::to_string(n) + " " + what + ", fewer than the " + std::to_string(share.ranks) +
                                " processes that share them " + how + std::to_string(n) + more);
  LayerShare l;
  l.functions = functions;
  l.own_from = static_cast<int>(n * share.rank / share.ranks);
  l.own_to = static_cast<int>(n * (share.rank + 1) / share.ranks);
  const auto first_function = [&](int layer) { return layer == 0 ? 0 : spans[layer] - q; };
  l.owned_from = first_function(l.own_from);
  l.owned_to = l.own_to == n ? functions : first_function(l.own_to);
  l.from = l.own_from;
  while (l.from > 0 && spans[l.from - 1] >= l.owned_from) --l.from;
  l.to = l.own_to;
  l.function_from = spans[l.from] - q;
  l.function_to = spans[l.to - 1] + 1;
  return l;
}

}  // namespace

TensorDiscretization build_tensor_discretization(const NurbsPatch& patch, const TensorSpaceOptions& o,
                                                 RowShare share) {
  TensorDiscretization d;
  auto [pu, pv] = plan_patch(patch, o);
  d.space_u = pu.space;
  d.space_v = pv.space;
  d.geometry_u = pu.geometry;
  d.geometry_v = pv.geometry;
  d.patch = patch;

  const int q = o.degree[1];
  const int su = d.space_u.num_functions(), sv = d.space_v.num_functions();
  const auto spans_u = d.space_u.element_spans(), spans_v = d.space_v.element_spans();
  d.elements_u = static_cast<int>(spans_u.size());
  d.elements_v = static_cast<int>(spans_v.size());

  // The element rows this mesh holds, [row_from, row_to), and its function rows.
  int row_from = 0, row_to = d.elements_v, function_row_from = 0, function_row_to = sv;
  if (share.ranks > 1) {
    const LayerShare l = share_layers(spans_v, q, sv, share, "rows of cells along v", "by rows: use at most ", " processes or more elements");
    row_from = l.from, row_to = l.to, function_row_from = l.function_from, function_row_to = l.function_to;
    d.part = l.part(su, d.elements_u, d.elements_v);
  }
  d.first_row = row_from;

  // The homogeneous control net on the geometry bases; a part keeps the net rows its element
  // rows use.
  const auto geometry_spans_v = d.geometry_v.element_spans();
  d.net_first_row = geometry_spans_v[row_from] - d.geometry_v.degree();
  const int net_rows = geometry_spans_v[row_to - 1] + 1 - d.net_first_row;
  d.geometry_homogeneous = refined_homogeneous_net(patch, d.geometry_u, d.geometry_v, d.net_first_row, net_rows);

  BezierMesh& mesh = d.mesh;
  const int offset = su * function_row_from;
  mesh.set_num_functions(su * (function_row_to - function_row_from));
  // Geometry and space bases coincide (degree >= the geometry's), so do the net's rows.
  if (o.rational) mesh.set_weights(d.geometry_homogeneous.col(2));

  const std::array<BSplineBasis1D, 2> bases{d.space_u, d.space_v};
  add_tensor_cells(mesh, bases, row_from, row_to, offset);
  return d;
}

TensorVolumeDiscretization build_tensor_volume(const NurbsVolume& volume, const TensorVolumeOptions& o, RowShare share) {
  volume.validate();
  static const char* const names[3] = {"u", "v", "w"};
  TensorVolumeDiscretization d;
  d.volume = volume;
  std::array<BSplineBasis1D, 3> geometry;
  for (int k = 0; k < 3; ++k) {
    if (o.elements_per_span[k] < 1) throw std::invalid_argument(std::string("elements in ") + names[k] + " must be >= 1");
    const int r = o.continuity[k] < 0 ? o.degree[k] - 1 : o.continuity[k];
    DirectionPlan plan =
        plan_direction(volume.bases[k], o.degree[k], r, o.elements_per_span[k], o.rational, o.extra_knots[k], names[k]);
    d.space[k] = std::move(plan.space);
    geometry[k] = std::move(plan.geometry);
  }
  const long functions = long(d.space[0].num_functions()) * d.space[1].num_functions() * d.space[2].num_functions();
  if (functions > std::numeric_limits<int>::max()) throw std::invalid_argument("more than 2^31 functions");
  // The slabs of elements along w this mesh holds, [slab_from, slab_to), and its function
  // slabs [function_from, function_to): the rows along v of a patch's parts, one direction up.
  const std::vector<int> spans_w = d.space[2].element_spans();
  const int nw = static_cast<int>(spans_w.size()), r = d.space[2].degree(), sw = d.space[2].num_functions();
  const long layer = long(d.space[0].num_functions()) * d.space[1].num_functions();  // functions per slab
  const long cells_per_slab = long(d.space[0].num_elements()) * d.space[1].num_elements();
  int slab_from = 0, slab_to = nw, function_from = 0, function_to = sw;
  if (share.ranks > 1) {
    const LayerShare l = share_layers(spans_w, r, sw, share, nw == 1 ? "slab of cells along w" : "slabs of cells along w",
                                      "by slabs: use at most ", " processes or more elements along w");
    slab_from = l.from, slab_to = l.to, function_from = l.function_from, function_to = l.function_to;
    d.part = l.part(static_cast<int>(layer), static_cast<int>(cells_per_slab), nw);
  }
  d.mesh.set_num_functions(static_cast<int>(layer * (function_to - function_from)));
  // The isoparametric space's weights: the volume's refined onto the geometry's bases (the
  // space's, since its degree is at least the volume's), one direction at a time. Equal weights
  // stay equal (the refinement is a partition of unity) and are left out: B-splines.
  const bool equal_weights = (volume.weights.array() == volume.weights[0]).all();
  if (o.rational && !equal_weights) {
    Eigen::MatrixXd w = volume.weights;  // n_u x (n_v n_w), then refined along u, v and w
    std::array<int, 3> n;
    for (int k = 0; k < 3; ++k) n[k] = volume.bases[k].num_functions();
    w.resize(n[0], n[1] * n[2]);
    Eigen::MatrixXd along_u = refinement_matrix(volume.bases[0], geometry[0]) * w;  // g_u x (n_v n_w)
    const Eigen::SparseMatrix<double> tv = refinement_matrix(volume.bases[1], geometry[1]);
    const int gu = geometry[0].num_functions(), gv = geometry[1].num_functions(), gw = geometry[2].num_functions();
    Eigen::MatrixXd along_v(static_cast<Eigen::Index>(gu) * gv, n[2]);
    for (int k = 0; k < n[2]; ++k) {
      const Eigen::MatrixXd slab = along_u.middleCols(static_cast<Eigen::Index>(k) * n[1], n[1]);  // g_u x n_v
      Eigen::Map<Eigen::MatrixXd>(along_v.col(k).data(), gu, gv) = slab * Eigen::MatrixXd(tv).transpose();
    }
    const Eigen::MatrixXd along_w = along_v * Eigen::MatrixXd(refinement_matrix(volume.bases[2], geometry[2])).transpose();
    // A part keeps its function slabs' weights.
    d.mesh.set_weights(Eigen::Map<const Eigen::VectorXd>(along_w.data(), static_cast<Eigen::Index>(gu) * gv * gw)
                           .segment(layer * function_from, layer * (function_to - function_from)));
  }
  add_tensor_cells(d.mesh, d.space, slab_from, slab_to, static_cast<int>(layer * function_from));
  return d;
}

}  // namespace knotwork
