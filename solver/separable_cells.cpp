#include "solver/separable_cells.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "basis/core/small_products.hpp"
#include "quadrature/bernstein.hpp"

namespace knotwork {

bool factor_separable(const Eigen::MatrixXd& C, int p, int q, SeparableExtraction& out) {
  const int nu = p + 1, nv = q + 1;
  out.u.resize(C.rows(), nu);
  out.v.resize(C.rows(), nv);
  for (Eigen::Index a = 0; a < C.rows(); ++a) {
    // M(i, j) = C(a, i + nu j): the row seen as a (nu x nv) matrix, in place.
    using RowView = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;
    const RowView M(C.data() + a, nu, nv, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(C.rows() * nu, C.rows()));
    Eigen::Index i0 = 0, j0 = 0;
    const double peak = M.cwiseAbs().maxCoeff(&i0, &j0);
    if (!(peak > 0)) return false;
    out.u.row(a) = M.col(j0).transpose();
    out.v.row(a) = M.row(i0) / M(i0, j0);
    const double misfit = (M - out.u.row(a).transpose() * out.v.row(a)).cwiseAbs().maxCoeff();
    if (!(misfit <= 1e-13 * peak)) return false;
  }
  return true;
}

SeparableMesh::SeparableMesh(const BezierMesh& mesh) {
  const int n = mesh.num_distinct_extractions();
  rows.resize(n);
  separable.assign(n, 0);
  // The degrees of a pooled matrix, from the first cell that uses it.
  std::vector<int> p(n, -1), q(n, -1);
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const int id = mesh.extraction_id(c);
    // Hexahedra take the dense path (a product of three univariate factors is not written yet).
    if (p[id] < 0 && mesh.cell(c).dimension == 2) p[id] = mesh.cell(c).degree_u, q[id] = mesh.cell(c).degree_v;
  }
#pragma omp parallel for schedule(dynamic, 256)
  for (int id = 0; id < n; ++id)
    if (p[id] >= 0) separable[id] = factor_separable(mesh.pooled_extraction(id), p[id], q[id], rows[id]);
}

