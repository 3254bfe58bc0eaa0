// GeoPDEs' geometry text format v2.1 (its doc/geo_specs_v21.txt and geo_specs_mp_v21.txt):
// lines starting with '#' are comments; a header "ndim rdim Np [Ni [Ns]]"; per patch an
// optional name line, the degrees, the numbers of control points, one knot vector per
// direction, one line per coordinate of the weighted control points (w x, w y), numbered u
// fastest, and the weights; per interface a name, "patch side" twice and the orientation flag;
// per subdomain a name and its patches; then, to the end, boundaries: a name, the number of
// sides and "patch side" per side. Volumes (ndim = rdim = 3) have three of each and faces 1..6
// (u = 0, u = 1, v = 0, v = 1, w = 0, w = 1). No library reads it: written here.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "basis/core/input_error.hpp"
#include "cases/geometry_file.hpp"

namespace knotwork {

namespace {

constexpr long kMaxControlPoints = long(1) << 24;

class LineReader {
 public:
  explicit LineReader(const std::string& path) : path_(path) {
    std::istringstream in(read_geometry_text(path));
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      ++n;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      const size_t first = line.find_first_not_of(" \t");
      if (first == std::string::npos || line[first] == '#') continue;
      lines_.push_back(line.substr(first));
      numbers_.push_back(n);
    }
  }
  bool done() const { return at_ >= lines_.size(); }
  const std::string& peek() const { return lines_[at_]; }
  const std::string& next(const std::string& what) {
    if (done()) throw InputError(path_ + ": the file ends where " + what + " should be");
    line_ = numbers_[at_];
    return lines_[at_++];
  }
  std::string where() const { return path_ + ": line " + std::to_string(line_); }
  [[noreturn]] void fail(const std::string& what) const { throw InputError(where() + ": " + what); }

  std::vector<double> numbers(const std::string& what, long expected) {
    const std::string& text = next(what);
    std::vector<double> out;
    const char* s = text.c_str();
    while (true) {
      while (*s == ' ' || *s == '\t' || *s == ',') ++s;
      if (!*s) break;
      char* end = nullptr;
      errno = 0;
      const double v = std::strtod(s, &end);
      if (end == s || errno == ERANGE || !std::isfinite(v)) {
        std::string token(s, std::min<size_t>(std::strcspn(s, " \t,"), 24));
        fail(what + ": '" + token + "' is not a finite number");
      }
      out.push_back(v);
      s = end;
      if (*s && *s != ' ' && *s != '\t' && *s != ',') fail(what + ": a number is followed by '" + std::string(1, *s) + "'");
    }
    if (expected >= 0 && static_cast<long>(out.size()) != expected)
      fail(what + ": expected " + std::to_string(expected) + " numbers, found " + std::to_string(out.size()));
    return out;
  }
  std::vector<long> integers(const std::string& what, long min_count, long max_count) {
    const std::vector<double> v = numbers(what, -1);
    if (static_cast<long>(v.size()) < min_count || static_cast<long>(v.size()) > max_count)
      fail(what + ": expected " + (min_count == max_count ? std::to_string(min_count)
                                                          : std::to_string(min_count) + " to " + std::to_string(max_count)) +
           " integers, found " + std::to_string(v.size()));
    std::vector<long> out;
    for (double x : v) {
      if (x != std::floor(x) || std::abs(x) > 1e9) fail(what + ": " + std::to_string(x) + " is not an integer");
      out.push_back(static_cast<long>(x));
    }
    return out;
  }

