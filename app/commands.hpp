#pragma once
#include <memory>
#include <string>
#include <vector>

#include "cases/basis_tool.hpp"

namespace knotwork {

struct CommonOptions {
  bool json = false;
  bool quiet = false;
  std::string out;             // overrides [output] directory
  int degree = 0;              // 0: as in the case
  int elements = 0;            // 0: as in the case
  std::string ordering = "auto";
  std::string solver;    // "": [solver] method of the case
  double tolerance = 0;  // 0: [solver] tolerance of the case
  std::string preconditioner;  // "": [solver] preconditioner of the case
  std::string matrix;          // "": [solver] matrix of the case
  std::string petsc_options;  // --petsc-options, when given (petsc_options_given)
  bool petsc_options_given = false;
  bool condition = false;  // --condition (run, converge)
};

struct RunOptions : CommonOptions {
  std::string case_file;
  bool no_output = false;
  bool allow_unverified_space = false;
};

struct ConvergeOptions : CommonOptions {
  std::string case_file;
  int levels = 4;
};

struct AdaptOptions : CommonOptions {
  std::string case_file;
  int steps = 0;        // 0: [adapt] steps of the case
  double theta = 0;     // 0: [adapt] theta
  long max_dofs = 0;    // 0: [adapt] max_dofs
  bool no_output = false;
  int output_every = 1;  // ParaView files of every K-th step (and the last)
  bool allow_unverified_space = false;  // --allow-dependent
  std::string marking;                  // "": [adapt] marking
  std::string strategy;                 // "": [adapt] strategy
  double min_fraction = -1;             // < 0: [adapt] min_fraction
};

struct BenchOptions {
  std::vector<std::string> configs;  // "P:N" (degree P, N x N elements; N^3 on the cube)
  std::string domain = "square";     // square (u = sin sin) | cube (u = sin sin sin)
  bool quick = false;
  bool json = false;
  std::string ordering = "auto";
  bool with_errors = true;
  bool floor = false;  // also time bare CHOLMOD (default settings) on the same matrix
  std::string solver = "direct";  // direct | iterative (CG + the space's preconditioner)
  double tolerance = 1e-15;
  std::string preconditioner = "auto";  // with solver "iterative": as [solver] preconditioner
  std::string matrix = "auto";          // with solver "iterative": as [solver] matrix
};

struct DimensionOptions {
  std::string file;
  bool exact = false;
  bool json = false;
};


int run_command(const RunOptions& o);
// `request.file` through the family tool that is asked for or claims it, else as a case file.
int basis_command(const BasisRequest& request, const std::vector<std::unique_ptr<BasisTool>>& tools);
int dimension_command(const DimensionOptions& o);
int converge_command(const ConvergeOptions& o);
int adapt_command(const AdaptOptions& o);
int bench_command(const BenchOptions& o);


}  // namespace knotwork
