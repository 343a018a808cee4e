// phex — fabrication output: every face of a P-Hex mesh as a flat panel, true to size, with its cut data, and
// every edge as a beam of the frame.
#pragma once
#include <string>
#include <vector>

#include "phex/mesh.hpp"

namespace phex {

// "P" followed by face + 1: the label of a face's panel on the cut sheet and in the schedules (1-based, as in OBJ).
std::string panelLabel(int face);
// Ten significant digits and no "-0": the numbers of the schedules and the cut sheet (a 100 m facade to a
// hundredth of a millimetre).
std::string formatNumber(double x);

// Checks what every fabrication output needs of a polygon mesh and throws Error(InvalidInput) naming the first
// defect, the message starting with `who` ("panels", "structure"): face offsets that do not span the face
// indices, no faces, a coordinate that is not finite, a face of fewer than three corners or one naming a vertex out
// of range. (Degenerate faces are found where each output measures them.)
void checkPolyMesh(const PolyMesh& mesh, const std::string& who);

// An edge of a polygon mesh: a beam of the frame.
struct MeshEdge {
  int a = 0, b = 0;          // its nodes, in the direction the left face runs it
  int left = 0, right = -1;  // the faces either side (right: the other face; -1 at the boundary)
};
// Every edge of `mesh` once, in order of first use by the faces: beam B<k> of the schedules is edges[k - 1].
// Throws Error(InvalidInput), the message starting with `who`, naming the edge where more than two faces share it
// or two run it the same way. Expects a mesh checkPolyMesh passes.
std::vector<MeshEdge> meshEdges(const PolyMesh& mesh, const std::string& who = "panels");

// One face laid flat in its own (least-squares) plane. The outline's frame: corner `base` at the origin, the
// edge from it to the next corner (the longest edge) along +x, +y towards the face, so the outline runs
// counterclockwise seen from the side its normal points to (the surface's normal side for phex meshes).
struct Panel {
  int face = 0;                // index in the mesh; its label is "P" followed by face + 1
  Vec3 centroid, normal;       // the face's least-squares plane
  Vec3 origin, xAxis, yAxis;   // the frame in space: outline point (x, y) lies at origin + x xAxis + y yAxis
  int base = 0;                // the corner at the origin
  std::vector<Vec2> outline;   // the corners in face order, projected onto the plane
  std::vector<double> edges;   // length in space of the edge from corner k to corner k + 1
  std::vector<double> angles;  // interior angle at corner k in degrees, measured in the plane (> 180 where reflex)
  double area = 0;             // of the outline
  double perimeter = 0;        // sum of `edges`
  double planarity = 0;        // farthest corner from the plane over the mean edge length (facePlanarity)
};

// Every face of `mesh` as a Panel, in face order. Throws Error(InvalidInput) naming the face for a vertex id out
// of range, a face of fewer than three corners, a coordinate that is not finite, or a degenerate face (no
// edge longer than round-off, or corners on one line).
std::vector<Panel> flattenPanels(const PolyMesh& mesh);

// Where each panel goes on one sheet: rows filled left to right in label order (shelf packing of the panels'
// bounding boxes), `gap` apart, no wider than `width`.
struct PanelSheetOptions {
  double gap = 0;      // between panels, in the mesh's units; 0: a quarter of the mean edge length
  double width = 0;    // of the sheet; 0: about square; never narrower than the widest panel plus gaps
  bool labels = true;  // each panel's label at its centre (SVG)
  // The mesh's length unit, "mm", "cm", "m" or "in", for an SVG sheet true to size in CAD and print; empty
  // (the default): no size is given and viewers fit the sheet to their window.
  std::string unit;
};
struct PanelSheet {
  double width = 0, height = 0;
  std::vector<Vec2> offset;  // per panel: the sheet position of its outline's (min x, max y) corner
};
PanelSheet layoutPanels(const std::vector<Panel>& panels, const PanelSheetOptions& options = {});

// The panels true to size as an SVG cut sheet (one user unit = one unit of the mesh): each outline a
// <polygon id="P…">, seen from the normal side, with its label. Throws Error(InvalidParameter) for a negative
// or non-finite gap or width, or another unit.
std::string panelsSvg(const std::vector<Panel>& panels, const PanelSheetOptions& options = {});
// The panel schedule as CSV, one row per panel: label, corners, area, perimeter, planarity, centroid and normal
// in space, then edge lengths, corner angles and the flat outline (x y pairs), each list ';'-separated.
std::string panelsCsv(const std::vector<Panel>& panels);

// The beam schedule as CSV, one row per edge of `mesh` (a P-Hex mesh's nodes join three beams): label B<k> in
// order of first use by the faces, its nodes (1-based vertex ids, as in OBJ) and their positions, its length,
// the panels on its left and right (the face that runs it from the first node to the second, and the other;
// empty at the boundary) and the fold between them in degrees: the angle between their planes, positive at a
// ridge (seen from the normal side the panels fall away on both sides), negative in a valley. Throws
// Error(InvalidInput) as flattenPanels does, and naming the edge where more than two faces share it or two run
// it the same way.
std::string beamsCsv(const PolyMesh& mesh);

}  // namespace phex
