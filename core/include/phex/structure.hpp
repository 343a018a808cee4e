// phex — the structure built on a P-Hex mesh: offsets at constant face distance, node axes, torsion-free beams.
//
// At a node of three faces the three face planes touch one cone of revolution (§1: every P-Hex mesh is a conical
// mesh, after Liu et al. 2006 and Pottmann et al. 2007b, "Geometry of multi-layer freeform structures for
// architecture"). So every face plane can be moved by the same distance d along its normal and each node's three
// planes still meet, on the node's axis: the line through the node equidistant from its planes. The axes at the
// two ends of an edge both lie in the bisector plane of the edge's two faces, so the beam spanned by an edge and
// its two axes is a planar quad: the frame is free of torsion, and the panels cut with their sides in those
// bisector planes fit without gaps at any thickness.
//
// Face planes: the planarized faces are planar to about 1e-9 of their edges, not exactly; each face's plane here
// is its least-squares plane (leastSquaresPlane), its normal on the side the face turns counterclockwise
// (normalLikeFace): the surface's normal side for phex meshes. Distances d > 0 go that way.
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "phex/mesh.hpp"
#include "phex/metrics.hpp"
#include "phex/panels.hpp"

namespace phex {

// How a node's axis is found, by the faces at it.
enum class NodeKind : std::uint8_t {
  // Three faces: the axis of the cone of revolution touching their planes, a = N⁻¹(1, 1, 1) for the rows N of their
  // unit normals: n_f · a = 1 for each, so the node's offset at face distance d is V + d a (exact to round-off).
  Cone = 0,
  // Two faces (and the boundary): n_f · a = n_g · a = 1 leaves the axis one turn within the bisector plane of the
  // two faces. The turn is chosen by the boundary rule (BoundaryRule below).
  Boundary = 1,
  // One face (a corner of the boundary): n_f · a = 1 leaves two turns; the boundary rule chooses them too, from
  // the face normal.
  Corner = 2,
  // Four or more faces (where faces were cut), or three whose planes are parallel to one line: no axis is
  // equidistant from all their planes in general. The best fit: the least-squares a of n_f · a = 1 over its faces
  // (smallest |a| among the equally good ones); its offset node is off the shifted planes by d |n_f · a - 1|.
  BestFit = 3,
  // An axis within kFoldedAxisDeg of the node's panels' planes (|a| > 1 / sin kFoldedAxisDeg), or a best fit off
  // its planes' equal distance by more than a quarter: two of its panels folded (nearly) onto each other, as where
  // the solve cut a face that only folding would make planar. Its offset would leap by |a| d, so there is no usable
  // axis: it takes the mean axis of its neighbours that have one (spread inwards through clusters of such nodes;
  // the unit mean of its panels' normals where none is near), so that offsets pass over the fold without a leap,
  // and is named; its panels are not offset by d exactly at it.
  Folded = 4,
  // No face: a vertex no panel uses; it stays in place (a = 0).
  Free = 5,
};
const char* nodeKindName(NodeKind kind);

// The boundary rule. A boundary beam (an edge of one face f, from node v to node w) is a planar quad iff the axes'
// components across the edge within f agree: u · a_v = u · a_w, u = e × n_f (both axes have n_f · a = 1). One
// linear equation per boundary edge in the nodes' free turns. Along each run of boundary edges (a boundary loop,
// or a stretch between nodes whose axes are fixed), phex solves all of them with the turns nearest the reference
// axes (Boundary: the axis along the mean of its two face normals; Corner: the face normal), the least-squares
// norm of the turns; where that solution keeps every axis of the run within kBoundaryTurnLimitDeg of its
// reference, it is taken and the run's beams are planar. Otherwise (a closed loop whose equations are nearly
// singular, turning the axes far off) the run keeps the reference axes, closest to the surface normal, and its
// beams are as planar as that leaves them (reported as twist).
constexpr double kBoundaryTurnLimitDeg = 30.0;

// An offset edge shorter than this share of the mean edge length (or reversed) counts as vanished: the offset
// cannot be taken that far. Edges that short in the mesh itself (nodes that nearly coincide) are named and left
// out of that judgement.
constexpr double kOffsetEdgeVanishes = 1e-3;
// Folded nodes (NodeKind::Folded): an axis closer than this to the node's panels' planes, in degrees.
constexpr double kFoldedAxisDeg = 10.0;

// Nodes on their planes. The structure is built on the face planes (the panels as cut), so each node is first put
// onto them: where its planes meet (Cone), at the nearest point of the line where its two planes meet
// (Boundary), of its plane (Corner), or the least-squares point of its planes (BestFit); Folded and Free nodes
// stay. The move is of the order of the mesh's planarity (1e-9 of an edge), more only where two panels at a node
// are nearly coplanar and the line they meet in is barely defined (NodeAxes::snapMax tells). So the offsets lie in
// the shifted planes and the beams are planar to round-off, not merely to the mesh's planarity.

// The axes of a polygon mesh's nodes, and everything an offset or a beam layer needs of the mesh. Computed once
// per mesh; offsets and beam layers of any distance follow from it.
struct NodeAxes {
  std::vector<FacePlane> planes;         // #F least-squares planes (centroid, unit normal on the normal side)
  double meanEdge = 0;                   // the mesh's mean edge length
  std::vector<std::uint8_t> convex;      // #F: 1 for a convex face (every corner turns left about its normal)
  Points position;                       // #V by 3: the nodes on their planes (see above)
  double snapMax = 0;                    // the largest move onto the planes over the mean edge length
  // #V by 3: a per node, scaled so that n_f · a = 1 for each face f at it (least squares for BestFit): the offset
  // at face distance d puts node v at position(v) + d a(v). |a| = 1 / sin(angle between the axis and its faces) >= 1.
  Points axis;
  std::vector<NodeKind> kind;            // #V
  std::vector<int> nodeFaceOffsets{0};   // #V + 1: the faces at node v are nodeFaces[nodeFaceOffsets[v] ..
  std::vector<int> nodeFaces;            //   nodeFaceOffsets[v + 1]), in order of first use
  std::vector<MeshEdge> edges;           // meshEdges: the beams' order
  std::vector<int> bestFit;              // the BestFit nodes, ascending
  std::vector<int> folded;               // the Folded nodes, ascending
  std::vector<double> residual;          // #V: max |n_f · a - 1| over the node's faces (0 but for BestFit nodes)
  int boundaryBeams = 0;                 // edges of one face
  int boundaryBeamsPlanar = 0;           // of them, planar by the boundary rule (twist under 1e-9 rad)
  int boundaryRuns = 0, boundaryRunsPlanar = 0;  // runs of boundary edges, and those the rule made planar
  double boundaryTwistMaxDeg = 0;        // the largest twist of a boundary beam (0 where all are planar)
  double boundaryTurnMaxDeg = 0;         // the largest angle between a boundary axis and its reference
  // The face distances at which the first offset edge vanishes (kOffsetEdgeVanishes), towards the normals (> 0)
  // and against them (< 0): ±infinity where none does. Faces crossing themselves inside this range are found
  // when an offset is taken.
  double offsetMin = 0, offsetMax = 0;
  std::vector<std::string> notes;        // what a designer should know: best-fit nodes by name, the boundary rule
};

// The node axes of `mesh` (a P-Hex mesh, or any consistently oriented polygon mesh). Throws Error(InvalidInput)
// naming the defect for a malformed mesh (checkPolyMesh, meshEdges) or a degenerate face (no area).
NodeAxes nodeAxes(const PolyMesh& mesh);

// Throws Error(InvalidParameter) unless the face distance d can be taken: d finite and not 0, and no offset edge
// vanishing or reversing at d. The message names the parameter `name` and its `value` (the offset; a beam height:
// d = -value; a panel thickness: d = value), the first edge and panel that collapse, where, and the face distances
// that can be taken. Panels whose offset crosses itself (seen along its normal: pinched panels whose corners
// nearly touch, which any offset may push across) are not an error: they go to `crossing`, where given.
void checkOffsetDistance(const PolyMesh& mesh, const NodeAxes& axes, double d, const std::string& name, double value,
                         std::vector<int>* crossing = nullptr);

// The offset of `mesh` at face distance d (either side; d > 0 towards the normals): the same vertices and faces in
// the same order (so the two files pair up line by line), node v at position(v) + d a(v). Every face lies in its
// plane shifted by d to round-off, but at BestFit and Folded nodes (by d |n_f · a - 1|). Checks d first
// (checkOffsetDistance with what = "offset").
PolyMesh offsetMesh(const PolyMesh& mesh, double d);
PolyMesh offsetMesh(const PolyMesh& mesh, const NodeAxes& axes, double d, std::vector<int>* crossing = nullptr);

// One beam: the quad between an edge (a, b) of the mesh and its offset edge at face distance -h, behind the panels
// (against the normals: inside a closed surface, under a roof).
struct Beam {
  std::array<Vec3, 4> corners;  // node a, node b, b - h a(b), a - h a(a) (nodes on their planes)
  Vec3 normal;                  // the quad's mean plane: normal · x = planeOffset; normal = unit diagonal cross
  double planeOffset = 0;
  double heightA = 0, heightB = 0;  // distance of the back corners from the edge's line, at each end
  // Largest corner distance from the mean plane (through the corners' centroid, along `normal`; for a quad the
  // corners lie at equal distances from it) over the quad's mean edge length: 0 for a planar quad.
  double planarity = 0;
  double twistDeg = 0;          // angle between the planes through the edge and each end's axis (0: planar)
};

struct BeamLayer {
  double height = 0;            // h: the face distance of the beams' back layer
  std::vector<Beam> beams;      // one per edge, in NodeAxes::edges order
  double planarityMax = 0;      // over all beams
  // Over the beams of two faces between nodes neither BestFit nor Folded, degenerate ones aside (edges shorter than
  // kOffsetEdgeVanishes of the mean: their quads have no shape to be planar).
  double interiorPlanarityMax = 0;
  double length = 0;            // sum of the edges' lengths
  std::vector<int> crossing;    // panels whose offset at -h crosses itself (see checkOffsetDistance)
};

// The beam layer of height h > 0 between `mesh` and its offset at -h. Throws Error(InvalidParameter) naming
// beamHeight for h not finite or not positive, or beyond what the offset can take (checkOffsetDistance).
BeamLayer beamLayer(const PolyMesh& mesh, const NodeAxes& axes, double h);

// The structure as a solid model for CAD and viewers: panels with a thickness (each face between its plane and the
// plane shifted by t towards the normal side, its sides in the bisector planes, so neighbouring panels share
// them), beams with a height and width (each beam's quad thickened by the width across its plane, symmetric), and
// the node axes as segments from the beams' back layer to the panels' top. Triangles turn outwards. Positions are
// relative to `origin`: the centre of the mesh's box where that lies more than ten times the box's diagonal from
// the coordinate origin (site coordinates, which 32-bit floats of GPUs and glTF cannot hold), else zero.
struct SolidPart {
  Points V;                      // #V by 3, relative to StructureModel::origin
  Triangles F;                   // #T by 3
  std::vector<int> element;      // #T: the panel (face) or beam (edge) each triangle belongs to
  int elements = 0;              // panels or beams in the part
};
struct StructureModel {
  Vec3 origin = Vec3::Zero();
  SolidPart panels, beams;
  Points axes;                   // 2 rows per node with faces: its axis from the back layer to the top
};

struct StructureOptions {
  std::optional<double> offset;          // face distance of an offset mesh (either side, not 0); none: no offset mesh
  std::optional<double> beamHeight;      // > 0; default a fifth of the mean edge length
  std::optional<double> beamWidth;       // > 0; default a quarter of the beam height
  std::optional<double> panelThickness;  // > 0; default a fiftieth of the mean edge length
};

struct Structure {
  NodeAxes axes;
  std::optional<PolyMesh> offset;        // offsetMesh at options.offset, where asked
  BeamLayer beams;
  double beamWidth = 0, panelThickness = 0;
  StructureModel model;
  std::vector<std::string> notes;        // of these distances: panels whose offsets cross themselves (axes.notes: the rest)
};

// Throws Error(InvalidParameter) naming the first option that is not finite, zero, or negative where not allowed
// (all but offset); the checks that need the mesh (how far the offset can go) come in buildStructure.
void validate(const StructureOptions& options);

// Axes, the offset mesh (where asked), the beam layer and the solid model of `mesh`. Throws as nodeAxes for a bad
// mesh and Error(InvalidParameter) naming the option for a bad option or a distance the offset cannot take.
Structure buildStructure(const PolyMesh& mesh, const StructureOptions& options = {});

// Exports.
// The node schedule as CSV, one row per node (1-based ids, as in OBJ and the beam schedule): kind, faces, position
// (on its planes),
// unit axis, |a| (how far the node moves per unit of face distance), the panels at it (P<n>, ';'-separated), the
// angles between the axis and each of those panels' planes in degrees (equal at a Cone node), the angle between
// the axis and the mean of the panels' normals, and the residual (BestFit).
std::string nodesCsv(const PolyMesh& mesh, const NodeAxes& axes);
// The beam schedule of beamsCsv (of the mesh with its nodes on their planes), each row extended with the beam's
// heights at either end, its plane (unit normal and offset: normal · x = offset), planarity, twist and the quad's
// four corners.
std::string beamsCsv(const PolyMesh& mesh, const NodeAxes& axes, const BeamLayer& layer);
// The solid model as Wavefront OBJ: one object per panel (P<n>) and per beam (B<k>), in the file's coordinates.
std::string toObj(const StructureModel& model);

}  // namespace phex
