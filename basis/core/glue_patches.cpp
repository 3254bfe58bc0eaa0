// Gluing per-patch spaces by their traces (see glue_patches.hpp). Written here because it is
// knotwork's own contract (BezierMesh) that is glued; no library knows it.
#include "basis/core/glue_patches.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>
#include <sstream>
#include <unordered_map>

#include "basis/core/disjoint_sets.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// A function's trace counts when its largest Bernstein coefficient along the side exceeds
// this, and two traces are one when they differ by at most this times the larger. Both are
// decisions between structurally different things (a B-spline's coefficients on its support
// are of order one; a trace that is not there is zero up to rounding), not rounding tests.
constexpr double kTraceTolerance = 1e-9;

// One cell along a patch side: its piece [t0, t1] of the side (the side's parameter mapped
// onto [0, 1], in the direction of the interface's first side) and, per function of the cell,
// its Bernstein coefficients along the piece in the direction t increases.
// On a volume's face, a cell's piece is the rectangle [t0, t1] x [r0, r1] of the face (in the
// frame of the interface's first face), its degrees along the two (degree, degree_r), and the
// coefficients of a trace are indexed i + (degree + 1) j.
struct SidePiece {
  int cell = -1;
  double t0 = 0, t1 = 0;
  int degree = 0;
  double r0 = 0, r1 = 0;
  int degree_r = 0;
  std::vector<std::pair<int, Eigen::VectorXd>> traces;  // (patch-local function, coefficients)
};

std::vector<SidePiece> side_pieces(const BezierMesh& mesh, const NurbsPatch& patch, int side, bool reversed) {
  const CellSide cs = cell_side_of_patch_side(side);
  const bool along_v = side <= 2;
  const BSplineBasis1D& b = along_v ? patch.basis_v : patch.basis_u;
  const double begin = b.domain_begin(), length = b.domain_end() - begin;
  std::vector<SidePiece> out;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& cell = mesh.cell(c);
    if (cell.boundary[cs] < 0) continue;
    SidePiece s;
    s.cell = c;
    const double a = along_v ? cell.v0 : cell.u0, z = along_v ? cell.v1 : cell.u1;
    s.t0 = (a - begin) / length;
    s.t1 = (z - begin) / length;
    const int p = cell.degree_u, q = cell.degree_v;
    s.degree = along_v ? q : p;
    std::vector<int> index;  // the Bernstein polynomials along the side, t increasing
    for (int k = 0; k <= s.degree; ++k)
      index.push_back(cs == kSideBottom ? k : cs == kSideTop ? k + (p + 1) * q : cs == kSideLeft ? (p + 1) * k : p + (p + 1) * k);
    if (reversed) {
      std::reverse(index.begin(), index.end());
      std::tie(s.t0, s.t1) = std::pair(1 - s.t1, 1 - s.t0);
    }
    const Eigen::MatrixXd& e = mesh.extraction(c);
    const auto functions = mesh.functions(c);
    for (size_t r = 0; r < functions.size(); ++r) {
      Eigen::VectorXd t(index.size());
      for (size_t k = 0; k < index.size(); ++k) t[k] = e(static_cast<Eigen::Index>(r), index[k]);
      if (t.cwiseAbs().maxCoeff() > 0) s.traces.push_back({functions[r], std::move(t)});
    }
    out.push_back(std::move(s));
  }
  std::sort(out.begin(), out.end(), [](const SidePiece& x, const SidePiece& y) { return x.t0 < y.t0; });
  return out;
}

// A function's trace, piece by piece: (piece index, coefficients).
using Trace = std::vector<std::pair<int, const Eigen::VectorXd*>>;

std::unordered_map<int, Trace> traces_by_function(const std::vector<SidePiece>& pieces) {
  std::unordered_map<int, Trace> out;
  for (size_t k = 0; k < pieces.size(); ++k)
    for (const auto& [f, t] : pieces[k].traces) out[f].push_back({static_cast<int>(k), &t});
  return out;
}

double largest(const Trace& t) {
  double m = 0;
  for (const auto& [k, c] : t) m = std::max(m, c->cwiseAbs().maxCoeff());
  return m;
}

bool same_trace(const Trace& x, const Trace& y, double tolerance) {
  // Both are sorted by piece; a piece in one only must be zero there.
  size_t i = 0, j = 0;
  while (i < x.size() || j < y.size()) {
    if (j == y.size() || (i < x.size() && x[i].first < y[j].first)) {
      if (x[i++].second->cwiseAbs().maxCoeff() > tolerance) return false;
    } else if (i == x.size() || y[j].first < x[i].first) {
      if (y[j++].second->cwiseAbs().maxCoeff() > tolerance) return false;
    } else {
      if ((*x[i++].second - *y[j++].second).cwiseAbs().maxCoeff() > tolerance) return false;
    }
  }
  return true;
}

