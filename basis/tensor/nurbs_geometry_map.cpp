#include "basis/tensor/nurbs_geometry_map.hpp"

#include "basis/core/bezier_ops.hpp"
#include "quadrature/bernstein.hpp"

namespace knotwork {

NurbsGeometryMap::NurbsGeometryMap(const TensorDiscretization& d)
    : pu_(d.geometry_u.degree()),
      pv_(d.geometry_v.degree()),
      nu_(d.geometry_u.num_functions()),
      elements_u_(d.elements_u),
      spans_u_(d.geometry_u.element_spans()),
      spans_v_(d.geometry_v.element_spans()),
      cu_(bezier_extraction(d.geometry_u)),
      cv_(bezier_extraction(d.geometry_v)),
      net_(d.geometry_homogeneous) {}

void NurbsGeometryMap::homogeneous_bezier(int cell, Eigen::MatrixX3d& out) const {
  const int iu = cell % elements_u_, iv = cell / elements_u_;
  const int su = spans_u_[iu] - pu_, sv = spans_v_[iv] - pv_;
  out.resize((pu_ + 1) * (pv_ + 1), 3);
  thread_local Eigen::MatrixXd local, half, bez;
  local.resize(pu_ + 1, pv_ + 1);
  for (int k = 0; k < 3; ++k) {
    for (int av = 0; av <= pv_; ++av)
      for (int au = 0; au <= pu_; ++au) local(au, av) = net_((su + au) + nu_ * (sv + av), k);
    half.noalias() = cu_[iu].transpose() * local;
    bez.noalias() = half * cv_[iv];
    out.col(k) = Eigen::Map<const Eigen::VectorXd>(bez.data(), bez.size());
  }
}

void NurbsGeometryMap::evaluate_at_rule(int cell, int nu, int nv, GeometryAtPoints& out) const {
  const BernsteinTable& t = bernstein_table(pu_, pv_, nu, nv);
  thread_local Eigen::MatrixX3d bez, h, hu, hv;
  homogeneous_bezier(cell, bez);
  h.noalias() = t.value * bez;
  hu.noalias() = t.d_u * bez;
  hv.noalias() = t.d_v * bez;
  dehomogenize_map(h, hu, hv, out);
}

void NurbsGeometryMap::evaluate(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                GeometryAtPoints& out) const {
  Eigen::MatrixXd B, Bu, Bv;
  tensor_bernstein(pu_, pv_, u, v, B, Bu, Bv);
  Eigen::MatrixX3d bez;
  homogeneous_bezier(cell, bez);
  dehomogenize_map(B * bez, Bu * bez, Bv * bez, out);
}

BezierGeometryCell NurbsGeometryMap::bezier_cell(int cell) const {
  Eigen::MatrixX3d bez;
  homogeneous_bezier(cell, bez);
  BezierGeometryCell g;
  g.degree_u = pu_;
  g.degree_v = pv_;
  g.weights = bez.col(2);
  g.points = bez.leftCols<2>().array().colwise() / bez.col(2).array();
  return g;
}

// From the cell's homogeneous Bezier net: H = (w x, w y, w) and its first and second
// derivatives, then the quotient rule for x = H / w, one coordinate at a time.
bool NurbsGeometryMap::second_derivatives(int cell, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                          Eigen::MatrixXd& out) const {
  thread_local Eigen::MatrixX3d bez;
  thread_local Eigen::MatrixXd B, Bu, Bv, Buu, Buv, Bvv;
  homogeneous_bezier(cell, bez);
  tensor_bernstein(pu_, pv_, u, v, B, Bu, Bv);
  tensor_bernstein_second(pu_, pv_, u, v, Buu, Buv, Bvv);
  const Eigen::MatrixX3d H = B * bez, Hu = Bu * bez, Hv = Bv * bez, Huu = Buu * bez, Huv = Buv * bez, Hvv = Bvv * bez;
  out.resize(u.size(), 6);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const double w = H(k, 2);
    for (int d = 0; d < 2; ++d) {
      const double g = H(k, d) / w;
      const double gu = (Hu(k, d) - g * Hu(k, 2)) / w, gv = (Hv(k, d) - g * Hv(k, 2)) / w;
      out(k, 3 * d + 0) = (Huu(k, d) - 2 * gu * Hu(k, 2) - g * Huu(k, 2)) / w;
      out(k, 3 * d + 1) = (Huv(k, d) - gu * Hv(k, 2) - gv * Hu(k, 2) - g * Huv(k, 2)) / w;
      out(k, 3 * d + 2) = (Hvv(k, d) - 2 * gv * Hv(k, 2) - g * Hvv(k, 2)) / w;
    }
  }
  return true;
}

}  // namespace knotwork
