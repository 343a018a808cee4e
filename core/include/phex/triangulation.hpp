// phex — triangulations of a surface and their checks (§4.2, §5).
#pragma once
#include <map>
#include <string>
#include <vector>

#include "phex/mesh.hpp"
#include "phex/surface.hpp"

namespace phex {

struct VertexRings;

// A singular point of a direction field: where its directions turn by `index` sixths of a turn around it (+1: a
// vertex of valence 5 of the triangulation, a pentagon of the P-Hex mesh; -1: valence 7, a heptagon).
struct FieldSingularity {
  Vec3 position = Vec3::Zero();
  int index = 0;
};

struct Triangulation {
  TriMesh mesh;
  std::vector<Vec2> uv;  // #V parameters when laid in the parameter domain of a ParametricSurface; else empty
  std::vector<std::vector<Vec3>> fieldLines;  // curves the method traced (base curves, conjugate lines), for display
  std::vector<std::string> notes;             // what the method had to do, e.g. where a lower bound acted
  // Systems of rows laid (layTriangulation): more than one where the rows from L0 left much of the surface
  // uncovered (no one family of rows reaches it, e.g. around a second bump) and seams join them.
  int systems = 1;
  // The singular points of the field the global method laid along (globalTriangulation); empty for the others.
  std::vector<FieldSingularity> singularities;
};

// The surface's closest points (closestPoint) at the vertices of triangulations as vertexGeometry found them, by
// the vertices' exact coordinates: rounds that change a triangulation here and there (the pipeline's rounds
// against folds) look up only the vertices that moved. Each call of vertexGeometry with it adds the points it
// had to look up (closestPoint is a function of the point: an entry kept from an earlier call is the one a look-up
// would give; emptied and filled again each call, the table cost 47 ms a call at 100k faces). One cache serves
// one surface.
class GeometryCache {
 public:
  // The geometry at p, or null where p was not a vertex in any call so far.
  const LocalGeometry* find(const Vec3& p) const;
  // Adds the vertices of V not found before (found[v] == 0) with their geometry.
  void keep(const Points& V, const std::vector<LocalGeometry>& geometry, const std::vector<char>& found);

