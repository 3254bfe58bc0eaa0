#include "basis/core/nurbs_patch.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace knotwork {

PatchPointDerivatives patch_point_derivatives(const NurbsPatch& patch, double u, double v) {
  const int p = patch.basis_u.degree(), q = patch.basis_v.degree(), nu = patch.basis_u.num_functions();
  const int su = patch.basis_u.find_span(u), sv = patch.basis_v.find_span(v);
  std::vector<double> bu(2 * (p + 1)), bv(2 * (q + 1));  // values, then first derivatives
  patch.basis_u.evaluate_derivatives(su, u, 1, bu.data());
  patch.basis_v.evaluate_derivatives(sv, v, 1, bv.data());
  // Homogeneous (w x, w y, w) and its derivatives, then the quotient rule.
  Eigen::Vector3d h = Eigen::Vector3d::Zero(), hu = h, hv = h;
  for (int b = 0; b <= q; ++b)
    for (int a = 0; a <= p; ++a) {
      const int i = (su - p + a) + nu * (sv - q + b);
      const double w = patch.weights[i];
      const Eigen::Vector3d c(w * patch.control_points(i, 0), w * patch.control_points(i, 1), w);
      h += c * (bu[a] * bv[b]);
      hu += c * (bu[p + 1 + a] * bv[b]);
      hv += c * (bu[a] * bv[q + 1 + b]);
    }
  PatchPointDerivatives out;
  out.weight = h[2];
  out.x = h.head<2>() / h[2];
  out.jacobian.col(0) = (hu.head<2>() - out.x * hu[2]) / h[2];
  out.jacobian.col(1) = (hv.head<2>() - out.x * hv[2]) / h[2];
  return out;
}

Eigen::Vector2d patch_point(const NurbsPatch& patch, double u, double v) { return patch_point_derivatives(patch, u, v).x; }

void NurbsPatch::validate() const {
  const int nu = basis_u.num_functions(), nv = basis_v.num_functions();
  if (!basis_u.is_open()) throw std::invalid_argument("knots_u is not open: the first and last knots must each be repeated degree+1 times");
  if (!basis_v.is_open()) throw std::invalid_argument("knots_v is not open: the first and last knots must each be repeated degree+1 times");
  for (int d = 0; d < 2; ++d) {
    const auto& b = d == 0 ? basis_u : basis_v;
    const auto m = b.multiplicities();
    for (size_t i = 1; i + 1 < m.size(); ++i)
      if (m[i] > b.degree())
        throw std::invalid_argument(std::string(d == 0 ? "knots_u" : "knots_v") +
                                    " has an interior knot of multiplicity degree+1: the patch would be discontinuous");
  }
  if (control_points.rows() != static_cast<Eigen::Index>(nu) * nv)
    throw std::invalid_argument("control_points has " + std::to_string(control_points.rows()) +
                                " points but the knot vectors need " + std::to_string(nu) + " x " +
                                std::to_string(nv) + " = " + std::to_string(nu * nv));
  if (weights.size() != control_points.rows())
    throw std::invalid_argument("weights has " + std::to_string(weights.size()) +
                                " entries but there are " + std::to_string(control_points.rows()) +
                                " control points");
  validate_net(control_points, weights);
}

void validate_net(const Eigen::Ref<const Eigen::MatrixXd>& control_points, const Eigen::VectorXd& weights) {
  for (Eigen::Index i = 0; i < control_points.rows(); ++i)
    if (!control_points.row(i).allFinite())
      throw std::invalid_argument("control point " + std::to_string(i) + " is not finite");
  for (Eigen::Index i = 0; i < weights.size(); ++i)
    if (!(std::isfinite(weights[i]) && weights[i] > 0))
      throw std::invalid_argument("weight " + std::to_string(i) + " must be a positive finite number");
}

}  // namespace knotwork
