// phex — regular triangulations of a parametric surface.
#pragma once
#include <vector>

#include "phex/mesh.hpp"
#include "phex/surface.hpp"

namespace phex {

struct Triangulation {
  TriMesh mesh;
  std::vector<Vec2> uv;  // #V parameters of the vertices on the surface
};

// Edge length that gives about `faces` hexagons (one per interior vertex) on the surface.
double cellForFaceCount(const ParametricSurface& surface, int faces);

// A lattice triangulation in parameter space: rows of constant v, spaced so that triangles are close
// to equilateral in 3D for edge length `cell`, every other row shifted by half a step. Every interior
// vertex has valence 6. Periodic directions close up without a seam.
Triangulation latticeTriangulation(const ParametricSurface& surface, double cell);

}  // namespace phex
