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

// The nodes of `mesh` on its boundary (ends of edges of one face).
std::vector<char> boundaryNodes(const PolyMesh& mesh);

// How far the P-Hex mesh's boundary nodes lie from the surface's boundary curve across the surface, in mean
// edges of the mesh (nodes farther than two edges from the curve are left out; none on a closed surface).
struct BoundaryOffset {
  double max = 0, median = 0;
  int nodes = 0;  // boundary nodes measured
};
BoundaryOffset boundaryOffset(const PolyMesh& mesh, const Surface& surface);

}  // namespace phex
