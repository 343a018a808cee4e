// phex — from a triangulation to its dual hexagonal mesh (§4.1, §6).
#pragma once
#include <cstdint>
#include <vector>

#include "phex/mesh.hpp"
#include "phex/triangulation.hpp"

namespace phex {

// The dual polygon mesh of a triangulation: one face per triangulation vertex. Faces around boundary vertices
// are closed with points on the boundary edges (and the vertex itself at boundary corners), so the mesh has a
// clean border of planar polygons. In both dualities a boundary triangle whose dual point would lie beyond its
// boundary edge (an obtuse or skinny one) has it moved back onto the edge's line, in the triangle's plane, so
// no node starts off the surface past its border; the solve makes those faces planar again.
struct DualMesh {
  PolyMesh mesh;
  std::vector<int> faceVertex;      // #faces: the triangulation vertex each face is dual to (-1: a clip's filler)
  std::vector<std::uint8_t> boundaryFace;  // #faces: 1 for faces around boundary vertices
  std::vector<int> vertexTriangle;  // #V: the triangle each vertex is dual to, -1 for boundary-edge and corner points
  int fallbackCount = 0;         // dual vertices placed at the centroid (§6 parabolic fallback)
  int untangled = 0;             // dual vertices placed otherwise where their faces crossed themselves
};

// Auto (the pipeline's default): the Dupin dual, and the tangent dual as well where the solve from the Dupin
// dual stalls or leaves faces crossing themselves; the better result is kept.
enum class Duality { Dupin, Tangent, Auto };

// Dupin duality as the §6 initializer: for each triangle and each of its vertices, the Dupin conic (a
// homothetic copy of the Dupin indicatrix) through the vertex and the projections of the other two onto
// its tangent plane; the triangle's dual vertex is the average of the three conic centres. In a parabolic
// region (Gaussian curvatures of differing signs, or |K| h^2 below 1e-8) the centroid is used (§6 step 1).
// With `untangle`, interior faces that cross themselves where their star straddles a parabolic curve get
// their corners' points placed by the tangent planes or at the centroid instead, where fewer faces then cross
// (DualMesh::untangled counts them).
// `cache`: the vertices' geometry as vertexGeometry found it before (see GeometryCache), or null.
DualMesh dupinDual(const Triangulation& triangulation, const Surface& surface, bool untangle = true,
                   GeometryCache* cache = nullptr);

// Tangent duality (§4.1): the dual vertex of each triangle is the intersection of the tangent planes at
// its three vertices. Where the planes are nearly parallel (near parabolic points or on tiny triangles)
// the intersection is ill-posed, and the triangle's centroid is used instead (§6 step 1).
// Throws Error(InvalidInput) for a non-manifold triangulation.
DualMesh tangentDual(const Triangulation& triangulation, const Surface& surface);

// One-ring of every vertex: the incident triangles in CCW order; `closed[v]` is false on the boundary.
struct VertexRings {
  std::vector<std::vector<int>> triangles;
  std::vector<bool> closed;
};
VertexRings vertexRings(const TriMesh& mesh);

}  // namespace phex