void evaluate_cell_functions(const BezierMesh& mesh, const GeometryMap& geometry, const SeparableExtraction& rows,
                             int cell, int nu, int nv, CellFunctions& out) {
  const BezierCell& c = mesh.cell(cell);
  // Univariate Bernstein tables: a (p, 0) table on an (nu x 1) rule is B_i(u_k) and B_i'(u_k).
  const BernsteinTable& tu = bernstein_table(c.degree_u, 0, nu, 1);
  const BernsteinTable& tv = bernstein_table(c.degree_v, 0, nv, 1);
  const BernsteinTable& t2 = bernstein_table(1, 1, nu, nv);  // only for the tensor weights
  product_abt(tu.value, rows.u, out.U);  // nu x functions
  product_abt(tu.d_u, rows.u, out.Uu);
  product_abt(tv.value, rows.v, out.V);  // nv x functions
  product_abt(tv.d_u, rows.v, out.Vv);
  const Eigen::Index na = rows.u.rows(), nq = static_cast<Eigen::Index>(nu) * nv;
  out.value.resize(nq, na);
  out.Ru.resize(nq, na);
  out.Rv.resize(nq, na);
  // Plain loops over contiguous columns: at these sizes (a few to a hundred points) Eigen's
  // per-expression overhead, not arithmetic, is what costs.
  for (Eigen::Index a = 0; a < na; ++a) {
    const double *U = out.U.col(a).data(), *Uu = out.Uu.col(a).data();
    double *N = out.value.col(a).data(), *Nu = out.Ru.col(a).data(), *Nv = out.Rv.col(a).data();
    for (int j = 0; j < nv; ++j) {
      const double V = out.V(j, a), Vv = out.Vv(j, a);
      for (int i = 0; i < nu; ++i) {
        N[i + nu * j] = U[i] * V;
        Nu[i + nu * j] = Uu[i] * V;
        Nv[i + nu * j] = U[i] * Vv;
      }
    }
  }
  if (mesh.is_rational()) {
    // R_a = w_a N_a / W, W = sum_a w_a N_a on the cell.
    const auto ids = mesh.functions(cell);
    out.weights.resize(na);
    for (Eigen::Index a = 0; a < na; ++a) out.weights[a] = mesh.weights()[ids[a]];
    out.w.noalias() = out.value * out.weights;
    out.wu.noalias() = out.Ru * out.weights;
    out.wv.noalias() = out.Rv * out.weights;
    out.w = out.w.cwiseInverse();
    for (Eigen::Index a = 0; a < na; ++a) {
      double *N = out.value.col(a).data(), *Nu = out.Ru.col(a).data(), *Nv = out.Rv.col(a).data();
      const double wa = out.weights[a];
      for (Eigen::Index k = 0; k < nq; ++k) {
        const double inv = out.w[k], r = wa * N[k] * inv;
        N[k] = r;
        Nu[k] = (wa * Nu[k] - r * out.wu[k]) * inv;
        Nv[k] = (wa * Nv[k] - r * out.wv[k]) * inv;
      }
    }
  }
  geometry.evaluate_at_rule(cell, nu, nv, out.geometry);
  const auto& J = out.geometry.jacobian;
  const int dim = out.dimension = out.geometry.dimension();
  out.measure.resize(nq);
  // Per point the map from reference to physical derivatives, times sqrt(measure).
  double min_jacobian = std::numeric_limits<double>::infinity();
  out.mu.resize(nq, 2 * dim);
  for (Eigen::Index k = 0; k < nq; ++k) {
    if (dim == 2) {
      const double det = J(k, 0) * J(k, 3) - J(k, 1) * J(k, 2);
      min_jacobian = std::min(min_jacobian, det);
      out.measure[k] = t2.weight[k] * std::abs(det);
      const double inv = std::sqrt(out.measure[k]) / det;
      out.mu(k, 0) = J(k, 3) * inv, out.mu(k, 1) = -J(k, 2) * inv;
      out.mu(k, 2) = -J(k, 1) * inv, out.mu(k, 3) = J(k, 0) * inv;
    } else {
      const double E = J(k, 0) * J(k, 0) + J(k, 2) * J(k, 2) + J(k, 4) * J(k, 4);
      const double F = J(k, 0) * J(k, 1) + J(k, 2) * J(k, 3) + J(k, 4) * J(k, 5);
      const double H = J(k, 1) * J(k, 1) + J(k, 3) * J(k, 3) + J(k, 5) * J(k, 5);
      const double det = E * H - F * F;
      min_jacobian = std::min(min_jacobian, det > 0 ? std::sqrt(det) : det);
      out.measure[k] = t2.weight[k] * std::sqrt(std::abs(det));
      const double inv = std::sqrt(out.measure[k]) / det;
      // grad = x_u (H f_u - F f_v)/det + x_v (E f_v - F f_u)/det, per coordinate d.
      for (int d = 0; d < 3; ++d) {
        out.mu(k, 2 * d) = (J(k, 2 * d) * H - J(k, 2 * d + 1) * F) * inv;
        out.mu(k, 2 * d + 1) = (J(k, 2 * d + 1) * E - J(k, 2 * d) * F) * inv;
      }
    }
  }
  out.min_jacobian = min_jacobian;
  out.scaled_gradients.resize(dim * nq, na);
  for (Eigen::Index a = 0; a < na; ++a) {
    const double *Nu = out.Ru.col(a).data(), *Nv = out.Rv.col(a).data();
    double* G = out.scaled_gradients.col(a).data();
    for (int d = 0; d < dim; ++d) {
      const double *mu = out.mu.col(2 * d).data(), *mv = out.mu.col(2 * d + 1).data();
      for (Eigen::Index k = 0; k < nq; ++k) G[d * nq + k] = mu[k] * Nu[k] + mv[k] * Nv[k];
    }
  }
}

}  // namespace knotwork