std::string number(double t) {
  std::ostringstream s;
  s << t;
  return s.str();
}

// [t0, t1] along a side; [t0, t1] x [r0, r1] on a face.
std::string piece_text(const SidePiece& p) {
  std::string text = "[" + number(p.t0) + ", " + number(p.t1) + "]";
  if (p.r1 > p.r0) text += " x [" + number(p.r0) + ", " + number(p.r1) + "]";
  return text;
}

// Identifies the functions of two glued sides by their traces: `unite(g, h)` for each function g
// of side A whose trace is function h's of side B; `refuse` names a trace without partner (or
// two with one), `weights_differ` partners of different weights (rational spaces).
template <class Refuse, class WeightsDiffer, class Unite>
void match_traces(const std::vector<SidePiece>& A, const std::vector<SidePiece>& B, const BezierMesh& mesh_a,
                  const BezierMesh& mesh_b, bool rational, const std::string& label_a, const std::string& label_b,
                  Refuse refuse, WeightsDiffer weights_differ, Unite unite) {
  const auto ta = traces_by_function(A), tb = traces_by_function(B);
  // Candidates on the other side, by piece.
  std::vector<std::vector<int>> b_on_piece(B.size());
  std::unordered_map<int, double> b_size;
  for (const auto& [g, t] : tb) {
    b_size[g] = largest(t);
    if (b_size[g] > kTraceTolerance)
      for (const auto& [k, c] : t) b_on_piece[k].push_back(g);
  }
  std::unordered_map<int, int> partner_of_b;
  std::vector<int> a_functions;
  for (const auto& [g, t] : ta) a_functions.push_back(g);
  std::sort(a_functions.begin(), a_functions.end());
  for (int g : a_functions) {
    const Trace& t = ta.at(g);
    const double size = largest(t);
    if (size <= kTraceTolerance) continue;
    const int piece = t.front().first;
    int partner = -1;
    for (int h : b_on_piece[piece])
      if (same_trace(t, tb.at(h), kTraceTolerance * std::max(size, b_size[h]))) {
        partner = h;
        break;
      }
    if (partner < 0)
      refuse("a function of patch " + label_a + " has a trace on the side, from " + piece_text(A[piece]) +
             " on, that no function of patch " + label_b + " has");
    if (!partner_of_b.emplace(partner, g).second) refuse("two functions of one side have the same trace");
    if (rational) {
      const double wa = mesh_a.weights()[g], wb = mesh_b.weights()[partner];
      if (std::abs(wa - wb) > 1e-9 * std::max(wa, wb))
        weights_differ(" have different weights: a conforming NURBS space needs the same weights on both sides");
    }
    unite(g, partner);
  }
  for (const auto& [h, size] : b_size)
    if (size > kTraceTolerance && !partner_of_b.count(h))
      refuse("a function of patch " + label_b + " has a trace on the side that no function of patch " + label_a + " has");
}

