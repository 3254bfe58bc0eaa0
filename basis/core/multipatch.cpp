#include "basis/core/multipatch.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "basis/core/input_error.hpp"
#include "quadrature/gauss_legendre.hpp"

namespace knotwork {

CellSide cell_side_of_patch_side(int side) {
  switch (side) {
    case 1: return kSideLeft;
    case 2: return kSideRight;
    case 3: return kSideBottom;
    case 4: return kSideTop;
  }
  throw std::invalid_argument("patch side must be 1, 2, 3 or 4, got " + std::to_string(side));
}

int patch_side_of_cell_side(CellSide side) {
  switch (side) {
    case kSideLeft: return 1;
    case kSideRight: return 2;
    case kSideBottom: return 3;
    case kSideTop: return 4;
    case kSideFront: return 5;  // a hexahedron's w = 0 and w = 1, as G+Smo numbers a volume's sides
    case kSideBack: return 6;
  }
  return 0;
}

std::vector<PatchSideRef> exterior_sides(const MultiPatch& domain) {
  std::vector<PatchSideRef> out;
  for (int p = 0; p < domain.num_patches(); ++p)
    for (int s = 1; s <= 4; ++s) {
      const PatchSideRef side{p, s};
      const bool glued = std::any_of(domain.interfaces.begin(), domain.interfaces.end(),
                                     [&](const PatchInterface& i) { return i.a == side || i.b == side; });
      if (!glued) out.push_back(side);
    }
  return out;
}

std::array<int, 4> boundary_ids_of_patch(const std::vector<PatchSideRef>& exterior, int p) {
  std::array<int, 4> id{-1, -1, -1, -1};
  // A cell keeps its sides' boundary ids in 16 bits (BezierCell).
  if (exterior.size() > static_cast<size_t>(std::numeric_limits<std::int16_t>::max()))
    throw InputError("the domain has " + std::to_string(exterior.size()) +
                     " boundary sides; knotwork takes at most 32767");
  for (size_t k = 0; k < exterior.size(); ++k)
    if (exterior[k].patch == p) id[cell_side_of_patch_side(exterior[k].side)] = static_cast<int>(k);
  return id;
}

std::vector<std::string> exterior_side_names(const MultiPatch& domain, const std::vector<PatchSideRef>& exterior) {
  std::vector<std::string> names;
  for (const PatchSideRef& s : exterior) names.push_back(side_name(domain, s));
  return names;
}

BezierCell domain_cell(BezierCell cell, int p, const std::array<int, 4>& boundary_id) {
  cell.patch = p;
  for (int s = 0; s < 4; ++s)
    if (cell.boundary[s] >= 0) cell.boundary[s] = boundary_id[s];
  return cell;
}

std::vector<int> side_indices(int nu, int nv, int side) {
  std::vector<int> out;
  const int n = side <= 2 ? nv : nu;
  for (int k = 0; k < n; ++k) out.push_back(side == 1 ? nu * k : side == 2 ? nu - 1 + nu * k : side == 3 ? k : k + nu * (nv - 1));
  return out;
}

std::string patch_label(const MultiPatch& domain, int p) {
  return p < static_cast<int>(domain.patch_labels.size()) ? domain.patch_labels[p] : std::to_string(p + 1);
}

std::string side_name(const MultiPatch& domain, PatchSideRef side) {
  return patch_label(domain, side.patch) + ":" + std::to_string(side.side);
}

namespace {

// The parameters (u, v) of the point at t in [0, 1] along a side (in the side's own direction).
std::pair<double, double> side_parameters(const NurbsPatch& patch, int side, double t) {
  const double u0 = patch.basis_u.domain_begin(), u1 = patch.basis_u.domain_end();
  const double v0 = patch.basis_v.domain_begin(), v1 = patch.basis_v.domain_end();
  switch (side) {
    case 1: return {u0, v0 + t * (v1 - v0)};
    case 2: return {u1, v0 + t * (v1 - v0)};
    case 3: return {u0 + t * (u1 - u0), v0};
    default: return {u0 + t * (u1 - u0), v1};
  }
}

}  // namespace

Eigen::MatrixX2d side_curve(const MultiPatch& domain, PatchSideRef side, int points) {
  const NurbsPatch& patch = domain.patches.at(side.patch);
  Eigen::MatrixX2d out(points, 2);
  for (int k = 0; k < points; ++k) {
    const auto [u, v] = side_parameters(patch, side.side, points > 1 ? double(k) / (points - 1) : 0.0);
    out.row(k) = patch_point(patch, u, v).transpose();
  }
  return out;
}

namespace {

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw GeometryError(where.empty() ? what : where + ": " + what);
}

std::string patch_where(const MultiPatch& d, int p) {
  return p < static_cast<int>(d.patch_where.size()) ? d.patch_where[p] : "";
}

std::string patch_name(const MultiPatch& d, int p) { return "patch " + patch_label(d, p); }

void check_side_ref(const MultiPatch& d, const PatchSideRef& s, const std::string& where) {
  if (s.patch < 0 || s.patch >= d.num_patches())
    fail(where, "patch " + std::to_string(s.patch + 1) + " does not exist (the file has " + std::to_string(d.num_patches()) +
                    " patches)");
  if (s.side < 1 || s.side > 4) fail(where, "side " + std::to_string(s.side) + " does not exist (sides are 1 to 4)");
}

// det J at the Gauss points of every knot span (4 x 4 points): positive everywhere, else the
// patch is inverted (all negative) or folds over.
void check_orientation(const MultiPatch& d, int p) {
  const NurbsPatch& patch = d.patches[p];
  const auto bu = patch.basis_u.breakpoints(), bv = patch.basis_v.breakpoints();
  const QuadratureRule1D rule = gauss_legendre(4);
  bool positive = false, negative = false;
  for (size_t i = 0; i + 1 < bu.size(); ++i)
    for (size_t j = 0; j + 1 < bv.size(); ++j)
      for (size_t a = 0; a < rule.nodes.size(); ++a)
        for (size_t b = 0; b < rule.nodes.size(); ++b) {
          const double u = bu[i] + (bu[i + 1] - bu[i]) * rule.nodes[a];
          const double v = bv[j] + (bv[j + 1] - bv[j]) * rule.nodes[b];
          const Eigen::Matrix2d J = patch_point_derivatives(patch, u, v).jacobian;
          const double det = J(0, 0) * J(1, 1) - J(0, 1) * J(1, 0);
          (det > 0 ? positive : negative) = true;
        }
  if (negative && !positive)
    fail(patch_where(d, p), patch_name(d, p) + " is inverted (det J < 0 everywhere): reverse one of its parameter "
                                               "directions or swap u and v");
  if (negative)
    fail(patch_where(d, p), patch_name(d, p) + " folds over (det J changes sign inside it)");
}

// The patch's parameters of point x, if x lies inside it (not within `margin` of its sides in
// the unit-square parameters): Newton's method on x(u, v) = x from a 3 x 3 grid of starts,
// kept in the parameter domain. A start that does not converge proves nothing; overlaps show
// at many points, so the check below samples enough of them.
bool strictly_inside(const NurbsPatch& patch, const Eigen::Vector2d& x, double tolerance, double margin) {
  const double u0 = patch.basis_u.domain_begin(), u1 = patch.basis_u.domain_end();
  const double v0 = patch.basis_v.domain_begin(), v1 = patch.basis_v.domain_end();
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      double u = u0 + (u1 - u0) * (0.5 * a + 0.25) / 1.75, v = v0 + (v1 - v0) * (0.5 * b + 0.25) / 1.75;
      for (int it = 0; it < 40; ++it) {
        const PatchPointDerivatives q = patch_point_derivatives(patch, u, v);
        const Eigen::Vector2d r = q.x - x;
        if (r.norm() <= tolerance) {
          const double su = (u - u0) / (u1 - u0), sv = (v - v0) / (v1 - v0);
          if (su > margin && su < 1 - margin && sv > margin && sv < 1 - margin) return true;
          break;
        }
        const double det = q.jacobian.determinant();
        if (!(std::abs(det) > 0)) break;
        const Eigen::Vector2d step = q.jacobian.inverse() * r;
        u = std::clamp(u - step[0], u0, u1);
        v = std::clamp(v - step[1], v0, v1);
      }
    }
  return false;
}

