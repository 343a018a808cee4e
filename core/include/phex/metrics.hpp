// phex — measures of a polygon mesh: planarity, validity, counts.
#pragma once
#include <map>
#include <vector>

#include "phex/mesh.hpp"
#include "phex/surface.hpp"

namespace phex {

// Least-squares plane of a face's vertices: through their centroid, normal along the smallest principal axis.
struct FacePlane {
  Vec3 centroid, normal;
};
FacePlane leastSquaresPlane(const PolyMesh& mesh, int face);

// Distance of the face's farthest vertex from its least-squares plane, divided by the face's mean edge length.
double facePlanarity(const PolyMesh& mesh, int face);
// True when two non-adjacent edges of the closed polygon cross or touch, or an edge is degenerate.
bool polygonSelfIntersects(const std::vector<Vec2>& polygon);
// True when two non-adjacent edges of the face cross (seen in its least-squares plane) or an edge is degenerate.
bool faceSelfIntersects(const PolyMesh& mesh, int face);

struct MeshMetrics {
  std::vector<double> planarity;          // #faces
  std::vector<std::uint8_t> selfIntersecting;  // #faces, 1 where the face crosses itself
  int vertexCount = 0;
  int faceCount = 0;
  std::map<int, int> facesBySize;         // polygon size -> count
  double planarityMax = 0.0;
  double planarityMean = 0.0;
  int selfIntersectingCount = 0;
  // Filled by measure(mesh, surface): vertex distance to the surface over the surface's bounding-box diagonal.
  std::vector<double> surfaceDistance;    // #vertices
  double surfaceDistanceMax = 0.0;
  double surfaceDistanceMean = 0.0;
};

MeshMetrics measure(const PolyMesh& mesh);
// Also measures how far the vertices are from `surface`.
MeshMetrics measure(const PolyMesh& mesh, const Surface& surface);

}  // namespace phex
