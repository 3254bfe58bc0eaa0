#pragma once
#include <string>
#include <vector>

namespace knotwork {

struct CommonOptions {
  bool json = false;
  bool quiet = false;
  std::string out;             // overrides [output] directory
  int degree = 0;              // 0: as in the case
  int elements = 0;            // 0: as in the case
  std::string ordering = "amd";
};

struct RunOptions : CommonOptions {
  std::string case_file;
  bool no_output = false;
  bool allow_non_semi_regular = false;
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
};

struct BenchOptions {
  std::vector<std::string> configs;  // "P:N" (degree P, N x N elements)
  bool quick = false;
  bool json = false;
  std::string ordering = "amd";
  bool with_errors = true;
  bool floor = false;  // also time bare CHOLMOD (default settings) on the same matrix
};

struct DimensionOptions {
  std::string file;
  bool exact = false;
  bool json = false;
};

struct BasisOptions {
  std::string case_file;
  std::string export_file;
  bool json = false;
  // --g1 MESH.obj: the G1 macro-patch space S_k^{1,r} on a quad mesh instead.
  std::string g1_mesh;
  int degree = 4;
  int split_smoothness = 1;
  std::string gluing = "symmetric";  // symmetric | geometric | FILE.json
  std::string vtk_file;               // the fitted G1 surface and the --show functions
  std::string show = "extraordinary";  // vertex:N | edge:I-J | face:N | all | extraordinary
  // --pt: the PT-spline basis of the T-mesh instead of a knot-segment collection.
  bool pt = false;
  std::string pt_extension = "auto";  // auto | minimal | horizontal | vertical | diagonalizable
  bool pt_non_negative = true;        // Prop. 1 (--no-prop1 keeps the EEE combinations)
  bool pt_reference = false;          // also the full-extension reference's support sizes
};

int run_command(const RunOptions& o);
int basis_command(const BasisOptions& o);
int g1_basis_command(const BasisOptions& o);
int pt_basis_command(const BasisOptions& o);
int dimension_command(const DimensionOptions& o);
int converge_command(const ConvergeOptions& o);
int adapt_command(const AdaptOptions& o);
int bench_command(const BenchOptions& o);


}  // namespace knotwork
