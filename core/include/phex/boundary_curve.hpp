// phex — a surface's boundary curve (Surface::boundaryCurves) indexed for nearest-point queries: where the P-Hex
// mesh's boundary nodes are put, and how far they ended from it.
#pragma once
#include <limits>
#include <utility>
#include <vector>

#include "phex/geometry.hpp"
#include "phex/mesh.hpp"
#include "phex/surface.hpp"

namespace phex {

class BoundaryCurve {
 public:
  struct Segment {
    Vec3 a, b;
  };
  // The loops' segments in a uniform grid of cells about `reach` wide (at most 1024 along an axis).
  BoundaryCurve(const std::vector<std::vector<Vec3>>& loops, double reach);

  bool empty() const { return segments_.empty(); }
  const std::vector<Segment>& segments() const { return segments_; }
  // The segments that may lie within `reach` of x (those of the grid cells around x's), into `out`.
  void near(const Vec3& x, std::vector<int>& out) const;
  // The segment among `candidates` (from near) nearest to x, its point nearest x and their distance (segment -1
  // and the distance infinite where there is no candidate; the first of equally near ones).
  struct Closest {
    int segment = -1;
    Vec3 point = Vec3::Zero();
    double distance = std::numeric_limits<double>::infinity();
  };
  Closest closest(const Vec3& x, const std::vector<int>& candidates) const;
  // The point of the curve nearest to x among `candidates` (from near), and its distance; infinite where none.
  std::pair<Vec3, double> nearest(const Vec3& x, const std::vector<int>& candidates) const;
  // The point of the curve nearest to x within reach (the distance infinite where none is that near).
  std::pair<Vec3, double> nearest(const Vec3& x) const;
  // How far x lies from the curve across the surface: its offset from the nearest point of the curve (among
  // `candidates`) in the surface's tangent plane there, leaving out its height over the surface.
  struct Offset {
    double across = std::numeric_limits<double>::infinity();  // infinite where no candidate is
    int segment = -1;
    Vec3 point = Vec3::Zero(), normal = Vec3::UnitZ();
  };
  Offset offset(const Vec3& x, const std::vector<int>& candidates, const Surface& surface) const;

 private:
  std::vector<Segment> segments_;
  Vec3 lo_ = Vec3::Zero();
  int dims_[3] = {1, 1, 1};
  double cell_[3] = {1, 1, 1};
  std::vector<std::pair<long long, int>> cells_;  // (cell key, segment), sorted
  int cellOf(const Vec3& x, int k) const { return gridCell((x(k) - lo_(k)) / cell_[k], dims_[k]); }
  long long key(int i, int j, int k) const { return (static_cast<long long>(i) * dims_[1] + j) * dims_[2] + k; }
};

// The edges of `mesh` that belong to one face (its outline), as (smaller, larger) node pairs, sorted.
std::vector<std::pair<int, int>> outlineEdges(const PolyMesh& mesh);
// The nodes of `mesh` on its boundary (ends of edges of one face).
std::vector<char> boundaryNodes(const PolyMesh& mesh);

// How far the P-Hex mesh's boundary nodes lie from the surface's boundary curve across the surface, in mean
// edges of the mesh (nodes farther than two edges from the curve are left out; none on a closed surface).
struct BoundaryOffset {
  double max = 0, median = 0;
  int nodes = 0;  // boundary nodes measured
};
BoundaryOffset boundaryOffset(const PolyMesh& mesh, const Surface& surface);

// Boundary panels clipped to the boundary curve (PipelineParams::clipBoundary), so that the edge panels can be
// cut as drawn. Each run of a panel's boundary edges (from node a to node b, the nodes it shares with the
// neighbouring boundary panels) is replaced by the boundary curve between a and b, projected onto the panel's
// plane: the panel stays planar, and its edge follows the curve up to the curve's height over that plane. The
// shared nodes a and b first move along the edge they share with the neighbouring panel (the line where the two
// planes meet, so both stay planar) onto the curve's wall (the ribbon of surface normals along it), at most
// kClipReach mean edges and no farther off the surface than the farthest node already is; where that line runs
// along the wall, or the move would fold a panel, the node stays and the curve starts at its nearest point (or at a
// filler's corner: below). The
// curve's points are thinned (Douglas-Peucker) to kClipTolerance mean edges, kept at least kClipSpacing apart, and
// those standing higher over the panel's plane than a moved node may lie off the surface left out. A panel whose clipped polygon would
// cross itself or turn over is clipped again with the curve followed to kClipRetryTolerances mean edges in turn
// (fewer corners); where that fails too it keeps its boundary edges as they were (`skipped`). On the 40-run sweep
// the retries clipped 9 of the 15 panels skipped before, on the shared models at 1500 and 3000 faces 11 of 21 (a
// tenth: 8 and 10), with no planarity changed and one coverage gap closer (the uploaded bumps at 3000 faces 0.27
// -> 0.14 mean edges); straight chords between the ends as the fallback clipped about as many but left the six_s0
// model at 1500 faces a gap of 0.28 mean edges where it had 0.14.
// A shared node that stays more than kFillerOff mean edges off the curve (its edge runs along the wall: where the
// boundary runs near an asymptotic direction, the two panels' planes meet along it) would leave a tooth in the
// outline; instead each of its two panels ends at a corner on the curve kFillerSpan mean edges (or half the node's
// distance, where more) from the node's nearest point, and a triangle (planar whatever its corners) fills the gap between them: the outline follows the
// curve and the node joins three panels (`fillers`).
// A boundary panel whose outline, clipped, turns over (the curve, projected onto its plane, runs beyond its other
// nodes into the surface) lies wholly outside the curve: such panels are removed where the mesh stays a manifold
// without them, and the panels then on the boundary are clipped afresh (`removed`). They are pieces of a boundary
// panel cut in two against a fold, a sliver between the cut and the curve (the uploaded bumps at 2000-5000 faces,
// the bubble, the hyperbolic paraboloid), which no clip could follow.
constexpr double kClipReach = 1.5;
constexpr double kClipTolerance = 0.005;
constexpr double kClipRetryTolerances[] = {0.1, 0.3};
constexpr double kClipSpacing = 0.2;
constexpr double kFillerOff = 0.1, kFillerSpan = 0.25;
struct BoundaryClip {
  int panels = 0;        // boundary panels whose boundary edges now follow the curve
  int skipped = 0;       // boundary panels left as they were
  int nodesMoved = 0;    // nodes moved along their shared edge onto the curve's wall
  int nodesAdded = 0;    // points of the curve added to the panels
  int nodesRemoved = 0;  // boundary nodes of one panel replaced by the curve
  int fillers = 0;       // triangles filling the gap at a shared node left off the curve (kFillerOff)
  int removed = 0;       // boundary panels removed, lying wholly outside the curve
  int cutDropped = 0;    // boundary panels cut in two, dropped before the clip (the pipeline's: no node of four left)
  // The edge as drawn: the largest distance of the curve's points to the P-Hex mesh's outline (the edges of one
  // panel), in mean edges (at most 2): the curve's height over the clipped panels' planes and the thinning, and
  // where panels could not be clipped, how far their edges stay from it.
  double gapMax = 0;
};
// `faceOf`, where given, gets for each face of the clipped mesh the index of the face it was (-1: a filler).
BoundaryClip clipBoundaryPanels(PolyMesh& mesh, const Surface& surface, std::vector<int>* faceOf = nullptr);

}  // namespace phex
