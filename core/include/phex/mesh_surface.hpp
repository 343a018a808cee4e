// phex — an uploaded triangle mesh as a Surface (§6: S given as a triangle mesh).
#pragma once
#include <string>
#include <vector>

#include "phex/mesh.hpp"
#include "phex/surface.hpp"

namespace phex {

// A triangle mesh seen as a smooth surface:
// - at each vertex, the shape operator is estimated by fitting a cubic jet z(x, y) (a degree-3 height
//   function, falling back to degree 2 where too few points) in the frame of the vertex normal, over
//   the smallest k-ring (k >= 2) with at least kMinJetPoints vertices (grown through no hub: kCrowdedVertex),
//   weighted by distance. The normal is re-estimated from the fit; boundary vertices fit their one-sided
//   neighbourhood the same way. On a
//   noisy mesh (the vertices' median distance to their fitted jets over kNoisyMesh of the mean edge: a
//   scan, jittered heights) the fits are redone over wider rings (noise()), since the noise's share of the
//   curvature falls as the cube of the patch's radius, each stopping before a fold (kPatchTurnDegrees); a
//   jet whose normal turns far from its triangles' (kJetTurnDegrees) gives way to theirs;
// - inside a triangle, the vertices' normals and 3D shape tensors (k1 d1 d1^T + k2 d2 d2^T) are
//   interpolated barycentrically and the tensor is restricted to the tangent plane of the interpolated
//   normal before its eigen-decomposition, so curvatures and directions vary smoothly (eigenvectors are
//   never interpolated, they flip sign and swap);
// - closest points are found exactly through a uniform grid of cells about two mean edges wide (the
//   triangles whose boxes meet each cell), searched in growing shells of cells around the query until the
//   nearest triangle found is provably the nearest, falling back to an AABB tree over the triangles for
//   points far from the mesh.
// Normals follow the triangles' orientation (CCW seen from the normal side).
class MeshSurface : public Surface {
 public:
  static constexpr int kMinJetPoints = 16;
  static constexpr int kCrowdedCell = 64;
  // Jet patches grow through vertices of at most this many neighbours (a UV sphere's pole of 500 segments is
  // one), not through a hub's (a fan-triangulated cap's centre, whose neighbours are the whole cap).
  static constexpr int kCrowdedVertex = 512;
  // Median fit residual, relative to the mean edge, above which a mesh counts as noisy. Meshes sampled from
  // smooth surfaces stay under 1e-4 (lattices of the analytic surfaces, jittered or graded grids of height
  // fields, coarse ones); heights jittered by 12 % of an edge give 0.04.
  static constexpr double kNoisyMesh = 0.002;
  // The wider rings of a noisy mesh's fits (past the second) take no vertex whose normal turns from the
  // fitted vertex's by more than this: a patch across a fold is no height field over any plane, and its jet's
  // normal is anyone's. (At 40 degrees the genus-3 model's fits kept to 2 rings nearly everywhere, and its
  // noisier directions took Method 2's trial lays 8 times as long.)
  static constexpr double kPatchTurnDegrees = 60;
  // A jet whose normal turns from its vertex's triangles' (area-weighted) by more than this has missed the
  // surface: the triangles' normal stands.
  static constexpr double kJetTurnDegrees = 40;

  // `mesh` must be clean (as readMesh / cleanTriMesh return it): throws Error(InvalidInput) for no
  // triangles, an index out of range, a non-finite coordinate, an edge used twice in the same direction
  // or by more than two triangles, or a vertex where two boundaries meet.
  //   mesh.V  #V by 3 positions (any unit); mesh.F  #F by 3 vertex ids.
  explicit MeshSurface(TriMesh mesh, std::string name = "mesh");