// No patch lies over another: points inside every patch (4 x 4 per knot span, away from its
// sides) are looked for inside every other patch whose control box holds them.
void check_overlaps(const MultiPatch& d, double size) {
  const int np = d.num_patches();
  std::vector<Eigen::AlignedBox2d> box(np);
  for (int p = 0; p < np; ++p)
    for (Eigen::Index i = 0; i < d.patches[p].control_points.rows(); ++i)
      box[p].extend(Eigen::Vector2d(d.patches[p].control_points.row(i).transpose()));
  for (int p = 0; p < np; ++p) {
    const NurbsPatch& patch = d.patches[p];
    const auto bu = patch.basis_u.breakpoints(), bv = patch.basis_v.breakpoints();
    for (size_t i = 0; i + 1 < bu.size(); ++i)
      for (size_t j = 0; j + 1 < bv.size(); ++j)
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b) {
            const double u = bu[i] + (bu[i + 1] - bu[i]) * (a + 0.5) / 4, v = bv[j] + (bv[j + 1] - bv[j]) * (b + 0.5) / 4;
            const Eigen::Vector2d x = patch_point(patch, u, v);
            for (int q = 0; q < np; ++q)
              if (q != p && box[q].contains(x) && strictly_inside(d.patches[q], x, 1e-12 * size, 1e-6)) {
                std::ostringstream where;
                where << "(" << x[0] << ", " << x[1] << ")";
                fail(patch_where(d, p), patch_name(d, p) + " and " + patch_name(d, q) + " overlap: the point " + where.str() +
                                            " of the first lies inside the second");
              }
          }
  }
}

