// phex — measures of a polygon mesh: planarity, validity, counts.
#pragma once
#include <map>
#include <vector>

#include "phex/mesh.hpp"

namespace phex {

// Distance of the face's farthest vertex from its least-squares plane, divided by the face's mean edge length.
double facePlanarity(const PolyMesh& mesh, int face);
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
};

MeshMetrics measure(const PolyMesh& mesh);

}  // namespace phex