 private:
  std::string path_;
  std::vector<std::string> lines_;
  std::vector<int> numbers_;
  size_t at_ = 0;
  int line_ = 0;
};

bool starts_with_number(const std::string& s) {
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return end != s.c_str();
}

PatchSideRef read_side(LineReader& in, const std::string& what, long patches, int sides = 4) {
  const auto v = in.integers(what, 2, 2);
  if (v[0] < 1 || v[0] > patches)
    in.fail(what + ": patch " + std::to_string(v[0]) + " does not exist (patches are 1 to " + std::to_string(patches) + ")");
  if (v[1] < 1 || v[1] > sides)
    in.fail(what + ": side " + std::to_string(v[1]) + " does not exist (sides are 1 to " + std::to_string(sides) + ")");
  return {static_cast<int>(v[0] - 1), static_cast<int>(v[1])};
}

// One patch of `dim` parametric directions in R^dim: its degrees, numbers of control points,
// knot vectors, weighted coordinates and weights (the caller has read its name).
struct FilePatch {
  std::vector<BSplineBasis1D> bases;
  Eigen::MatrixXd points;  // Euclidean, u fastest
  Eigen::VectorXd weights;
  std::string where;
};

FilePatch read_patch(LineReader& in, const std::string& name, int dim, long& total_points) {
  static const char* const directions[3] = {"u", "v", "w"};
  FilePatch patch;
  const auto degree = in.integers(name + " degrees", dim, dim);
  patch.where = in.where();
  for (long g : degree)
    if (g < 1 || g > 10) in.fail(name + " degrees: must be in [1, 10], got " + std::to_string(g));
  const auto count = in.integers(name + " numbers of control points", dim, dim);
  long n = 1;
  for (int k = 0; k < dim; ++k) {
    if (count[k] < degree[k] + 1 || count[k] > kMaxControlPoints)
      in.fail(name + " numbers of control points: must be in [degree + 1, 2^24], got " + std::to_string(count[k]));
    n *= count[k];
    if (n > kMaxControlPoints) in.fail(name + ": more than 2^24 control points");
  }
  total_points += n;
  if (total_points > kMaxControlPoints) in.fail(name + ": more than 2^24 control points");
  for (int k = 0; k < dim; ++k) {
    const std::string what = name + " knots_" + directions[k];
    std::vector<double> knots = in.numbers(what, count[k] + degree[k] + 1);
    try {
      patch.bases.emplace_back(static_cast<int>(degree[k]), std::move(knots));
    } catch (const std::invalid_argument& e) {
      in.fail(what + ": " + e.what());
    }
  }
  std::vector<std::vector<double>> weighted;
  for (int k = 0; k < dim; ++k)
    weighted.push_back(in.numbers(name + " weighted " + "xyz"[k] + " coordinates", n));
  const std::vector<double> w = in.numbers(name + " weights", n);
  patch.points.resize(n, dim);
  patch.weights.resize(n);
  for (long i = 0; i < n; ++i) {
    if (!(w[i] > 0)) in.fail(name + " weights: weight " + std::to_string(i + 1) + " must be positive");
    for (int k = 0; k < dim; ++k) patch.points(i, k) = weighted[k][i] / w[i];
    patch.weights[i] = w[i];
  }
  return patch;
}

// The boundaries to the end of the file: a name, the number of sides, "patch side" per side.
std::vector<NamedBoundary> read_boundaries(LineReader& in, long np, int sides) {
  std::vector<NamedBoundary> out;
  while (!in.done()) {
    NamedBoundary b;
    b.name = in.next("a boundary name");
    if (b.name.rfind("BOUNDARY ", 0) == 0) b.name = b.name.substr(9);
    while (!b.name.empty() && (b.name.back() == ' ' || b.name.back() == '\t')) b.name.pop_back();
    b.where = in.where();
    const auto count = in.integers("boundary " + b.name + " number of sides", 1, 1);
    if (count[0] < 1 || count[0] > sides * np)
      in.fail("boundary " + b.name + ": the number of sides must be in [1, " + std::to_string(sides) +
              " x patches], got " + std::to_string(count[0]));
    for (long k = 0; k < count[0]; ++k) b.sides.push_back(read_side(in, "boundary " + b.name + " (patch side)", np, sides));
    for (const NamedBoundary& other : out)
      if (other.name == b.name) in.fail("boundary " + b.name + " is given twice");
    out.push_back(std::move(b));
  }
  return out;
}

// The header "ndim rdim [Np [Ni [Ns]]]" (Np optional for one patch, as the format allows).
std::vector<long> read_header(LineReader& in) {
  return in.integers("the header (ndim rdim [patches [interfaces [subdomains]]])", 2, 5);
}

// The `np` patches of `dim` directions after the header, each with its optional name line,
// into the domain's patches (as `convert` makes them), labels "1".."np" and places.
template <class Domain, class Convert>
void read_patches(LineReader& in, long np, int dim, Domain& d, Convert convert) {
  long total_points = 0;
  for (long p = 1; p <= np; ++p) {
    const std::string name = "patch " + std::to_string(p);
    if (!in.done() && !starts_with_number(in.peek())) in.next(name);  // its name
    FilePatch f = read_patch(in, name, dim, total_points);
    d.patches.push_back(convert(f));
    d.patch_labels.push_back(std::to_string(p));
    d.patch_where.push_back(f.where);
  }
}

NurbsVolume volume_of(FilePatch& f) {
  NurbsVolume volume;
  for (int k = 0; k < 3; ++k) volume.bases[k] = std::move(f.bases[k]);
  volume.control_points = f.points;
  volume.weights = std::move(f.weights);
  return volume;
}

// The subdomain records (names and patch lists), checked and not kept: knotwork solves one
// problem on the whole domain.
void skip_subdomains(LineReader& in, long ns, long np) {
  for (long s = 1; s <= ns; ++s) {
    const std::string name = "subdomain " + std::to_string(s);
    in.next(name);
    for (long p : in.integers(name + " patches", 1, np))
      if (p < 1 || p > np) in.fail(name + ": patch " + std::to_string(p) + " does not exist");
  }
}

}  // namespace