double domain_size(const MultiPatch& d) {
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (const NurbsPatch& p : d.patches)
    for (Eigen::Index i = 0; i < p.control_points.rows(); ++i)
      for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], p.control_points(i, k)), hi[k] = std::max(hi[k], p.control_points(i, k));
  return std::hypot(hi[0] - lo[0], hi[1] - lo[1]);
}

// The two sides of an interface at points along them: 8 points per knot span of either side
// and the ends, positions to `tolerance`, the weight functions to 1e-9 relative.
void check_interface_curves(const MultiPatch& d, const PatchInterface& f, double tolerance) {
  const NurbsPatch& A = d.patches[f.a.patch];
  const NurbsPatch& B = d.patches[f.b.patch];
  auto side_breaks = [](const NurbsPatch& patch, int side) {
    const BSplineBasis1D& b = side <= 2 ? patch.basis_v : patch.basis_u;
    std::vector<double> t = b.breakpoints();
    const double from = b.domain_begin(), length = b.domain_end() - from;
    for (double& x : t) x = (x - from) / length;
    return t;
  };
  std::vector<double> ts;
  for (const auto& breaks : {side_breaks(A, f.a.side), side_breaks(B, f.b.side)})
    for (size_t i = 0; i + 1 < breaks.size(); ++i)
      for (int k = 0; k < 8; ++k) ts.push_back(breaks[i] + (breaks[i + 1] - breaks[i]) * (k + 0.5) / 8);
  ts.push_back(0), ts.push_back(1);
  for (double t : ts) {
    const auto [ua, va] = side_parameters(A, f.a.side, t);
    const auto [ub, vb] = side_parameters(B, f.b.side, f.reversed ? 1 - t : t);
    const PatchPointDerivatives a = patch_point_derivatives(A, ua, va), b = patch_point_derivatives(B, ub, vb);
    const double gap = (a.x - b.x).norm();
    if (!(gap <= tolerance)) {
      char m[320];
      std::snprintf(m, sizeof m,
                    "%s side %d and %s side %d are not the same curve: at (%.6g, %.6g) on the first the second is "
                    "%.3g away (check the sides and the orientation%s)",
                    patch_name(d, f.a.patch).c_str(), f.a.side, patch_name(d, f.b.patch).c_str(), f.b.side, a.x[0], a.x[1],
                    gap, f.reversed ? ", given as reversed" : ", given as matching");
      fail(f.where, m);
    }
    if (std::abs(a.weight - b.weight) > 1e-9 * std::max(a.weight, b.weight)) {
      char m[320];
      std::snprintf(m, sizeof m,
                    "%s side %d and %s side %d have different weights along the interface (%.12g and %.12g at the same "
                    "point): a conforming NURBS space needs the same weights on both sides (scale the weights of one "
                    "patch)",
                    patch_name(d, f.a.patch).c_str(), f.a.side, patch_name(d, f.b.patch).c_str(), f.b.side, a.weight,
                    b.weight);
      fail(f.where, m);
    }
  }
}

}  // namespace

void check_multipatch(const MultiPatch& d) {
  if (d.patches.empty()) throw GeometryError("the geometry has no patch");
  for (int p = 0; p < d.num_patches(); ++p) {
    try {
      d.patches[p].validate();
    } catch (const std::invalid_argument& e) {
      fail(patch_where(d, p), patch_name(d, p) + ": " + e.what());
    }
    check_orientation(d, p);
  }
  const double size = domain_size(d), tolerance = 1e-9 * size;
  check_overlaps(d, size);
  std::vector<PatchSideRef> used;
  for (const PatchInterface& f : d.interfaces) {
    check_side_ref(d, f.a, f.where);
    check_side_ref(d, f.b, f.where);
    if (f.a == f.b) fail(f.where, "an interface joins a side to itself");
    for (const PatchSideRef& s : {f.a, f.b}) {
      if (std::find(used.begin(), used.end(), s) != used.end())
        fail(f.where, patch_name(d, s.patch) + " side " + std::to_string(s.side) + " is already in another interface");
      used.push_back(s);
    }
    check_interface_curves(d, f, tolerance);
  }
  std::vector<PatchSideRef> named;
  for (const NamedBoundary& b : d.boundaries)
    for (const PatchSideRef& s : b.sides) {
      check_side_ref(d, s, b.where);
      if (std::find(used.begin(), used.end(), s) != used.end())
        fail(b.where, "boundary \"" + b.name + "\" lists " + patch_name(d, s.patch) + " side " + std::to_string(s.side) +
                          ", which is an interface");
      if (std::find(named.begin(), named.end(), s) != named.end())
        fail(b.where, "boundary \"" + b.name + "\" lists " + patch_name(d, s.patch) + " side " + std::to_string(s.side) +
                          ", which is already in another boundary");
      named.push_back(s);
    }
}

}  // namespace knotwork
