#pragma once
// What a family's case reader works with: the parsed document (TOML or JSON, one tree:
// cases/document_node.hpp) and a reader that validates values and prefixes every message
// with the file and the field. Everything after reading sees only CaseDescription.
#include <Eigen/Core>
#include <array>
#include <gmpxx.h>
#include <string>
#include "cases/document_node.hpp"
#include <vector>

#include "basis/tmesh/rectangular_partition.hpp"
#include "cases/case_file.hpp"

namespace knotwork {

constexpr int kMaxCaseDegree = 10;
constexpr long kMaxCaseCells = 1L << 26;  // ~67M cells: beyond any machine this runs on

// "did you mean 'x'?" for the closest of `valid`, or the list of valid names.
std::string closest_name(const std::string& key, const std::vector<std::string>& valid);

class CaseReader {
 public:
  explicit CaseReader(std::string path) : path_(std::move(path)) {}
  [[noreturn]] void fail(const std::string& field, const std::string& what) const;
  // Unknown keys are refused with the closest valid one (`section` "" is the top level).
  void check_keys(const DocumentNode& t, const std::string& section, const std::vector<std::string>& valid) const;
  // A section ([key]); an empty table when absent and not required.
  const DocumentNode& table(const DocumentNode& t, const std::string& key, bool required) const;
  double number(const DocumentNode& n, const std::string& field) const;
  // Exact: integers, rational strings ("14/9", "0.1" = 1/10), or a float's exact binary value.
  mpq_class rational(const DocumentNode& x, const std::string& field) const;
  long integer(const DocumentNode& n, const std::string& field) const;
  std::array<long, 2> integer_pair(const DocumentNode& n, const std::string& field) const;  // int or [u, v]
  // An integer for every direction, or a list of `count` (2: [u, v]; 3: [u, v, w]).
  std::vector<long> integers(const DocumentNode& n, const std::string& field, int count) const;
  std::vector<double> numbers(const DocumentNode& n, const std::string& field) const;
  Eigen::MatrixX2d points(const DocumentNode& n, const std::string& field) const;
  Eigen::MatrixXd points(const DocumentNode& n, const std::string& field, int dimension) const;  // [x, y(, z)] rows
  std::string string(const DocumentNode& n, const std::string& field) const;
  bool boolean(const DocumentNode& n, const std::string& field) const;
  // A file name relative to the case file's folder.
  std::string resolve(const std::string& file) const;
  // The file the string names (relative to the case file's folder), refused on `field` when
  // it is not there or cannot be read: a missing T-mesh, mesh or collection names the case
  // file and the key that points to it, not the file that is not there.
  std::string readable_file(const DocumentNode& n, const std::string& field) const;
  std::string readable_file(const std::string& name, const std::string& field) const;
  const std::string& path() const { return path_; }
  // Keys of [space] that other families take: an unknown [space] key that one of them knows
  // is refused with "only with family = ..." (load_case fills it from the registry).
  void set_other_families_keys(std::string family, std::vector<std::pair<std::string, std::vector<std::string>>> family_keys) {
    family_ = std::move(family);
    other_families_keys_ = std::move(family_keys);
  }