  std::string name() const override { return name_; }
  // Nearest point over all triangles, with the interpolated geometry there.
  LocalGeometry closestPoint(const Vec3& p) const override;
  // Every k-th vertex of the mesh, with its estimated geometry.
  std::vector<LocalGeometry> samples(int count) const override;
  Box3 bounds() const override { return bounds_; }
  bool isClosed() const override { return boundaryLoops_.empty(); }
  // The boundary loops' vertices (the upload's own boundary edges).
  std::vector<std::vector<Vec3>> boundaryCurves() const override;

  const TriMesh& mesh() const { return mesh_; }
  int vertexCount() const { return static_cast<int>(mesh_.V.rows()); }
  // V - E + F: 2 - 2g for a closed surface of genus g (summed over its components), 1 for a disk.
  int eulerCharacteristic() const {
    return vertexCount() - static_cast<int>(neighbours_.size() / 2) + static_cast<int>(mesh_.F.rows());
  }
  // The estimated geometry at vertex i (point = the vertex).
  const LocalGeometry& vertexGeometry(int i) const { return vertexGeometry_[i]; }
  const std::vector<LocalGeometry>& vertexGeometries() const { return vertexGeometry_; }
  // Geometry at barycentric coordinates (b0, b1, b2), summing to 1, of triangle f.
  LocalGeometry geometryInTriangle(int f, const Vec3& barycentric) const;
  // Each boundary loop as vertex ids in order, the surface on the left (following the triangles' edges).
  const std::vector<std::vector<int>>& boundaryLoops() const { return boundaryLoops_; }
  bool isBoundaryVertex(int i) const { return onBoundary_[i] != 0; }
  // How noisy the mesh is: the vertices' median distance to the cubic jets fitted around them (first over
  // their 2-rings), relative to the mean edge; and over how many rings the curvature was fitted (2, or up to
  // 8 where noise() is above kNoisyMesh).
  double noise() const { return noise_; }
  int curvatureRings() const { return curvatureRings_; }
  // Whether the mesh is a developable: one principal curvature under kDevelopableRatio of the other at
  // kDevelopableShare of the vertices where it is curved (over kCurvedScale / diagonal). That curvature is
  // then 0 wherever it is under kDevelopableRatio of the other, as on an analytic developable, and also
  // where both are small (under kPlanarShare of the vertices' median largest curvature: about an inflection
  // of a corrugated profile, whose planar points the fits give no sharp ratio).
  bool developable() const { return developable_; }
  static constexpr double kCurvedScale = 1e-6;
  // Whether the mesh is a plane (a flat façade, a sloping roof): its largest curvature under kCurvedScale /
  // diagonal at every vertex. Its principal directions are then undefined everywhere.
  bool planar() const { return planar_; }
  // Interior edges where the two triangles' planes turn by more than kCreaseDegrees (and at most kFoldDegrees,
  // beyond which the triangles fold back over each other: a broken mesh, not a ridge; slivers aside): a ridge
  // or a valley, where the surface has no tangent plane. How many, the sharpest turn (degrees) and the middle
  // of its edge.
  struct Creases {
    int edges = 0;
    double degrees = 0;
    Vec3 at = Vec3::Zero();
    double medianDegrees = 0;  // the median turn over all interior edges (slivers aside)
    // A ridge or valley, not a coarse faceting: the sharpest turn stands out from the typical one (a gable's
    // 44 degrees against 0; a low-poly dome's 30 against a median of 10 does not).
    bool sharp() const { return edges > 0 && degrees > 3 * medianDegrees + 15; }
  };
  static constexpr double kCreaseDegrees = 30.0, kFoldDegrees = 150.0;
  const Creases& creases() const { return creases_; }