// The glued mesh: one number per class of `copies` (in the order the patches' functions come),
// the patches' cells in patch order as `domain_cell_of` renumbers their boundary sides, their
// weights, and the estimator's neighbours inside every patch and then across the interfaces.
template <class DomainCell>
GluedPatches assemble_glued(const std::vector<const BezierMesh*>& patches, const std::vector<int>& first_function,
                            DisjointSets& copies, bool rational, std::vector<std::string> boundary_names,
                            const std::vector<std::pair<CellInterface, std::array<int, 2>>>& across, DomainCell domain_cell_of) {
  const int np = static_cast<int>(patches.size());
  GluedPatches out;
  int count = 0;
  const std::vector<int> number = copies.numbering(&count);
  for (int p = 0; p < np; ++p)
    out.global_function.emplace_back(number.begin() + first_function[p], number.begin() + first_function[p + 1]);
  BezierMesh& mesh = out.mesh;
  mesh.set_num_functions(count);
  mesh.set_boundary_names(std::move(boundary_names));
  if (rational) {
    Eigen::VectorXd w(count);
    for (int p = 0; p < np; ++p)
      for (int i = 0; i < patches[p]->num_functions(); ++i) w[out.global_function[p][i]] = patches[p]->weights()[i];
    mesh.set_weights(std::move(w));
  }
  out.first_cell.push_back(0);
  std::vector<int> ids;
  for (int p = 0; p < np; ++p) {
    const BezierMesh& local = *patches[p];
    std::vector<int> extraction(local.num_distinct_extractions());
    for (int e = 0; e < local.num_distinct_extractions(); ++e) extraction[e] = mesh.add_extraction(local.pooled_extraction(e));
    for (int c = 0; c < local.num_cells(); ++c) {
      ids.clear();
      for (int f : local.functions(c)) ids.push_back(out.global_function[p][f]);
      mesh.add_cell(domain_cell_of(local.cell(c), p), ids, extraction[local.extraction_id(c)]);
    }
    out.first_cell.push_back(mesh.num_cells());
  }
  std::vector<CellInterface> interfaces;
  for (int p = 0; p < np; ++p) {
    const std::vector<CellInterface> own =
        patches[p]->has_interfaces() ? patches[p]->interfaces() : interfaces_from_parameter_boxes(*patches[p]);
    for (CellInterface ci : own) {
      ci.cell_a += out.first_cell[p], ci.cell_b += out.first_cell[p];
      interfaces.push_back(ci);
    }
  }
  for (auto [ci, pair] : across) {
    ci.cell_a += out.first_cell[pair[0]];
    ci.cell_b += out.first_cell[pair[1]];
    interfaces.push_back(ci);
  }
  mesh.set_interfaces(std::move(interfaces));
  return out;
}

}  // namespace

GluedPatches glue_patches(const MultiPatch& domain, const std::vector<const BezierMesh*>& patches) {
  const int np = domain.num_patches();
  if (static_cast<int>(patches.size()) != np) throw std::invalid_argument("glue_patches: one space per patch is needed");
  const bool rational = patches[0]->is_rational();
  std::vector<int> first_function{0};
  for (const BezierMesh* m : patches) {
    if (m->is_rational() != rational) throw std::invalid_argument("glue_patches: the patches' spaces are not all rational or all not");
    first_function.push_back(first_function.back() + m->num_functions());
  }

  DisjointSets copies(first_function.back());
  std::vector<std::pair<CellInterface, std::array<int, 2>>> across;  // patch-local cells, and their patches
  for (const PatchInterface& f : domain.interfaces) {
    const int pa = f.a.patch, pb = f.b.patch;
    const std::string sides = "patch " + patch_label(domain, pa) + " side " + std::to_string(f.a.side) + " and patch " +
                              patch_label(domain, pb) + " side " + std::to_string(f.b.side);
    auto refuse = [&](const std::string& what) {
      throw GeometryError(f.where + ": the spaces of " + sides + " do not match: " + what +
                          " (a conforming space needs the same functions along an interface)");
    };
    const std::vector<SidePiece> A = side_pieces(*patches[pa], domain.patches[pa], f.a.side, false);
    const std::vector<SidePiece> B = side_pieces(*patches[pb], domain.patches[pb], f.b.side, f.reversed);
    if (A.size() != B.size())
      refuse("the sides are cut into " + std::to_string(A.size()) + " and " + std::to_string(B.size()) + " cells");
    for (size_t k = 0; k < A.size(); ++k) {
      if (std::abs(A[k].t0 - B[k].t0) > 1e-12 || std::abs(A[k].t1 - B[k].t1) > 1e-12)
        refuse("cell " + std::to_string(k + 1) + " along the side spans [" + number(A[k].t0) + ", " + number(A[k].t1) +
               "] of one and [" + number(B[k].t0) + ", " + number(B[k].t1) + "] of the other");
      if (A[k].degree != B[k].degree)
        refuse("the degree along the side is " + std::to_string(A[k].degree) + " and " + std::to_string(B[k].degree));
    }
    match_traces(A, B, *patches[pa], *patches[pb], rational, patch_label(domain, pa), patch_label(domain, pb), refuse,
                 [&](const std::string& what) { throw GeometryError(f.where + ": " + sides + what); },
                 [&](int g, int h) { copies.unite(first_function[pa] + g, first_function[pb] + h); });
    for (size_t k = 0; k < A.size(); ++k) {
      CellInterface ci;
      ci.cell_a = A[k].cell;
      ci.side_a = cell_side_of_patch_side(f.a.side);
      ci.cell_b = B[k].cell;
      ci.side_b = cell_side_of_patch_side(f.b.side);
      ci.b_from = f.reversed ? 1 : 0;
      ci.b_to = f.reversed ? 0 : 1;
      across.push_back({ci, {pa, pb}});
    }
  }

  const std::vector<PatchSideRef> exterior = exterior_sides(domain);
  std::vector<std::array<int, 4>> boundary_id;
  for (int p = 0; p < np; ++p) boundary_id.push_back(boundary_ids_of_patch(exterior, p));
  return assemble_glued(patches, first_function, copies, rational, exterior_side_names(domain, exterior), across,
                        [&](const BezierCell& cell, int p) { return domain_cell(cell, p, boundary_id[p]); });
}


