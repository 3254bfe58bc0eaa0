#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <mutex>
#include <span>
#include <string>
#include <vector>

namespace knotwork {

// Side order of a cell, counter-clockwise in its parameter box [u0,u1]x[v0,v1]; a hexahedral
// cell (dimension 3) also has the sides w = w0 (front) and w = w1 (back).
enum CellSide { kSideBottom = 0, kSideRight = 1, kSideTop = 2, kSideLeft = 3, kSideFront = 4, kSideBack = 5 };

// One cell: a quadrilateral (dimension 2: planar domains and surfaces) or a hexahedron
// (dimension 3: volumes). A quadrilateral has degree_w = 0, so (p+1)(q+1)(r+1) counts its
// Bernstein polynomials in either dimension. The fields are sized so that the third direction
// costs 16 bytes per cell (88 in all): tensor meshes hold millions of cells.
struct BezierCell {
  int patch = 0;
  int index_u = 0, index_v = 0, index_w = 0;  // position of the element in its patch (tensor bases)
  double u0 = 0, u1 = 1, v0 = 0, v1 = 1, w0 = 0, w1 = 0;  // parameter box (for reporting; maps use [0,1]^d)
  int degree_u = 1, degree_v = 1;
  std::int16_t degree_w = 0;
  std::int8_t dimension = 2;
  // Boundary id per CellSide, -1 if interior (sides 4 and 5: hexahedra only).
  std::array<std::int16_t, 6> boundary{-1, -1, -1, -1, -1, -1};
  int num_sides() const { return 2 * dimension; }
  int num_bernstein() const { return (degree_u + 1) * (degree_v + 1) * (degree_w + 1); }
};

// Two cells that meet along part of a side: the piece [a_from, a_to] of cell_a's side (in
// the cell's reference coordinate along that side: u on bottom/top, v on left/right) is the
// same curve as [b_from, b_to] of cell_b's side, point for point (b_from > b_to when the
// two run opposite ways). Built once by the family, which knows its topology (multi-patch
// and G1 meshes included); the residual estimator walks them.
// Hexahedra meet on faces. A face's two reference coordinates (s, t) are the cell's own
// except the normal one, in the order u, v, w (front/back: u, v; bottom/top: u, w; left/right:
// v, w); the piece is [a_from, a_to] x [a_from_t, a_to_t] of cell_a's face, and its point of
// relative position (alpha, beta) is the point (b_from + alpha (b_to - b_from), b_from_t +
// beta (b_to_t - b_from_t)) of cell_b's face, with alpha and beta exchanged when `transposed`.
struct CellInterface {
  int cell_a = -1;
  CellSide side_a = kSideBottom;
  double a_from = 0, a_to = 1;
  int cell_b = -1;
  CellSide side_b = kSideBottom;
  double b_from = 0, b_to = 1;
  double a_from_t = 0, a_to_t = 1, b_from_t = 0, b_to_t = 1;  // hexahedra only
  bool transposed = false;                                    // hexahedra only
};

// The contract between every spline construction and the solver: cell by cell, which
// global functions are alive and which combination of the cell's Bernstein polynomials
// each one is (N_active = C_e * B, B ordered a + (p+1)*c with a along u).
// Rational spaces add one positive weight per global function: R_i = w_i N_i / sum_j w_j N_j.
// The functions that do not vanish on a boundary side must have linearly independent traces
// there: Dirichlet data are imposed by L2 projection onto those traces.
// Extraction matrices live in a pool so that identical ones (most interior cells of
// uniform tensor meshes) are stored once.
class BezierMesh {
 public:
  void reserve(int cells, long ids) {
    cells_.reserve(cells);
    extraction_of_cell_.reserve(cells);
    offsets_.reserve(cells + 1);
    ids_.reserve(ids);
  }
  int add_extraction(Eigen::MatrixXd matrix);
  void add_cell(const BezierCell& cell, std::span<const int> functions, int extraction);
  void set_num_functions(int n) { num_functions_ = n; }
  void set_weights(Eigen::VectorXd weights) { weights_ = std::move(weights); }
  void set_boundary_names(std::vector<std::string> names) { boundary_names_ = std::move(names); }
  void set_interfaces(std::vector<CellInterface> interfaces) { interfaces_.set(std::move(interfaces)); }
  // For meshes whose interfaces are cheap to derive but costly to keep when nothing asks for
  // them (a million-cell tensor mesh): the rule runs on the first call of interfaces().
  using InterfaceRule = std::vector<CellInterface> (*)(const BezierMesh&);
  void set_interface_rule(InterfaceRule rule) { interfaces_.set_rule(rule); }