  // The mesh refined into a smooth surface near its vertices: each triangle split into k x k, its points on the
  // blend of their projections onto the cubic jets fitted around the vertices near them (the fits its curvature
  // comes from, over two rings, shifted to pass through their vertex). Like Phong tessellation with the corners'
  // tangent planes replaced by their cubic jets. How the jets are weighted:
  //  - Blend::Smooth: each jet reaches kBlendReach times its vertex's longest edge, with a weight falling smoothly
  //    to 0 there (Wendland's C2 function); every point takes the jets that reach it, the vertices too. The
  //    surface is smooth across the triangles' edges, and on a noisy upload the vertices' scatter is averaged out
  //    with the jets'. Measured on the shared models refined (20 runs: five models at 1500, 3000, 5000 and 10000
  //    faces), against Blend::Barycentric: singular points of the global field 2269 -> 945 (the car at 10000
  //    faces 374 -> 74, the intersection shell 909 -> 62), hexagons at >= 3000 faces 89.84 -> 90.66 %, nodes of
  //    four 111 -> 80. A reach of 1.0 / 1.2 / 1.5 / 2.0: 89.85 / 90.95 / 90.55 / 89.47 % (the wider, the farther
  //    the jets are taken past the rings they were fitted over); as interpolating Shepard weights (through the
  //    vertices): 90.13 %; the jets refitted on the blended vertices and blended again: 90.85 %.
  //  - Blend::Barycentric: the triangle's three corners' jets by the point's barycentric coordinates, so the
  //    surface passes through every vertex and is continuous across edges (an edge's points depend on its two ends
  //    alone) but its curvature kinks at every edge. For an uneven upload (slivers among its triangles: a
  //    marching-tetrahedra mesh), whose slivers the smooth blend's moved vertices turn over: the generated genus 3
  //    at 100k faces refined smoothly turned by 46 degrees between neighbouring triangles (laid on its facets
  //    then, 93.4 -> 86.3 % hexagons), and the genus 2's field mesh came out 2.6 times as large (1.3 GB).
  // A point no jet reaches (a degenerate triangle) takes the barycentric blend. The vertices keep their ids
  // (0 .. #V-1), then come the edges' points, then the triangles' inner points; triangles keep their orientation.
  // Throws Error(InvalidParameter) for k < 1 or a result over kMaxRefinedTriangles.
  enum class Blend { Smooth, Barycentric };
  TriMesh refined(int k, Blend blend = Blend::Smooth) const;
  static constexpr std::size_t kMaxRefinedTriangles = std::size_t(1) << 20;  // 1,048,576
  static constexpr double kBlendReach = 1.35, kBlendReachSpread = 3.0;

  // A surface made of another's refined(k): that mesh's triangles and vertex count (its vertices are this mesh's
  // first ones) and k, for what is smooth at its scale (the global method's cell scale is solved on it: on a
  // 20k-triangle upload refined 7 x 7, 10k unknowns instead of 490k); k = 0 on any other surface.
  struct Refinement {
    Triangles F;
    int vertices = 0, k = 0;
  };
  const Refinement& refinement() const { return refinement_; }
  // Says that this mesh is `coarse`.refined(k) (before the surface is shared).
  void setRefinement(const TriMesh& coarse, int k);