MultiPatch read_geopdes_text(const std::string& path) {
  LineReader in(path);
  const auto header = read_header(in);
  if (header[0] == 3) in.fail("a 3D (volume) geometry where a planar one (ndim = 2) is read");
  if (header[0] != 2) in.fail("ndim must be 2, got " + std::to_string(header[0]));
  if (header[1] != 2) in.fail("rdim must be 2 (a planar domain), got " + std::to_string(header[1]));
  const long np = header.size() > 2 ? header[2] : 1, ni = header.size() > 3 ? header[3] : 0, ns = header.size() > 4 ? header[4] : 0;
  if (np < 1 || np > 100000) in.fail("the number of patches must be in [1, 100000], got " + std::to_string(np));
  if (ni < 0 || ni > 4 * np) in.fail("the number of interfaces must be in [0, 4 x patches], got " + std::to_string(ni));
  if (ns < 0 || ns > np) in.fail("the number of subdomains must be in [0, patches], got " + std::to_string(ns));
  MultiPatch d;
  read_patches(in, np, 2, d, [](FilePatch& f) {
    NurbsPatch patch;
    patch.basis_u = std::move(f.bases[0]);
    patch.basis_v = std::move(f.bases[1]);
    patch.control_points = f.points;
    patch.weights = std::move(f.weights);
    return patch;
  });
  for (long i = 1; i <= ni; ++i) {
    const std::string name = "interface " + std::to_string(i);
    in.next(name);  // its name
    PatchInterface f;
    f.a = read_side(in, name + " (patch side)", np);
    f.where = in.where();
    f.b = read_side(in, name + " (patch side)", np);
    const auto o = in.integers(name + " orientation", 1, 1);
    if (o[0] != 1 && o[0] != -1 && o[0] != 0)
      in.fail(name + " orientation: must be 1 (the sides run the same way) or -1 (opposite ways), got " + std::to_string(o[0]));
    f.reversed = o[0] != 1;
    d.interfaces.push_back(f);
  }
  skip_subdomains(in, ns, np);
  d.boundaries = read_boundaries(in, np, 4);
  return d;
}

int geopdes_text_dimension(const std::string& path) {
  LineReader in(path);
  const long ndim = read_header(in)[0];
  return ndim == 3 ? 3 : 2;  // anything else is refused by the planar reader, naming ndim
}

namespace {

// A file of several volumes: the patches, then per interface "patch face", "patch face" and
// "flag ornt1 ornt2" (flag 1: the faces' first coordinates correspond, else the first to the
// second; ornt1, ornt2: 1 when a's first, second coordinate runs as its counterpart, -1 when
// against), the subdomains and the boundaries (faces 1..6).
VolumeFile read_geopdes_volumes(LineReader& in, const std::vector<long>& header) {
  const long np = header[2], ni = header.size() > 3 ? header[3] : 0, ns = header.size() > 4 ? header[4] : 0;
  if (np > 100000) in.fail("the number of patches must be in [1, 100000], got " + std::to_string(np));
  if (ni < 0 || ni > 6 * np) in.fail("the number of interfaces must be in [0, 6 x patches], got " + std::to_string(ni));
  if (ns < 0 || ns > np) in.fail("the number of subdomains must be in [0, patches], got " + std::to_string(ns));
  VolumeFile v;
  MultiVolume& d = v.domain;
  read_patches(in, np, 3, d, volume_of);
  for (long i = 1; i <= ni; ++i) {
    const std::string name = "interface " + std::to_string(i);
    in.next(name);
    VolumeInterface f;
    f.a = read_side(in, name + " (patch face)", np, 6);
    f.b = read_side(in, name + " (patch face)", np, 6);
    const auto o = in.integers(name + " (flag ornt1 ornt2)", 3, 3);
    f.where = in.where();  // the orientation's line: what the geometry is checked against
    for (long x : o)
      if (x != 1 && x != -1 && x != 0) in.fail(name + " (flag ornt1 ornt2): each must be 1 or -1, got " + std::to_string(x));
    f.same_order = o[0] == 1;
    f.reverse_first = o[1] != 1;
    f.reverse_second = o[2] != 1;
    d.interfaces.push_back(f);
  }
  skip_subdomains(in, ns, np);
  d.boundaries = read_boundaries(in, np, 6);
  v.volume = d.patches.front();
  v.where = d.patch_where.front();
  return v;
}

}  // namespace

VolumeFile read_geopdes_volume(const std::string& path) {
  LineReader in(path);
  const auto header = read_header(in);
  if (header[0] != 3) in.fail("ndim must be 3 (a volume), got " + std::to_string(header[0]));
  if (header[1] != 3) in.fail("rdim must be 3 (a volume in space), got " + std::to_string(header[1]));
  const long np = header.size() > 2 ? header[2] : 1;
  if (np > 1) return read_geopdes_volumes(in, header);
  if (np != 1) in.fail("the number of patches must be at least 1, got " + std::to_string(np));
  if (header.size() > 3 && header[3] != 0) in.fail("interfaces on a volume of one patch (the header gives " + std::to_string(header[3]) + ")");
  const long ns = header.size() > 4 ? header[4] : 0;
  if (ns < 0 || ns > 1) in.fail("the number of subdomains must be 0 or 1 on one patch, got " + std::to_string(ns));
  VolumeFile v;
  if (!in.done() && !starts_with_number(in.peek())) v.label = in.next("patch 1");
  long total_points = 0;
  FilePatch f = read_patch(in, "patch 1", 3, total_points);
  v.where = f.where;
  v.volume = volume_of(f);
  skip_subdomains(in, ns, 1);
  v.boundaries = read_boundaries(in, 1, 6);
  return v;
}

}  // namespace knotwork
