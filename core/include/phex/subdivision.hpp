// phex — Loop subdivision and the §7 route for closed convex genus-0 surfaces.
//
// §7: "for the important class of convex surface of g = 0, subdivision surface schemes provide an effective
// means for generating valid triangulations": Loop subdivision of a convex control polyhedron gives a
// convex triangle mesh whose vertices all have valence 6 except the control's own vertices, and its
// triangles contain their Dupin centres with respect to the limit surface, so by Proposition 4 the dual
// P-Hex mesh is valid. Euler's formula forces the non-hexagons: a valence-3 mesh of genus g with pentagons,
// hexagons and heptagons only has F5 - F7 = 12 (1 - g); the icosahedron's 12 valence-5 vertices become the
// 12 pentagons of Figure 21 (right).
#pragma once
#include <cstddef>
#include <memory>

#include "phex/mesh.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/triangulation.hpp"

namespace phex {

// Largest mesh loopSubdivide produces, and so the finest surface subdivisionTriangulation builds
// (its triangulation has 16 times fewer triangles). About 0.7 GB with the MeshSurface built on it,
// within the wasm module's 2 GB.
constexpr std::size_t kMaxSubdivisionTriangles = std::size_t(1) << 22;  // 4,194,304

// Levels of subdivision between the triangulation and the surface it is measured against.
constexpr int kSubdivisionSurfaceExtraLevels = 2;

// Loop's scheme applied `levels` times (0 returns a copy).
//   control.V  #V by 3 positions, control.F  #F by 3 vertex ids, CCW; a manifold, open or closed.
// The result keeps the vertex ids of its input (vertex i of the input is vertex i of the output, at its
// refined position), then one new vertex per edge; each triangle is split in four, orientation kept.
// Rules (Loop 1987):
//   interior edge ab with opposite vertices c, d:  3/8 (a + b) + 1/8 (c + d)
//   interior vertex of valence n:                   (1 - n beta) v + beta * sum of neighbours,
//                                                   beta = (5/8 - (3/8 + 1/4 cos(2 pi / n))^2) / n (Loop's
//                                                   original weights: 1/16 for n = 6, bounded curvature at n = 5)
//   boundary edge ab:                               1/2 (a + b)
//   boundary vertex with boundary neighbours b0, b1: 3/4 v + 1/8 (b0 + b1)
// so boundary curves are subdivided as cubic B-splines, independently of the interior.
// Throws Error(InvalidParameter) for levels < 0 or an output above kMaxSubdivisionTriangles, and
// Error(InvalidInput) for an index out of range, a repeated vertex in a triangle, an edge used by more
// than two triangles or twice in the same direction, or a vertex where two boundary curves meet.
TriMesh loopSubdivide(const TriMesh& control, int levels);

// The points of the Loop limit surface that the vertices of `mesh` converge to (limit masks):
//   interior vertex of valence n:  (1 - n chi) v + chi * sum of neighbours, chi = 1 / (n + 3 / (8 beta))
//                                  (1/2 v + 1/12 per neighbour for n = 6)
//   boundary vertex:               2/3 v + 1/6 (b0 + b1), the cubic B-spline limit of the boundary curve.
// A vertex of no triangle keeps its position. Same checks and errors as loopSubdivide.
TriMesh loopLimitPositions(const TriMesh& mesh);

// Exact unit normals of the Loop limit surface at the limit points of the vertices of a closed mesh, from
// the tangent masks t1 = sum cos(2 pi i / n) p_i, t2 = sum sin(2 pi i / n) p_i over the one ring p_0 .. p_n-1
// in CCW order; normal = t1 x t2 / |t1 x t2|, on the side the triangles' CCW orientation points to.
// Returns #V by 3. Throws Error(InvalidInput) naming a boundary vertex (the boundary tangent masks are not
// implemented) and for a non-manifold mesh.
Points loopLimitNormals(const TriMesh& mesh);

// Control polyhedra (closed, convex, outward CCW faces).
// The regular icosahedron inscribed in the sphere of `radius` (> 0), a vertex on +z: 12 vertices of valence 5,
// the control structure of Figure 21 (right). Its limit surface is close to, not exactly, a sphere.
TriMesh icosahedronControl(double radius);
// The icosahedron of circumradius 1 scaled by `semiAxes` (each > 0) along x, y, z: an affine image of a
// convex polyhedron is convex, and its limit surface is an ellipsoid-like free-form shape (not a quadric).
TriMesh stretchedIcosahedronControl(const Vec3& semiAxes);
// An egg: the unit icosahedron with its upper half (z > 0) scaled by `top` and its lower half by `bottom`
// along z (both > 0): a convex shape without the icosahedron's central symmetry. Convex for every
// top, bottom > 0: each edge's convexity test (a tetrahedron volume) is linear in top / bottom and holds
// at both ends of (0, inf).
TriMesh eggControl(double top, double bottom);

// Checks a control mesh for the §7 route and returns it cleaned (cleanTriMesh: degenerate triangles
// dropped, faces oriented outward). Throws
//   Error(InvalidInput) for a malformed mesh (see cleanTriMesh),
//   Error(CannotTile) for more than one connected component, a boundary (naming a boundary edge), genus
//   other than 0 (Euler characteristic V - E + F != 2), or a reflex edge: the dihedral angle measured
//   inside exceeds 180 degrees (naming the edge's vertices and the angle). Flat edges (180 degrees) pass.
TriMesh checkConvexControl(const TriMesh& control);

// Number of Loop levels for the §7 route (0 .. the most that kMaxSubdivisionTriangles allows for the
// surface): when cell > 0, the level whose limit-position mesh has the mean edge length nearest to `cell`
// (model units, nearest on a log scale); otherwise the level whose vertex count (= hexagons of the dual)
// is nearest to `faces` (>= 1). The same convention as PipelineParams: cell wins over faces.
// Throws Error(InvalidParameter) when cell is not finite or negative, faces < 1 with cell == 0, or the
// size asked for needs more levels than the memory limit allows; the control errors of checkConvexControl.
int subdivisionLevels(const TriMesh& control, int faces, double cell);

struct SubdivisionTriangulation {
  // The control subdivided `levels` times, vertices at their limit positions (uv is empty; notes say
  // how many levels and which valences occur).
  Triangulation triangulation;
  // The control subdivided `levels + kSubdivisionSurfaceExtraLevels` times at limit positions, as the
  // surface to measure curvature against: every triangulation vertex is one of its vertices (a vertex's
  // limit point does not move under further subdivision), so the triangulation lies on it.
  std::shared_ptr<MeshSurface> surface;
  int levels = 0;
};

// §7: a valid triangulation of the limit surface of a convex genus-0 control, for dupinDual(triangulation,
// *surface) and planarize. `levels` >= 0 (see subdivisionLevels). Throws what checkConvexControl throws,
// and Error(InvalidParameter) when the surface would exceed kMaxSubdivisionTriangles.
SubdivisionTriangulation subdivisionTriangulation(const TriMesh& control, int levels);

// §7 for an uploaded closed convex surface, which comes as a fine triangle mesh rather than a control
// polyhedron: whether `surface` is one (closed, genus 0, every vertex's normal pointing away from the centroid
// of its vertices, and K > 0 at kConvexShare of them), and a triangulation of it from the icosahedron: each
// face of the icosahedron cut into frequency^2 triangles and projected onto the unit sphere (a geodesic
// sphere, 10 frequency^2 + 2 vertices, all of valence 6 but the icosahedron's 12 of valence 5), mapped onto
// the surface by its principal axes and extents (an ellipsoid of the same size) and then to the closest
// points. Its faces are CCW seen from the side the surface's normals point to. Throws Error(InvalidParameter)
// for frequency < 1.
constexpr double kConvexShare = 0.99;
bool closedConvexUpload(const MeshSurface& surface);
Triangulation geodesicTriangulation(const MeshSurface& surface, int frequency);

}  // namespace phex
