#pragma once
// A family's own modes of `knotwork basis` (the G1 space on a quad mesh, the PT-splines of
// a T-mesh file, knot segments on a T-mesh or collection file): each family adds its options
// to the command and is asked whether the command line or the input selects it. app/ only
// knows this interface (SpaceFamily::add_basis_tool).
#include <string>

namespace CLI {
class App;
}

namespace knotwork {

// What `knotwork basis` gives every tool.
struct BasisRequest {
  std::string file;         // the positional input (may be empty)
  std::string export_file;  // --export
  std::string vtk_file;     // --vtk
  std::string show;         // --show ("" : the tool's default)
  bool json = false;
};

class BasisTool {
 public:
  virtual ~BasisTool() = default;
  // The tool's selecting option was given (--g1 MESH, --pt).
  virtual bool requested() const = 0;
  // Without a selecting option: whether the tool handles this input file by its kind
  // (knot segments take T-mesh and collection files).
  virtual bool claims(const std::string& /*file*/) const { return false; }
  // The option that selects it, for messages ("--g1").
  virtual std::string selector() const = 0;
  // What --show accepts when this tool writes --vtk ("": it writes no .vtu).
  virtual std::string show_help() const { return ""; }
  // Throws InputError when one of the tool's own options was given but the tool is not used.
  virtual void refuse_unused_options() const = 0;
  virtual int run(const BasisRequest& request) const = 0;
};

}  // namespace knotwork