  int num_functions() const { return num_functions_; }
  int num_cells() const { return static_cast<int>(cells_.size()); }
  const BezierCell& cell(int c) const { return cells_[c]; }
  std::span<const int> functions(int c) const {
    return {ids_.data() + offsets_[c], static_cast<size_t>(offsets_[c + 1] - offsets_[c])};
  }
  const Eigen::MatrixXd& extraction(int c) const { return pool_[extraction_of_cell_[c]]; }
  int num_distinct_extractions() const { return static_cast<int>(pool_.size()); }
  // The pool: cells with the same extraction_id share one matrix (work done per distinct
  // matrix, e.g. factoring it, is done once).
  int extraction_id(int c) const { return extraction_of_cell_[c]; }
  const Eigen::MatrixXd& pooled_extraction(int id) const { return pool_[id]; }
  bool is_rational() const { return weights_.size() > 0; }
  const Eigen::VectorXd& weights() const { return weights_; }
  const std::vector<std::string>& boundary_names() const { return boundary_names_; }
  int max_functions_per_cell() const { return max_active_; }
  // The interior sides shared by two cells; has_interfaces() is false when the family did
  // not provide them (an empty list is a single cell).
  bool has_interfaces() const { return interfaces_.given(); }
  const std::vector<CellInterface>& interfaces() const { return interfaces_.get(*this); }
  int max_degree() const { return max_degree_; }

 private:
  std::vector<BezierCell> cells_;
  std::vector<int> extraction_of_cell_;
  std::vector<Eigen::MatrixXd> pool_;
  std::vector<int> offsets_{0};
  std::vector<int> ids_;
  Eigen::VectorXd weights_;
  std::vector<std::string> boundary_names_;
  // The list, or the rule that makes it on first use (thread-safe; a copy of the mesh copies
  // what is there and the rule).
  class Interfaces {
   public:
    Interfaces() = default;
    Interfaces(const Interfaces& o) { *this = o; }
    Interfaces& operator=(const Interfaces& o) {
      if (this == &o) return *this;
      std::scoped_lock lock(o.mutex_);
      list_ = o.list_;
      rule_ = o.rule_;
      built_ = o.built_;
      given_ = o.given_;
      return *this;
    }
    void set(std::vector<CellInterface> list) {
      list_ = std::move(list);
      rule_ = nullptr;
      built_ = given_ = true;
    }
    void set_rule(InterfaceRule rule) {
      list_.clear();
      rule_ = rule;
      built_ = false;
      given_ = true;
    }
    bool given() const { return given_; }
    const std::vector<CellInterface>& get(const BezierMesh& mesh) const {
      std::scoped_lock lock(mutex_);
      if (!built_ && rule_) {
        list_ = rule_(mesh);
        built_ = true;
      }
      return list_;
    }

   private:
    mutable std::mutex mutex_;
    mutable std::vector<CellInterface> list_;
    InterfaceRule rule_ = nullptr;
    mutable bool built_ = false;
    bool given_ = false;
  } interfaces_;
  int num_functions_ = 0;
  int max_active_ = 0;
  int max_degree_ = 0;
};

// Bernstein weights of a rational cell and the extraction that acts on the rational
// Bernstein polynomials wb_b B_b / W: R_active = C_hat * (wb .* B / W).
// For polynomial meshes wb = 1 and C_hat = C_e.
void rational_cell_extraction(const BezierMesh& mesh, int cell, Eigen::VectorXd& bernstein_weights,
                              Eigen::MatrixXd& extraction);

// The interfaces of a mesh whose cells tile one patch's parameter domain (tensor, knot-segment
// and T-mesh spaces), from the cells' parameter boxes: a right side meets the left sides
// that overlap it on the same line, a top side the bottom sides (hanging nodes included).
// On hexahedra (a volume) the same for faces: a high face meets the low faces that overlap it
// in the same plane, each piece their common rectangle (face_interfaces.cpp).
std::vector<CellInterface> interfaces_from_parameter_boxes(const BezierMesh& mesh);
std::vector<CellInterface> face_interfaces_from_parameter_boxes(const BezierMesh& mesh);

}  // namespace knotwork
