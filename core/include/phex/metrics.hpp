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
// The adjugate of a symmetric 3x3 matrix (read from its upper triangle). For a face's covariance about its
// centroid, with eigenvalues l0 <= l1 <= l2, its dominant eigenvector (eigenvalue l1 l2) is the normal of the
// least-squares plane, which power iteration on it reaches by l0 / l1 a step; its trace is 0 for collinear corners.
Eigen::Matrix3d symmetricAdjugate(const Eigen::Matrix3d& m);

// Distance of the face's farthest vertex from its least-squares plane, divided by the face's mean edge length.
double facePlanarity(const PolyMesh& mesh, int face);
// The same against `plane` (e.g. the face's least-squares plane, known already).
double facePlanarity(const PolyMesh& mesh, int face, const FacePlane& plane);
// `normal` or its opposite, whichever is turned like the face's vector area (Newell's vector): the corners run
// counterclockwise seen from the side it points to.
Vec3 normalLikeFace(const PolyMesh& mesh, int face, const Vec3& normal);
// Signed area of a closed polygon, positive where it runs counterclockwise.
double signedArea(const std::vector<Vec2>& polygon);
// True when two non-adjacent edges of the closed polygon cross or touch, or an edge is degenerate.
bool polygonSelfIntersects(const std::vector<Vec2>& polygon);
// True when two non-adjacent edges of the face cross (seen in its least-squares plane) or an edge is degenerate.
bool faceSelfIntersects(const PolyMesh& mesh, int face);
// The same, with the corners projected onto a plane of the given normal (e.g. the face's current plane).
bool faceSelfIntersects(const PolyMesh& mesh, int face, const Vec3& normal);
// faceSelfIntersects(mesh, f) of every face (1: it crosses itself), over threads.
std::vector<char> selfIntersectingFaces(const PolyMesh& mesh);
// How far the face, its corners projected onto a plane of the given normal, is from crossing itself: the
// smallest distance from a corner to an edge not at it, 0 when it crosses itself already. Moving one corner
// by less than this keeps the polygon simple (two edges first touch with a corner on the other edge).
double faceFoldMargin(const PolyMesh& mesh, int face, const Vec3& normal);

// The 4-point planarity measure of libhedra, for comparison: for every run of four consecutive corners, the
// distance between the lines of its two diagonals over their mean length; the face's value is the root mean
// square over its runs, in percent.
double facePlanarityDiagonals(const PolyMesh& mesh, int face);

// How far a hexagon is from the affine image of a template (§4.2, Fig. 12): the regular hexagon (K > 0) or
// the quasi-regular one, two halves of a regular hexagon juxtaposed back to back (K < 0). The least-squares
// affine fit over the six cyclic alignments; root mean square residual over the root mean square radius
// (0 for an exact affine copy). `corners` are in the face's plane, counterclockwise.
double affineRegularityDefect(const std::vector<Vec2>& corners, bool quasiRegular);

// An edge shorter than this share of the mean edge counts as short (MeshMetrics::shortEdgeCount).
inline constexpr double kShortEdge = 0.01;

struct MeshMetrics {
  std::vector<double> planarity;          // #faces
  std::vector<double> planarityDiagonals; // #faces, libhedra's measure in percent
  std::vector<std::uint8_t> selfIntersecting;  // #faces, 1 where the face crosses itself
  std::vector<std::uint8_t> convex;       // #faces, 1 for a convex polygon
  std::vector<double> faceArea;           // #faces, area of the polygon in its least-squares plane
  int vertexCount = 0;
  int faceCount = 0;
  std::map<int, int> facesBySize;         // polygon size -> count
  double planarityMax = 0.0;
  double planarityMean = 0.0;
  int selfIntersectingCount = 0;
  double edgeLengthMin = 0, edgeLengthMax = 0, edgeLengthMean = 0;
  // Edges shorter than kShortEdge of the mean edge, each once: their two nodes nearly coincide, so where they
  // meet four panels meet in effect (next to parabolic curves a planar hexagon tends to a quad, §3).
  int shortEdgeCount = 0;
  double faceAreaMin = 0, faceAreaMax = 0, faceAreaMean = 0;
  std::map<int, int> vertexValence;      // number of faces at a vertex -> count (3 inside a P-Hex mesh)
  // Filled by measure(mesh, surface), from the Gaussian curvature at each face's centre:
  // §3: a valid face is convex where K > 0 and non-convex where K < 0 (parabolic faces may be either).
  // A face whose corners lie where K has another sign than at its centre spans a parabolic curve (§6 step 1)
  // and is counted in parabolicFaceCount instead.
  std::vector<std::uint8_t> convexityMismatch;  // #faces, 1 where the face contradicts the sign of K
  int convexityMismatchCount = 0;
  int parabolicFaceCount = 0;                   // faces across a parabolic curve, not judged
  // affineRegularityDefect of each hexagon against the template the sign of K calls for; -1 where it does not
  // apply (not a hexagon, or a parabolic face).
  std::vector<double> regularity;
  double regularityMean = 0.0;
  // Filled by measure(mesh, surface): vertex distance to the surface over the surface's bounding-box diagonal.
  std::vector<double> surfaceDistance;    // #vertices
  double surfaceDistanceMax = 0.0;
  double surfaceDistanceMean = 0.0;
};

MeshMetrics measure(const PolyMesh& mesh);
// Also measures how far the vertices are from `surface`.
MeshMetrics measure(const PolyMesh& mesh, const Surface& surface);

// The largest distance of a vertex of `mesh` to `surface` (absolute; 0 for no vertices): measure's
// surfaceDistanceMax times the diagonal, without the rest of the measures.
double largestSurfaceDistance(const PolyMesh& mesh, const Surface& surface);

// The largest distance from `points` (an upload's vertices, an analytic surface's samples) to the polygon mesh
// (its faces fanned from their centroids): where a part of the surface has no panel over it. NaN for a mesh so
// spread out that the search grid would be too large.
// `where`, if given, receives the index of the point farthest from the mesh (-1 for no point).
double largestGapToMesh(const PolyMesh& mesh, const std::vector<Vec3>& points, int* where = nullptr);

}  // namespace phex