namespace {

// The cells of volume mesh `mesh` on face `face` of its volume as pieces in the frame of the
// interface's face a: directly for face a (`i` null), through the interface's orientation for
// face b. Sorted by (t0, r0).
std::vector<SidePiece> face_pieces(const BezierMesh& mesh, const NurbsVolume& volume, int face, const VolumeInterface* i) {
  const CellSide cs = cell_side_of_face(face);
  const int normal = (face - 1) / 2, first = normal == 0 ? 1 : 0, second = normal == 2 ? 1 : 2;
  std::vector<SidePiece> out;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& cell = mesh.cell(c);
    if (cell.boundary[cs] < 0) continue;
    const double lo[3] = {cell.u0, cell.v0, cell.w0}, hi[3] = {cell.u1, cell.v1, cell.w1};
    const int degree[3] = {cell.degree_u, cell.degree_v, cell.degree_w};
    const auto normalized = [&](int d, double x) {
      const BSplineBasis1D& b = volume.bases[d];
      return (x - b.domain_begin()) / (b.domain_end() - b.domain_begin());
    };
    // The face's own frame: s along `first`, t along `second`.
    double s0 = normalized(first, lo[first]), s1 = normalized(first, hi[first]);
    double t0 = normalized(second, lo[second]), t1 = normalized(second, hi[second]);
    int ds = degree[first], dt = degree[second];
    // Bernstein index in the cell of the face's coefficient (i along s, j along t).
    const auto bernstein = [&](int a, int b) {
      int index[3];
      index[normal] = face % 2 == 0 ? degree[normal] : 0;
      index[first] = a, index[second] = b;
      return index[0] + (degree[0] + 1) * (index[1] + (degree[1] + 1) * index[2]);
    };
    // Face a's frame from face b's: undo the reversals, then the exchange.
    bool swap = false, flip_s = false, flip_t = false;
    if (i) {
      swap = !i->same_order;
      // b's first coordinate is a's first (same order) or a's second; its reversal is that one's.
      flip_s = i->same_order ? i->reverse_first : i->reverse_second;
      flip_t = i->same_order ? i->reverse_second : i->reverse_first;
    }
    if (flip_s) std::tie(s0, s1) = std::pair(1 - s1, 1 - s0);
    if (flip_t) std::tie(t0, t1) = std::pair(1 - t1, 1 - t0);
    SidePiece p;
    p.cell = c;
    if (swap) {
      p.t0 = t0, p.t1 = t1, p.r0 = s0, p.r1 = s1, p.degree = dt, p.degree_r = ds;
    } else {
      p.t0 = s0, p.t1 = s1, p.r0 = t0, p.r1 = t1, p.degree = ds, p.degree_r = dt;
    }
    const Eigen::MatrixXd& e = mesh.extraction(c);
    const auto functions = mesh.functions(c);
    for (size_t row = 0; row < functions.size(); ++row) {
      Eigen::VectorXd trace((p.degree + 1) * (p.degree_r + 1));
      for (int a = 0; a <= ds; ++a)
        for (int b = 0; b <= dt; ++b) {
          const int fa = flip_s ? ds - a : a, fb = flip_t ? dt - b : b;  // in the flipped face frame
          const int x = swap ? fb : fa, y = swap ? fa : fb;               // in face a's frame
          trace[x + (p.degree + 1) * y] = e(static_cast<Eigen::Index>(row), bernstein(a, b));
        }
      if (trace.cwiseAbs().maxCoeff() > 0) p.traces.push_back({functions[row], std::move(trace)});
    }
    out.push_back(std::move(p));
  }
  std::sort(out.begin(), out.end(), [](const SidePiece& x, const SidePiece& y) { return std::pair(x.t0, x.r0) < std::pair(y.t0, y.r0); });
  return out;
}

}  // namespace