 private:
  std::string family_;
  std::vector<std::pair<std::string, std::vector<std::string>>> other_families_keys_;
  double rational_string(const std::string& s, const std::string& field) const;
  std::string path_;
};

// A parsed case and its reader: what SpaceFamily::read_case gets.
struct CaseDocument {
  const CaseReader& reader;
  const DocumentNode& root;
};

// TOML, or JSON (by the .json extension) through nlohmann-json with the same validation:
// the JSON object becomes a DocumentNode. Throws InputError naming the file (syntax errors
// with line and column).
DocumentNode parse_document(const std::string& path);
DocumentNode parse_document_text(const std::string& toml_text, const std::string& name);

// The sections every family shares: [output] and [adapt].
void read_output(const CaseReader& r, const DocumentNode& output, CaseDescription& c);
void read_adapt(const CaseReader& r, const DocumentNode& adapt, CaseDescription& c);
void read_solver(const CaseReader& r, const DocumentNode& solver, CaseDescription& c);
// `value` if it is one of `valid`, else InputError "<file>: <what>: 'value' is not a choice
// (closest name)"; `file` may be empty (command-line options).
std::string checked_name(const std::string& value, const std::vector<std::string>& valid, const std::string& what,
                         const std::string& file);

// Shared section readers for the families whose domain is one NURBS patch.
// [geometry] type = rectangle | quarter_annulus | lshape | nurbs, or [geometry] file = "PATH"
// (G+Smo .xml or GeoPDEs .txt, relative to the case file; type then optional). A file of
// several patches is refused unless `multipatch_allowed` (it fills c.domain only).
void read_patch_geometry(const CaseDocument& doc, CaseDescription& c, bool multipatch_allowed = false);
// [geometry] type = "box" (corners [[x0, y0, z0], [x1, y1, z1]], default the unit cube) or
// "thick_quarter_annulus" (inner_radius 1, outer_radius 2, height 1 by default): a volume
// (c.volume). is_volume_geometry: whether the document's [geometry] names one.
bool is_volume_geometry(const CaseDocument& doc);
void read_volume_geometry(const CaseDocument& doc, CaseDescription& c);
// [problem] coefficient: an expression or number a (one entry: A = a I), or a symmetric
// size x size matrix of them (size 2: the entries a11, a12, a22; size 3, on surfaces: a11, a12,
// a13, a22, a23, a33; a_ji must equal a_ij).
std::vector<Expression> read_coefficient(const CaseReader& r, const DocumentNode& n, int size);
// [problem] coefficient (read_coefficient with matrix_size 2 in the plane, 3 on surfaces) and
// reaction (a number >= 0, or an expression c checked >= 0 where it is integrated).
void read_coefficient_and_reaction(const CaseReader& r, const DocumentNode& problem, int matrix_size, PoissonProblem& pb);
// [problem] exact and source of a planar problem (source defaults to -div(A grad exact) + c exact);
// read_exact_and_source in `dimension` 2 or 3 (a volume: exact is u(x, y, z)).
void read_exact_and_source(const CaseReader& r, const DocumentNode& problem, CaseDescription& c, int dimension);
void read_planar_exact_and_source(const CaseReader& r, const DocumentNode& problem, CaseDescription& c);
// [problem] dirichlet_method ("projection", the default, or "nitsche") and nitsche_penalty.
void read_dirichlet_method(const CaseReader& r, const DocumentNode& problem, PoissonProblem& pb);
// [problem] exact/source/dirichlet/neumann on the sides boundary_labels names (of a patch, or
// of c.volume).
void read_patch_problem(const CaseDocument& doc, CaseDescription& c);
// [space] quadrature_points / error_quadrature_points: one int for every direction, or a list of
// `directions` (2: [u, v]; 3: [u, v, w]; 1: only one int), and boundary_quadrature_points.
void read_quadrature(const CaseReader& r, const DocumentNode& space, CaseDescription& c, int directions = 2);
// [space] degree (int or pair) in [1, 10], [space] elements >= 1 with at most 2^26 cells.
void check_degree(const CaseReader& r, const std::array<long, 2>& d, const std::string& field);
void check_elements(const CaseReader& r, const std::array<long, 2>& e, const std::string& field);

// cells = [[x0, y0, x1, y1], ...] with exact coordinates (`field` names the key).
std::vector<RationalBox> read_cells(const CaseReader& r, const DocumentNode& node, const std::string& field);
// segments = [{direction = "vertical", position, from, to}, ...] with exact coordinates.
std::vector<AxisSegment> read_axis_segments(const CaseReader& r, const DocumentNode& node, const std::string& field);
// A T-mesh from `cells`, or from `grid` = {x = [...], y = [...]} and `segments` (`prefix`
// goes in front of the field names), validated as a partition of a rectangle.
std::vector<RationalBox> read_tmesh(const CaseReader& r, const DocumentNode& t, const std::string& prefix);

}  // namespace knotwork