 private:
  struct Node {
    Box3 box;
    int first = 0;  // leaf: first index into triangleOrder_; inner: index of the left child (right = first + 1)
    int count = 0;  // leaf: number of triangles; 0 for an inner node
  };
  void buildTopology();
  void noteCrease(int f, int g, int a, int b, std::vector<double>& turns);
  Creases creases_;
  Refinement refinement_;
  // Fits every vertex's jet over at least `rings` rings; returns the median fit residual.
  double estimateCurvature(int rings);
  // One vertex's fit: its shape tensor and normal, and the jet z(x, y) in `frame` (columns: x, y and the
  // trial normal z it was fitted along) as sum coefficient[i] * monomial_i(x * scale, y * scale) / scale over
  // `terms` monomials (0: no jet could be fitted).
  struct VertexFit {
    Eigen::Matrix3d tensor = Eigen::Matrix3d::Zero(), frame = Eigen::Matrix3d::Identity();
    Vec3 normal = Vec3::UnitZ();
    double residual = 0, scale = 0, coefficient[10] = {0};
    int terms = 0;
  };
  struct FitScratch {
    explicit FitScratch(int vertices) : stamp(vertices, -1) {}
    std::vector<int> stamp, patch;
    std::vector<Vec3> local;
  };
  std::vector<Vec3> trialNormals() const;
  // `trial`: every vertex's trial normal (trialNormals()); rings past the second stop short of a vertex whose
  // trial normal turns from v's by more than kPatchTurnDegrees.
  VertexFit fitVertex(int v, int minRings, const std::vector<Vec3>& trial, FitScratch& scratch) const;
  void buildTree();
  void buildGrid();
  // The grid cell holding coordinate x along `axis`, clamped to the grid (NaN: 0).
  int gridCellOf(double x, int axis) const;
  // Squared distance from p to triangle f, and the barycentric coordinates of the nearest point on it.
  double triangleDistance(int f, const Vec3& p, Vec3& barycentric) const;
  // Lowers `best` (a squared distance) to the nearest triangle's, setting `triangle` and `barycentric`.
  void searchTree(const Vec3& p, double& best, int& triangle, Vec3& barycentric) const;
  // The same through the grid; false when the shells searched cannot prove the nearest (then `best` is
  // still an upper bound, reached by `triangle`), or when the point's cell holds more than kCrowdedCell
  // triangles (then the tree is faster).
  bool searchGrid(const Vec3& p, double& best, int& triangle, Vec3& barycentric) const;

  TriMesh mesh_;
  std::string name_;
  double noise_ = 0;
  bool developable_ = false;
  bool planar_ = false;
  double planarBelow_ = 0;  // a developable's largest curvature under which a point counts as planar
  std::vector<Vec3> rulings_;  // a developable's ruling direction at each vertex (planar ones: borrowed)
  void snapDevelopable(LocalGeometry& g) const;
  void findRulings();
  void alongRuling(LocalGeometry& g, const Vec3& ruling) const;
  int curvatureRings_ = 2;
  Box3 bounds_;
  std::vector<int> neighbourStart_, neighbours_;  // vertex adjacency in compressed rows
  std::vector<char> onBoundary_;
  std::vector<std::vector<int>> boundaryLoops_;
  std::vector<LocalGeometry> vertexGeometry_;
  std::vector<Eigen::Matrix3d> shapeTensor_;  // k1 d1 d1^T + k2 d2 d2^T per vertex
  std::vector<Node> nodes_;
  std::vector<int> triangleOrder_;
  // Grid: cell (i, j, k) covers origin + h [i, i+1] x [j, j+1] x [k, k+1]; its triangles are
  // cellTriangles_[cellStart_[c] .. cellStart_[c + 1]) with c = i + n0 (j + n1 k).
  Vec3 gridOrigin_ = Vec3::Zero();
  double gridCell_ = 0, gridInverseCell_ = 0;
  int gridSize_[3] = {0, 0, 0};
  std::vector<int> cellStart_, cellTriangles_;
  std::vector<Eigen::Vector4d> spheres_;  // per triangle: a ball holding it (centre, radius), for quick rejection
};

// Whether `surface` is an uploaded mesh whose vertices lie off smooth fits of their neighbourhoods (noise() over
// kNoisyMesh): its curvature ratios are noise, and the steps tuned on smooth surfaces leave it alone.
bool noisyUpload(const Surface& surface);

// The point of triangle abc nearest to p (exact, by the Voronoi regions of its corners, edges and face).
Vec3 closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// `phex curvature` output: one row per entry of `rows` (for a MeshSurface, its vertexGeometries(), in the
// order of surface.mesh(): the file's vertex order less the vertices no kept triangle uses; STL: distinct
// corners in order of first appearance; MeshReadReport::fileVertex maps each row back to the file), as
// CSV with the header `x,y,z,k1,k2,d1x,d1y,d1z,d2x,d2y,d2z` (17 significant digits).
std::string curvatureCsv(const std::vector<LocalGeometry>& rows);

}  // namespace phex
