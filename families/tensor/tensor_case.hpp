#pragma once
// The [space] of the families that live on one NURBS patch (tensor, and the local
// refinements of it: knot segments, PT): degree and elements per geometry knot span, and
// for the tensor family continuity, rational and extra knots.
#include <memory>
#include <string>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/dyadic_knots.hpp"
#include "basis/tensor/tensor_patch.hpp"
#include "cases/case_file.hpp"
#include "basis/core/geometry_map.hpp"

namespace knotwork {

struct CaseDocument;
class CaseReader;
class DocumentNode;

struct PatchSpaceSection : CaseSection {
  TensorSpaceOptions space;
  std::unique_ptr<CaseSection> clone() const override { return std::make_unique<PatchSpaceSection>(*this); }
};

// A volume's [space] (docs/VOLUMES.md): degrees, elements and continuity per direction u, v, w.
struct VolumeSpaceSection : CaseSection {
  TensorVolumeOptions space;
  std::unique_ptr<CaseSection> clone() const override { return std::make_unique<VolumeSpaceSection>(*this); }
};

// The patch space options of a case of any family whose section derives from
// PatchSpaceSection; std::logic_error for other families.
TensorSpaceOptions& patch_space(CaseDescription& c);
const TensorSpaceOptions& patch_space(const CaseDescription& c);

// Family "tensor": [geometry], [space], [problem].
// The keys [space] takes.
const std::vector<std::string>& tensor_space_keys();

// A [geometry] that is a volume is read with its [space] as a VolumeSpaceSection.
void read_tensor_case(const CaseDocument& doc, CaseDescription& c);

// --degree / --elements on a volume case: the same in every direction.
void override_volume_space(TensorVolumeOptions& s, int degree, int elements);

// A volume's [space] degree and elements (both required): one integer or a list [u, v, w].
void read_volume_degree_elements(const CaseReader& r, const DocumentNode& s, const CaseDescription& c, TensorVolumeOptions& o);

// [space] degree (required) and elements (required unless `elements_optional`).
void read_patch_degree_elements(const CaseDocument& doc, TensorSpaceOptions& s, bool elements_optional);

// --degree / --elements with the same validation as the file; `fixed_by` non-empty: the
// case's functions are fixed by that file, and both are refused.
void override_patch_space(TensorSpaceOptions& s, int degree, int elements, const std::string& fixed_by = "");

// The tensor-product start of a one-patch local refinement along `direction`: the geometry's
// knot spans cut into `elements << level` parts; a geometry knot keeps min(its continuity,
// degree - 1) (the L-shape's C0 fold), the new knots are C^(degree-1).
struct PatchBreaks {
  std::vector<double> breaks;
  std::vector<int> interior_multiplicity;  // per interior breakpoint
};
PatchBreaks patch_breaks(const NurbsPatch& geometry, const TensorSpaceOptions& s, int direction, int level);
// The same as the level-0 knots of a dyadic family.
DyadicKnots patch_dyadic_knots(const NurbsPatch& geometry, const TensorSpaceOptions& s, int direction, int level);
// The breaks of one direction whose geometry knots are `g`, of degree `degree`, each span cut
// into elements_per_span << level parts (patch_breaks's rule).
PatchBreaks span_breaks(const BSplineBasis1D& g, int degree, int elements_per_span, int level);
// The level-0 knots of a dyadic family on a volume, along `direction` (0, 1, 2).
DyadicKnots volume_dyadic_knots(const NurbsVolume& volume, const TensorVolumeOptions& s, int direction, int level);

// A one-patch family's mesh made ready: its interfaces from the cells' parameter boxes, and its
// geometry (GeometryError becomes InputError naming [geometry]).
std::unique_ptr<PatchGeometryMap> finish_patch_mesh(const CaseDescription& c, BezierMesh& mesh);

// The start of a dyadic one-patch family's reader: [geometry], then [space] checked
// against `keys`, the tensor family's continuity, insert_knots_* and rational refused with the
// reason (`knots`: what the family's knots are). A geometry file of several patches is
// refused unless `multipatch_allowed`. Returns [space].
const DocumentNode& read_dyadic_patch_start(const CaseDocument& doc, CaseDescription& c, const std::string& family,
                                            const std::vector<std::string>& keys, const std::string& knots,
                                            bool multipatch_allowed = false);

// Refuses (InputError) a level-0 mesh of a dyadic one-patch family that would not fit in
// memory, before it is built; `what` names its kind of cells.
void check_dyadic_start_memory(const CaseDescription& c, const DyadicKnots& u, const DyadicKnots& v, const char* what);

// The same for a refined space of `cells` cells (about one function per cell), before it is
// built: the Galerkin estimate and 4 KB per cell for the family's own tables (measured: 6 KB
// per cell for a whole hierarchical run at p = 3, Galerkin part included).
void check_refined_memory(const CaseDescription& c, double cells, const char* what);

// For families refined by doubling [space] elements per level: throws InputError when the
// finest of `levels` levels would have more than 2^26 cells.
void check_uniform_levels(const TensorSpaceOptions& s, int levels);

}  // namespace knotwork