GluedPatches glue_volumes(const MultiVolume& domain, const std::vector<const BezierMesh*>& patches) {
  const int np = domain.num_patches();
  if (static_cast<int>(patches.size()) != np) throw std::invalid_argument("glue_volumes: one space per volume is needed");
  const bool rational = patches[0]->is_rational();
  std::vector<int> first_function{0};
  for (const BezierMesh* m : patches) {
    if (m->is_rational() != rational) throw std::invalid_argument("glue_volumes: the volumes' spaces are not all rational or all not");
    first_function.push_back(first_function.back() + m->num_functions());
  }
  const auto label = [&](int p) {
    return p < static_cast<int>(domain.patch_labels.size()) && !domain.patch_labels[p].empty() ? domain.patch_labels[p]
                                                                                                 : std::to_string(p + 1);
  };
  DisjointSets copies(first_function.back());
  std::vector<std::pair<CellInterface, std::array<int, 2>>> across;
  for (const VolumeInterface& f : domain.interfaces) {
    const int pa = f.a.patch, pb = f.b.patch;
    const std::string sides = "patch " + label(pa) + " face " + std::to_string(f.a.side) + " and patch " + label(pb) + " face " +
                              std::to_string(f.b.side);
    auto refuse = [&](const std::string& what) {
      throw GeometryError(f.where + ": the spaces of " + sides + " do not match: " + what +
                          " (a conforming space needs the same functions across an interface)");
    };
    const std::vector<SidePiece> A = face_pieces(*patches[pa], domain.patches[pa], f.a.side, nullptr);
    const std::vector<SidePiece> B = face_pieces(*patches[pb], domain.patches[pb], f.b.side, &f);
    if (A.size() != B.size())
      refuse("the faces are cut into " + std::to_string(A.size()) + " and " + std::to_string(B.size()) + " cells");
    for (size_t k = 0; k < A.size(); ++k) {
      if (std::abs(A[k].t0 - B[k].t0) > 1e-12 || std::abs(A[k].t1 - B[k].t1) > 1e-12 || std::abs(A[k].r0 - B[k].r0) > 1e-12 ||
          std::abs(A[k].r1 - B[k].r1) > 1e-12)
        refuse("cell " + std::to_string(k + 1) + " on the face spans " + piece_text(A[k]) + " of one and " + piece_text(B[k]) +
               " of the other");
      if (A[k].degree != B[k].degree || A[k].degree_r != B[k].degree_r)
        refuse("the degrees on the face are " + std::to_string(A[k].degree) + "x" + std::to_string(A[k].degree_r) + " and " +
               std::to_string(B[k].degree) + "x" + std::to_string(B[k].degree_r));
    }
    match_traces(A, B, *patches[pa], *patches[pb], rational, label(pa), label(pb), refuse,
                 [&](const std::string& what) { throw GeometryError(f.where + ": " + sides + what); },
                 [&](int g, int h) { copies.unite(first_function[pa] + g, first_function[pb] + h); });
    // The estimator's neighbours across: cell pairs, b's face in a's frame by the orientation.
    for (size_t k = 0; k < A.size(); ++k) {
      CellInterface ci;
      ci.cell_a = A[k].cell;
      ci.side_a = cell_side_of_face(f.a.side);
      ci.cell_b = B[k].cell;
      ci.side_b = cell_side_of_face(f.b.side);
      ci.transposed = !f.same_order;
      // b's first coordinate follows a's first (same order) or a's second; reversed as that one.
      const bool flip_s = f.same_order ? f.reverse_first : f.reverse_second;
      const bool flip_t = f.same_order ? f.reverse_second : f.reverse_first;
      ci.b_from = flip_s ? 1 : 0, ci.b_to = flip_s ? 0 : 1;
      ci.b_from_t = flip_t ? 1 : 0, ci.b_to_t = flip_t ? 0 : 1;
      across.push_back({ci, {pa, pb}});
    }
  }
  const std::vector<PatchSideRef> exterior = exterior_faces(domain);
  if (exterior.size() > static_cast<size_t>(std::numeric_limits<std::int16_t>::max()))
    throw InputError("the domain has " + std::to_string(exterior.size()) + " boundary faces; knotwork takes at most 32767");
  std::vector<std::array<int, 6>> boundary_id(np, {-1, -1, -1, -1, -1, -1});  // per patch and CellSide
  for (size_t k = 0; k < exterior.size(); ++k) boundary_id[exterior[k].patch][cell_side_of_face(exterior[k].side)] = static_cast<int>(k);
  return assemble_glued(patches, first_function, copies, rational, exterior_face_names(domain, exterior), across,
                        [&](BezierCell cell, int p) {
                          cell.patch = p;
                          for (int s = 0; s < 6; ++s)
                            if (cell.boundary[s] >= 0) cell.boundary[s] = static_cast<std::int16_t>(boundary_id[p][s]);
                          return cell;
                        });
}

}  // namespace knotwork
