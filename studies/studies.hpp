#pragma once
// The three studies a user runs (one solve, a convergence study, an adaptive loop), each
// written once and shared by the command line (app/*_command.cpp) and the Python module
// (python/): both print or return the same JSON object, so a Python result is the CLI's.
// `output_directory` null: nothing is written (the Python default); otherwise the files go
// through an OutputStage, so a failed study leaves none behind.
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "studies/adaptive.hpp"
#include "studies/pipeline.hpp"
#include "cases/json_output.hpp"
#include "cases/output_files.hpp"
#include "solver/petsc_module.hpp"
#include "solver/vtk_output.hpp"

namespace knotwork {

// The overrides every command and the Python module take: degree and elements (0: as the
// case says, else through the family), solver method and tolerance ("" / 0: as [solver] says).
// `preconditioner` ("": as [solver] says) must be one of the algebraic ones or one of the family's;
// `matrix` ("": as [solver] says) auto, assembled or matrix_free.
void override_case(CaseDescription& c, int degree, int elements, const std::string& solver, double tolerance,
                   const std::string* petsc_options = nullptr, const std::string& preconditioner = "",
                   const std::string& matrix = "");

// Under mpirun: every rank writes its cells of one output (`mine`, from cells_to_write) as the
// piece `<base>_<rank>.vtu`, into rank 0's staging folder (`stage`, null on the other ranks),
// and rank 0 also `<base>.pvtu`, which names them all; returns that name. Collective.
using PieceWriter = std::function<void(const std::string& path, CellRange cells, const PieceSummary* summary)>;
std::string write_pieces(OutputStage* stage, ParallelWorld world, const std::string& base, CellRange mine,
                         const PieceWriter& write);

// Opens `stage`, the staging folder of a study's output (null directory: none). Under mpirun
// rank 0 makes it and says to all ranks if it cannot; the other ranks get none (they write
// pieces into rank 0's through write_pieces). Collective under mpirun.
void open_output_stage(const std::string* output_directory, std::optional<OutputStage>& stage);

struct RunOutcome {
  std::unique_ptr<SplineSpace> space;
  PoissonSolution solution;
  SolverReport solver;
  std::string description;
  std::vector<ReportField> fields;  // the family's report and solution checks
  std::vector<std::string> outputs;
  double seconds_space = 0;  // building the space, part of timings.setup
  double seconds_checks = 0, seconds_output = 0;
  double total_without_output() const;
};
RunOutcome run_study(const CaseDescription& c, Ordering ordering, const std::string* output_directory,
                     const ProgressFunction& progress);
// `knotwork run --json`'s object.
Json run_json(const CaseDescription& c, const RunOutcome& r);
// The ParaView files of a solved case (solution.vtu and/or solution_sampled.vtu, as [output]
// says) into `stage`.
void write_run_output(const CaseDescription& c, const SplineSpace& space, const PoissonSolution& s, OutputStage& stage);

// On a domain of several patches, its interfaces as polylines for ParaView (interfaces.vtp,
// cell data "interface": the interface's number in the file, from 1). Returns the file's name,
// or "" for one patch (nothing written).
std::string write_interface_lines(const CaseDescription& c, OutputStage& stage);

struct ConvergeLevel {
  double h = 0;
  int dofs = 0, cells = 0, free = 0;
  double l2 = 0, h1_semi = 0, h1 = 0;
  double l2_rate = NAN, h1_rate = NAN;  // NaN on the first level
  double seconds = 0;
  std::vector<ReportField> fields;  // the family's (report and solution checks)
  SolverReport solver;              // how this level was solved ("auto" decides by size)
};
struct ConvergeOutcome {
  std::vector<ConvergeLevel> levels;
  std::string description;
  SolverReport first_solver, iterative_solver;  // of level 0, and of a level solved by CG
  int iterative_levels = 0;
  Json json = Json::object();  // convergence.json's object ("outputs" added when written)
  std::vector<std::string> outputs;
};
// The solver line of a study: "CG + P[ (no matrix)]" when every level solved by CG used the
// same, else each run of levels named ("CG: fast_diagonalization (no matrix) on levels 0-3;
// multigrid (no matrix) on level 4"); empty without CG.
std::string iterative_solvers_summary(const std::vector<ConvergeLevel>& levels);
// Levels 0..levels-1 of uniform refinement; checks the level count and the exact solution.
ConvergeOutcome converge_study(const CaseDescription& c, int levels, Ordering ordering,
                               const std::string* output_directory, const ProgressFunction& progress);

struct AdaptOutcome {
  std::vector<AdaptiveStep> steps;
  std::string description;
  Json json = Json::object();  // adapt.json's object
  std::vector<std::string> outputs;
};
// The adaptive loop of c.adapt (steps, theta and max_dofs checked here). No output directory:
// no files; otherwise the history (adapt.csv/json/svg) and the ParaView files of every
// `output_every`-th step and of the last.
AdaptOutcome adapt_study(const CaseDescription& c, Ordering ordering, const std::string* output_directory,
                         const ProgressFunction& progress, int output_every = 1);

// `knotwork basis --json`'s object for a case's space: the family's checks, partition of
// unity and rank.
Json basis_json(const CaseDescription& c, const SplineSpace& space);
// `knotwork dimension --json`'s object for a T-mesh (partition); `name` stands for its file.
Json dimension_json(const PartitionDescription& partition, const std::string& name, bool exact);

}  // namespace knotwork