 private:
  // Open addressing over the entries' numbers (exactPointSlots; an unordered_map took 12 ms a look-up of 100k
  // vertices).
  std::vector<Vec3> keys_;
  std::vector<LocalGeometry> entries_;
  std::vector<int> slots_;
  std::size_t slotOf(const Vec3& p) const;  // the slot holding p, or the empty one where it would go
};

// The local geometry at every vertex: exact from `uv` on a parametric surface, else from closestPoint (the
// vertices found in `cache` taken from there, and the cache then left with these vertices').
std::vector<LocalGeometry> vertexGeometry(const Triangulation& triangulation, const Surface& surface,
                                          GeometryCache* cache = nullptr);

// Area of a surface: the sum of its triangles for an uploaded mesh, a 64 x 64 midpoint rule over the
// parameter domain for an analytic surface.
double surfaceArea(const Surface& surface);
// Edge length that gives about `faces` hexagons (one per vertex) on the surface.
double cellForFaceCount(const Surface& surface, int faces);

// Which parameter lines the rows of a lattice follow.
enum class LatticeRows {
  Auto,  // the lines of smaller mean normal curvature: a developable's rulings (§3), a torus' parallels (§7)
  U,     // rows of constant v
  V      // rows of constant u
};

// A lattice triangulation in parameter space: rows spaced so that triangles are close to equilateral in 3D
// for edge length `cell`, every other row shifted by half a step. Every interior vertex has valence 6.
// Periodic directions close up without a seam. The ends of the shifted rows zigzag half a step in from the
// domain's sides (every interior vertex keeps valence 6); with `straightSides` those rows also get a vertex on
// each side, so the boundary runs along the domain's edges (a sampling of the whole surface, as the global
// method's field mesh needs).
Triangulation latticeTriangulation(const ParametricSurface& surface, double cell, LatticeRows rows = LatticeRows::Auto,
                                   bool straightSides = false);

// What a triangulation promises for its dual P-Hex mesh (§4.2): every interior vertex's star checked in its
// tangent plane with the vertex's Dupin indicatrix — each incident triangle, taken as the fundamental
// triangle of a symmetric star, must satisfy Proposition 4 (K > 0) or 5 (K < 0); valences; edge lengths.
// Stars at parabolic or planar points (classify with tolerance 1e-6 at the mean edge length), and stars across
// a parabolic curve (a vertex of the star where K has the other sign or vanishes, the paper's §6 test for the
// parabolic region), cannot be judged this way (§5.3) and are listed apart.
struct TriangulationCheck {
  int vertices = 0, interiorVertices = 0, boundaryVertices = 0;
  std::map<int, int> interiorValence;  // valence -> count, interior vertices only
  double regularFraction = 0.0;        // interior vertices of valence 6 / interior vertices
  std::vector<int> invalidStars;       // interior vertices whose star fails Proposition 4 / 5
  std::vector<int> parabolicStars;     // interior vertices at or across a parabolic curve (not checkable)
  double edgeMin = 0, edgeMax = 0, edgeMean = 0;
  // Area of the triangulation over the area of the surface (surfaceArea): about 1 when the laying covered
  // the whole surface, less where layers stopped short (at singularities of the field, or where fronts
  // could not go on); -1 for a surface whose area phex cannot take.
  double coverage = -1;
};
TriangulationCheck checkTriangulation(const Triangulation& triangulation, const Surface& surface);

// Per vertex, 1 where checkTriangulation judges its star by Propositions 4/5: an interior vertex, neither at
// nor across a parabolic curve (classify with tolerance 1e-6 at `edgeMean` for it and its neighbours).
std::vector<char> judgedStars(const TriMesh& mesh, const VertexRings& rings, const std::vector<LocalGeometry>& geo,
                              double edgeMean);

// Local repair of the stars checkTriangulation finds invalid: each centre of an invalid star, and each of its
// neighbours, is moved within the surface (at most 0.4 of its ring's mean edge from where it was laid, no
// triangle turned over) to the candidate position — towards its ring's centroid, or a small step in its
// tangent plane — that leaves fewer invalid stars around it, or the same number further from the edge of
// validity. Sweeps until no star is invalid, nothing improves, or `maxSweeps`. Connectivity is unchanged.
// When there were invalid stars, a note says how many were repaired.
struct RepairResult {
  int invalidBefore = 0, invalidAfter = 0;  // invalid stars (as checkTriangulation counts them)
  int moved = 0;                            // vertices moved
  int sweeps = 0;
  int flips = 0;                            // edges flipped where moves alone left a star invalid
};
inline constexpr int kRepairSweeps = 12;
// `marked` (one entry per vertex of `mesh`) grown by `edges` rings: every corner of a triangle with a marked corner
// marked, `edges` times.
void markWithinEdges(const TriMesh& mesh, std::vector<char>& marked, int edges);

// `cache`: the vertices' geometry as vertexGeometry found it before (see GeometryCache), or null. `only` (where
// given, one entry per vertex): the stars to mend are those it marks (the rest, repaired before and unchanged since,
// count as they are: moves and flips next to the marked ones still judge them).
RepairResult repairStars(Triangulation& triangulation, const Surface& surface, int maxSweeps = kRepairSweeps,
                         GeometryCache* cache = nullptr, const std::vector<char>* only = nullptr);

// Drops the slivers along an open boundary: a triangle on a boundary edge whose third corner is an interior
// vertex no higher than `ratio` times that edge above it (where the last row ran along the boundary, or
// stopped slantwise at it). Its dual point falls near or beyond the edge and the boundary panels through it
// fold or cannot be made planar; without it the third corner becomes a boundary vertex with a proper
// panel. One triangle per corner and pass, and only where both ends of the edge keep another triangle
// (connectivity stays manifold, no vertex is left unused). Returns how many were dropped; a note says so.
int trimBoundarySlivers(Triangulation& triangulation, double ratio = 0.35);

// Where the last triangles along an open boundary close the star of a vertex next to it into an invalid one
// (Props 4, 5; e.g. a row ending half a spacing from the boundary, whose triangles up to it are right-angled
// there, which K > 0 does not allow), drops one of them (a failing one if it can): the vertex becomes a
// boundary vertex, as it was before the rows ended on the boundary. One triangle per corner, with an edge on
// the boundary whose ends both keep another triangle. Returns how many were dropped; a note says so.
int openInvalidBoundaryStars(Triangulation& triangulation, const Surface& surface);

}  // namespace phex
