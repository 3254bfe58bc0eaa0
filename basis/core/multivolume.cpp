#include "basis/core/multivolume.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

Eigen::Vector3d point_at(const NurbsVolume& v, int face, double s, double t) {
  return volume_point_derivatives(v, face_parameters(v, face, s, t)).x;
}

std::string patch_name(const MultiVolume& d, int p) {
  return p < static_cast<int>(d.patch_labels.size()) && !d.patch_labels[p].empty() ? d.patch_labels[p] : std::to_string(p + 1);
}

std::string face_label(const MultiVolume& d, PatchSideRef f) { return patch_name(d, f.patch) + ":" + std::to_string(f.side); }

// The largest distance between the two faces' points at a 5 x 5 grid of face a, under `i`.
double face_distance(const MultiVolume& d, const VolumeInterface& i) {
  double worst = 0;
  for (int a = 0; a <= 4; ++a)
    for (int b = 0; b <= 4; ++b) {
      const double s = a / 4.0, t = b / 4.0;
      const auto [sb, tb] = i.on_b(s, t);
      worst = std::max(worst, (point_at(d.patches[i.a.patch], i.a.side, s, t) - point_at(d.patches[i.b.patch], i.b.side, sb, tb)).norm());
    }
  return worst;
}

}  // namespace

std::array<double, 2> VolumeInterface::on_b(double s, double t) const {
  const double first = reverse_first ? 1 - s : s, second = reverse_second ? 1 - t : t;
  return same_order ? std::array<double, 2>{first, second} : std::array<double, 2>{second, first};
}

CellSide cell_side_of_face(int face) {
  switch (face) {
    case 1: return kSideLeft;
    case 2: return kSideRight;
    case 3: return kSideBottom;
    case 4: return kSideTop;
    case 5: return kSideFront;
    case 6: return kSideBack;
  }
  throw std::invalid_argument("a volume's face must be 1 to 6, got " + std::to_string(face));
}

std::array<double, 3> face_parameters(const NurbsVolume& volume, int face, double s, double t) {
  const int normal = (face - 1) / 2;
  const bool high = face % 2 == 0;
  std::array<double, 3> at;
  const int first = normal == 0 ? 1 : 0, second = normal == 2 ? 1 : 2;
  const auto scale = [&](int d, double x) {
    const BSplineBasis1D& b = volume.bases[d];
    return b.domain_begin() + x * (b.domain_end() - b.domain_begin());
  };
  at[normal] = scale(normal, high ? 1.0 : 0.0);
  at[first] = scale(first, s);
  at[second] = scale(second, t);
  return at;
}

double domain_size(const MultiVolume& d) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const NurbsVolume& v : d.patches)
    for (Eigen::Index k = 0; k < v.control_points.rows(); ++k) {
      lo = lo.cwiseMin(v.control_points.row(k).transpose());
      hi = hi.cwiseMax(v.control_points.row(k).transpose());
    }
  return (hi - lo).norm();
}

bool match_faces(const MultiVolume& d, PatchSideRef a, PatchSideRef b, double tolerance, VolumeInterface& out) {
  for (int order = 0; order < 2; ++order)
    for (int r1 = 0; r1 < 2; ++r1)
      for (int r2 = 0; r2 < 2; ++r2) {
        VolumeInterface i;
        i.a = a, i.b = b, i.same_order = order == 0, i.reverse_first = r1, i.reverse_second = r2;
        bool corners = true;
        for (int c = 0; c < 4 && corners; ++c) {
          const double s = c & 1, t = c >> 1;
          const auto [sb, tb] = i.on_b(s, t);
          corners = (point_at(d.patches[a.patch], a.side, s, t) - point_at(d.patches[b.patch], b.side, sb, tb)).norm() <= tolerance;
        }
        if (corners && face_distance(d, i) <= tolerance) {
          out = i;
          return true;
        }
      }
  return false;
}

std::vector<VolumeInterface> find_face_interfaces(const MultiVolume& d) {
  const double tolerance = 1e-9 * domain_size(d);
  std::vector<VolumeInterface> out;
  for (int p = 0; p < d.num_patches(); ++p)
    for (int f = 1; f <= 6; ++f)
      for (int q = p; q < d.num_patches(); ++q)
        for (int g = q == p ? f + 1 : 1; g <= 6; ++g) {
          VolumeInterface i;
          if (match_faces(d, {p, f}, {q, g}, tolerance, i)) out.push_back(i);
        }
  return out;
}

std::vector<PatchSideRef> exterior_faces(const MultiVolume& d) {
  std::vector<PatchSideRef> out;
  for (int p = 0; p < d.num_patches(); ++p)
    for (int f = 1; f <= 6; ++f) {
      const PatchSideRef face{p, f};
      if (std::none_of(d.interfaces.begin(), d.interfaces.end(), [&](const VolumeInterface& i) { return i.a == face || i.b == face; }))
        out.push_back(face);
    }
  return out;
}

std::vector<std::string> exterior_face_names(const MultiVolume& d, const std::vector<PatchSideRef>& exterior) {
  std::vector<std::string> names;
  for (const PatchSideRef& f : exterior) names.push_back(face_label(d, f));
  return names;
}

void check_multivolume(const MultiVolume& d) {
  for (int p = 0; p < d.num_patches(); ++p) {
    try {
      d.patches[p].validate();
    } catch (const std::invalid_argument& e) {
      throw GeometryError((p < static_cast<int>(d.patch_where.size()) ? d.patch_where[p] + ": " : std::string()) + "patch " +
                          patch_name(d, p) + ": " + e.what());
    }
  }
  const double tolerance = 1e-9 * domain_size(d);
  std::vector<PatchSideRef> used;
  for (const VolumeInterface& i : d.interfaces) {
    const std::string what = "faces " + face_label(d, i.a) + " and " + face_label(d, i.b);
    if (i.a.patch < 0 || i.a.patch >= d.num_patches() || i.b.patch < 0 || i.b.patch >= d.num_patches() || i.a.side < 1 ||
        i.a.side > 6 || i.b.side < 1 || i.b.side > 6)
      throw GeometryError(i.where + ": interface of " + what + ": no such face");
    if (i.a == i.b) throw GeometryError(i.where + ": interface of " + what + ": a face glued to itself");
    for (const PatchSideRef& f : {i.a, i.b}) {
      if (std::find(used.begin(), used.end(), f) != used.end())
        throw GeometryError(i.where + ": face " + face_label(d, f) + " is in two interfaces");
      used.push_back(f);
    }
    const double gap = face_distance(d, i);
    if (gap > tolerance) {
      std::ostringstream m;
      m << i.where << ": " << what << " are not one surface under the file's orientation (they differ by " << gap << ")";
      throw GeometryError(m.str());
    }
  }
  for (const VolumeInterface& found : find_face_interfaces(d))
    if (std::find(used.begin(), used.end(), found.a) == used.end())
      throw GeometryError((found.a.patch < static_cast<int>(d.patch_where.size()) ? d.patch_where[found.a.patch] + ": " : std::string()) +
                          "faces " + face_label(d, found.a) + " and " + face_label(d, found.b) +
                          " coincide but are not an interface of the file: the space would be discontinuous there");
  for (const NamedBoundary& b : d.boundaries)
    for (const PatchSideRef& f : b.sides)
      if (std::find(used.begin(), used.end(), f) != used.end())
        throw GeometryError(b.where + ": boundary \"" + b.name + "\" lists face " + face_label(d, f) + ", an interface");
}

}  // namespace knotwork
