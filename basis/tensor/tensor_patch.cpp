#include "basis/tensor/tensor_patch.hpp"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
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

Eigen::MatrixXd kronecker(const Eigen::MatrixXd& cu, const Eigen::MatrixXd& cv) {
  const int pu = static_cast<int>(cu.rows()), pv = static_cast<int>(cv.rows());
  Eigen::MatrixXd C(pu * pv, pu * pv);
  for (int av = 0; av < pv; ++av)
    for (int au = 0; au < pu; ++au)
      for (int bv = 0; bv < pv; ++bv)
        for (int bu = 0; bu < pu; ++bu) C(au + pu * av, bu + pu * bv) = cu(au, bu) * cv(av, bv);
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

TensorDiscretization build_tensor_discretization(const NurbsPatch& patch, const TensorSpaceOptions& o,
                                                 RowShare share) {
  TensorDiscretization d;
  auto [pu, pv] = plan_patch(patch, o);
  d.space_u = pu.space;
  d.space_v = pv.space;
  d.geometry_u = pu.geometry;
  d.geometry_v = pv.geometry;
  d.patch = patch;

  const int p = o.degree[0], q = o.degree[1];
  const int su = d.space_u.num_functions(), sv = d.space_v.num_functions();
  const auto spans_u = d.space_u.element_spans(), spans_v = d.space_v.element_spans();
  d.elements_u = static_cast<int>(spans_u.size());
  d.elements_v = static_cast<int>(spans_v.size());

  // The element rows this mesh holds, [row_from, row_to), and its function rows.
  int row_from = 0, row_to = d.elements_v, function_row_from = 0, function_row_to = sv;
  if (share.ranks > 1) {
    const long nv = d.elements_v;
    if (nv < share.ranks)
      throw std::invalid_argument("the mesh has " + std::to_string(nv) + " rows of cells along v, fewer than the " +
                                  std::to_string(share.ranks) + " processes that share them by rows: use at most " +
                                  std::to_string(nv) + " processes or more elements");
    const int own_from = static_cast<int>(nv * share.rank / share.ranks);
    const int own_to = static_cast<int>(nv * (share.rank + 1) / share.ranks);
    // Function row j lives on the elements whose span s has s - q <= j <= s: a rank owns the
    // function rows that start on its element rows, and holds the rows below its own where
    // they also live.
    const auto first_function_row = [&](int row) { return row == 0 ? 0 : spans_v[row] - q; };
    const int owned_functions_from = first_function_row(own_from);
    const int owned_functions_to = own_to == d.elements_v ? sv : first_function_row(own_to);
    row_from = own_from;
    while (row_from > 0 && spans_v[row_from - 1] >= owned_functions_from) --row_from;
    row_to = own_to;
    function_row_from = spans_v[row_from] - q;
    function_row_to = spans_v[row_to - 1] + 1;
    MeshPart part;
    part.owned = CellRange{(own_from - row_from) * d.elements_u, (own_to - row_from) * d.elements_u};
    part.function_offset = su * function_row_from;
    part.first_owned_function = su * owned_functions_from;
    part.last_owned_function = su * owned_functions_to;
    part.global_functions = su * sv;
    part.global_cells = d.elements_u * d.elements_v;
    d.part = part;
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
  mesh.set_boundary_names({"bottom", "right", "top", "left"});
  // Geometry and space bases coincide (degree >= the geometry's), so do the net's rows.
  if (o.rational) mesh.set_weights(d.geometry_homogeneous.col(2));

  const auto Cu = bezier_extraction(d.space_u), Cv = bezier_extraction(d.space_v);
  std::vector<int> rep_u, rep_v;
  const auto idu = deduplicate(Cu, rep_u), idv = deduplicate(Cv, rep_v);
  // The pool's matrix of each pair of distinct univariate extractions, made on first use.
  std::vector<int> pool_index(rep_u.size() * rep_v.size(), -1);
  const auto& U = d.space_u.knots();
  const auto& V = d.space_v.knots();
  std::vector<int> ids((p + 1) * (q + 1));
  const long cells = static_cast<long>(d.elements_u) * (row_to - row_from);
  mesh.reserve(static_cast<int>(cells), cells * (p + 1) * (q + 1));
  for (int iv = row_from; iv < row_to; ++iv)
    for (int iu = 0; iu < d.elements_u; ++iu) {
      int& pooled = pool_index[idu[iu] + rep_u.size() * idv[iv]];
      if (pooled < 0) pooled = mesh.add_extraction(kronecker(Cu[rep_u[idu[iu]]], Cv[rep_v[idv[iv]]]));
      BezierCell cell;
      cell.index_u = iu;
      cell.index_v = iv;
      cell.u0 = U[spans_u[iu]];
      cell.u1 = U[spans_u[iu] + 1];
      cell.v0 = V[spans_v[iv]];
      cell.v1 = V[spans_v[iv] + 1];
      cell.degree_u = p;
      cell.degree_v = q;
      if (iv == 0) cell.boundary[kSideBottom] = 0;
      if (iu == d.elements_u - 1) cell.boundary[kSideRight] = 1;
      if (iv == d.elements_v - 1) cell.boundary[kSideTop] = 2;
      if (iu == 0) cell.boundary[kSideLeft] = 3;
      for (int av = 0; av <= q; ++av)
        for (int au = 0; au <= p; ++au)
          ids[au + (p + 1) * av] = (spans_u[iu] - p + au) + su * (spans_v[iv] - q + av) - offset;
      mesh.add_cell(cell, ids, pooled);
    }
  return d;
}

}  // namespace knotwork
