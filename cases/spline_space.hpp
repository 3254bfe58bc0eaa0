#pragma once
// The family interface: the one seam between the spline families (basis/<family>/) and the
// commands that use them (run, converge, adapt, bench; the Python module later). A family
// builds its BezierMesh and geometry from a case, refines where it can, describes itself and
// reports its own checks; everything else (assembly, solve, norms, estimator, output) is
// written once against BezierMesh and GeometryMap. docs/ARCHITECTURE.md says how to add one.
#include <Eigen/Core>
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "cases/case_file.hpp"
#include "basis/core/geometry_map.hpp"
#include "solver/iterative_solver.hpp"
#include "solver/matrix_free.hpp"
#include "solver/poisson_problem.hpp"
#include "solver/sparsity.hpp"

namespace knotwork {

// An array of degrees (or counts) per direction as the list degree() gives.
template <size_t n>
std::vector<int> as_list(const std::array<int, n>& a) {
  return {a.begin(), a.end()};
}

// A value a family adds to the reports of run, converge, adapt and basis. The key is the
// JSON key ("c1_jump"; "counts.vertex" is member `vertex` of object `counts`); monostate is
// JSON null.
using ReportValue = std::variant<std::monostate, double, long, std::string, bool, std::vector<std::string>>;
struct ReportField {
  std::string key{};
  ReportValue value{};
  std::string text{};   // a line of the text summary, "label    text" ("": JSON only)
  std::string label{};  // its label ("mesh", "C1"; default: the key)
  bool column = false;  // also a column of converge's level table (numbers)
  int width = 0;        // its width there (0: 12)
};

// Knot lines of a mesh in physical space, for ParaView (adapt writes one .vtp per step).
struct KnotLines {
  std::vector<Eigen::MatrixX2d> lines;
  std::vector<int> kind;          // 0 line, 1 ray, 2 segment
  std::vector<int> multiplicity;  // per line
};

// How a marked cell is halved by adaptive refinement.
enum class CellSplit { kAcrossU, kAcrossV };

using ProgressFunction = std::function<void(const std::string&)>;

// What a family says about one of its spaces, for people: the reports, notes, the `basis`
// checks and export, the knot lines of ParaView output. Nothing the solve needs; the family's
// plugin implements it (families/<family>/).
class SpaceReport {
 public:
  virtual ~SpaceReport() = default;
  // One line: "NURBS, degree 2x2, C^1 at new knots".
  virtual std::string description() const = 0;
  // Facts about the space for the reports (before solving), and notes that must be seen
  // (a segment extended, a construction that fell back to another).
  virtual std::vector<ReportField> report() const { return {}; }
  virtual std::vector<std::string> notes() const { return {}; }
  // Checks of a solution only the family can make (G1: the C1 jump across interfaces).
  virtual std::vector<ReportField> check_solution(const Eigen::VectorXd& /*coefficients*/) const { return {}; }
  // `knotwork basis`: the family's own checks of the space (semi-regularity, dimension
  // counts), next to the partition of unity and rank every space gets.
  virtual std::vector<ReportField> basis_report() const { return {}; }
  // `knotwork basis --export FILE`: writes every function (the format is the family's);
  // throws InputError when the family has no export.
  virtual void export_functions(const std::string& file, const std::string& source) const;
  // The knot lines of ParaView output (physical polylines; none by default).
  virtual KnotLines knot_lines() const { return {}; }
  // The same, to be computed later, on another thread and after this space is gone (what it
  // needs is copied): adapt draws a step's knots while the next step computes. Null when the
  // family draws none. By default knot_lines(), computed now.
  virtual std::function<KnotLines()> knot_lines_later() const;
};

// A spline space of some family, built from a case: what the pipeline needs (the mesh, its
// geometry, degree, refinement, a process's part, a structured preconditioner) and, apart,
// what the family says about it (presentation()).
class SplineSpace {
 public:
  virtual ~SplineSpace() = default;
  virtual const BezierMesh& mesh() const = 0;
  virtual const GeometryMap& geometry() const = 0;
  // The polynomial degree per parameter direction (the reports' `degree`: two, or three on a
  // volume).
  virtual std::vector<int> degree() const = 0;
  // The family's words about this space (SpaceReport).
  virtual const SpaceReport& presentation() const = 0;
  // Throws InputError when the space must not be solved on (and the case did not allow it).
  virtual void check_solvable() const {}
  // The h of convergence tables: the largest cell diagonal in physical space.
  virtual double mesh_size() const;
  // Adaptive refinement: the space with the marked cells halved as told, or null when the
  // family cannot refine locally. `extended` (optional) counts what the family had to add
  // beyond the marked cells (knot segments lengthened to stay semi-regular). It consumes the
  // space (call it on std::move(*space) and drop the space after): a family may free this
  // space's mesh before it builds the next one, so that the two never need memory at once.
  // `progress` hears the stages of a build that takes long (up to a minute in exact arithmetic).
  virtual std::unique_ptr<SplineSpace> refine(const std::vector<int>& /*marked*/, const std::vector<CellSplit>& /*split*/,
                                              int* /*extended*/ = nullptr, const ProgressFunction& /*progress*/ = {}) && {
    return nullptr;
  }
  // Adaptive refinement as nested spaces, for a multigrid over the steps (studies/adaptive.cpp):
  // keep_prolongations() asks this space, and every space refine() makes from it, to keep the
  // prolongation from the space it was refined from; false when the family cannot (the default).
  virtual bool keep_prolongations() { return false; }
  // That prolongation P (this space's functions x its predecessor's): the predecessor's function
  // j is sum_i P(i, j) times function i of this space. Null when not kept (not asked, or the
  // starting space).
  virtual const Eigen::SparseMatrix<double>* prolongation_from_predecessor() const { return nullptr; }
  // Whether [solver] "auto" takes that multigrid in adapt (where keep_prolongations() can), or
  // only the name "multigrid" does: false where measurements found a loop no faster with it
  // than with CHOLMOD (docs/ADAPTIVITY.md, "Multigrid over the steps").
  virtual bool multigrid_over_steps_is_automatic() const { return true; }
  // Preconditioners that know the space's structure, for the iterative solve: their names
  // ([solver] preconditioner; none when the family has none), the first the one "auto" takes,
  // and the one named for the free dofs of `layout` of `problem`'s operator (null when it
  // does not apply to them).
  virtual std::vector<std::string> structured_preconditioners() const { return {}; }
  // Whether [solver] = "auto" may choose the first (CG with it from 10 000 functions on); false
  // where measurements found algebraic multigrid or CHOLMOD better (docs/SOLVERS.md).
  virtual bool structured_preconditioner_is_automatic() const { return true; }
  // The one "auto" takes (where it takes a structured one): the first, unless the space
  // measures another one better for itself; then `why` says so, for the run's note.
  virtual std::string automatic_structured_preconditioner(std::string& /*why*/) const {
    const std::vector<std::string> names = structured_preconditioners();
    return names.empty() ? std::string() : names.front();
  }
  // Whether the named one is built from the matrix's diagonal alone (the fast diagonalization
  // is; a multigrid that reads the whole matrix is not). Under method = "petsc" every structured
  // one is a PCShell that each process applies to the whole residual: those built from the
  // diagonal as they are, the others without a matrix (below) where every element is affine,
  // and elsewhere from the whole matrix, gathered on every process (studies/pipeline.cpp).
  virtual bool structured_preconditioner_needs_only_diagonal(const std::string& /*name*/) const { return true; }
  virtual std::unique_ptr<Preconditioner> make_structured_preconditioner(const std::string& /*name*/,
                                                                         const DofLayout& /*layout*/,
                                                                         const Eigen::SparseMatrix<double>& /*lower*/,
                                                                         const PoissonProblem& /*problem*/) const {
    return nullptr;
  }
  // Whether the named one also serves CG without a matrix ([solver] matrix): those built from
  // the diagonal alone do, through make_structured_preconditioner; the others through
  // make_structured_preconditioner_without_matrix, from the operator matrix_free_operator gave.
  // On a part (method = "petsc"), `op` is the part's operator and the preconditioner acts on
  // the whole space's free dofs (`layout`, `free_diagonal`): the family builds what it needs of
  // the whole space from its own data, with op's coefficients and rules.
  virtual bool structured_preconditioner_without_matrix(const std::string& name) const {
    return structured_preconditioner_needs_only_diagonal(name);
  }
  virtual std::unique_ptr<Preconditioner> make_structured_preconditioner_without_matrix(
      const std::string& /*name*/, const DofLayout& /*layout*/, std::shared_ptr<const MatrixFreePoisson> /*op*/,
      const Eigen::VectorXd& /*free_diagonal*/) const {
    return nullptr;
  }
  // Its Poisson operator applied without a matrix, K = stiffness (grad, grad) + reaction (., .)
  // by `quadrature`'s rules, when the family has one for this space (null otherwise). It may
  // read the space's data in place: the space must outlive it. Where a matrix is assembled, it
  // may also write it or its pattern (MatrixFreePoisson::assembles_lower, gives_pattern).
  // On a part (part() not null), the operator over the part's mesh, whose rows of the
  // functions the part owns must be whole (the distributed solve writes those rows from it).
  virtual std::unique_ptr<MatrixFreePoisson> matrix_free_operator(double /*stiffness*/, double /*reaction*/,
                                                                  const QuadratureOptions& /*quadrature*/) const {
    return nullptr;
  }
  // A space SpaceFamily::build_part made: which cells and functions of the global space its
  // mesh holds (its coefficients, check_solution and output are this rank's share). Null: the
  // whole space.
  virtual const MeshPart* part() const { return nullptr; }
};

struct CaseDocument;  // cases/case_reader.hpp
class BasisTool;     // cases/basis_tool.hpp
}  // namespace knotwork
namespace CLI {
class App;
}
namespace knotwork {

// A family: its name in [space] family, how it reads its cases and builds their spaces.
struct SpaceFamily {
  std::string name;
  // Reads the case's [space] (and whatever else of the file the family owns: [geometry] and
  // [problem] for one-patch families through the shared readers) into c.section. Throws
  // InputError naming the file and the field.
  std::function<void(const CaseDocument&, CaseDescription&)> read_case;
  // The keys its [space] takes (read_case refuses others; other families' cases are told
  // which family takes a key).
  std::vector<std::string> space_keys;
  // The case's space refined `level` times uniformly (converge's level; 0: as written).
  // Throws InputError naming the case file and field when it cannot be built.
  std::function<std::unique_ptr<SplineSpace>(const CaseDescription&, int level, const ProgressFunction&)> build;
  // Under mpirun with method = "petsc": the part of build's space that rank `rank` of `ranks`
  // needs (SplineSpace::part), so that no rank holds the whole space. Null: every rank builds
  // the whole space. Throws InputError when the space cannot be split among that many ranks.
  std::function<std::unique_ptr<SplineSpace>(const CaseDescription&, int level, int rank, int ranks,
                                             const ProgressFunction&)>
      build_part;
  // --degree / --elements on the command line (InputError when they do not apply).
  std::function<void(CaseDescription&, int degree, int elements)> override_options;
  // Whether SplineSpace::refine halves marked cells (what `adapt` needs).
  bool local_refinement = false;
  // Throw InputError when a convergence study or adaptive refinement is not possible for
  // this case (before any work is done); null: always possible.
  std::function<void(const CaseDescription&, int levels)> check_converge;
  std::function<void(const CaseDescription&)> check_adapt;
  // The family's own mode of `knotwork basis`: adds its options to the command and returns
  // the tool that holds them; null: the family has none.
  std::function<std::unique_ptr<BasisTool>(CLI::App& basis)> add_basis_tool;
  // The names of its spaces' structured preconditioners ([solver] preconditioner): what
  // SplineSpace::structured_preconditioners may return.
  std::vector<std::string> structured_preconditioners;
};

// Throws InputError naming [space] family unless the case's family refines cells locally
// (and its own check_adapt passes); the message lists the families that do.
void check_adaptive_family(const CaseDescription& c);

// Every registered family (families/families.cpp: one line per family).
const std::vector<SpaceFamily>& space_families();
// The case's family; throws InputError naming [space] family if it is not registered.
const SpaceFamily& space_family(const CaseDescription& c);
// Every name [solver] preconditioner (and --preconditioner) takes: the algebraic ones, then
// every family's structured ones, each once.
std::vector<std::string> preconditioner_names();

// The sides of a mesh's cells through its geometry, as KnotLines (each side once: bottom and
// left sides, and top and right sides on the boundary): the knot lines of a family whose cells
// tile one patch's parameter domain. Read off each cell's Bezier form (GeometryMap::bezier_cell,
// exact for NURBS maps): a straight side as its two ends, a curved one at `samples` points.
KnotLines knot_lines_of_cells(const BezierMesh& mesh, const GeometryMap& geometry, int samples = 9);

// The largest cell diagonal of a mesh through its geometry (the default mesh_size).
double largest_cell_diagonal(const BezierMesh& mesh, const GeometryMap& geometry);

}  // namespace knotwork
