// phex — the global triangulation's internal pieces (phex/global_triangulation.hpp says what the method does).
#pragma once
#include <cmath>
#include <vector>

#include "phex/geometry.hpp"
#include "phex/global_triangulation.hpp"
#include "phex/mesh.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/parallel.hpp"
#include "phex/progress.hpp"
#include "phex/surface.hpp"

namespace phex::global {

// Sums in a fixed order, so that native and WebAssembly builds round alike (see mesh_surface.cpp).
inline double dot(const Vec3& a, const Vec3& b) { return a.x() * b.x() + a.y() * b.y() + a.z() * b.z(); }
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return Vec3(a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(), a.x() * b.y() - a.y() * b.x());
}
inline Vec3 normalized(const Vec3& a) {
  const double n = norm(a);
  return n > 0 ? Vec3(a / n) : a;
}
// `v` less its component along the unit normal `n`.
inline Vec3 tangential(const Vec3& v, const Vec3& n) { return v - dot(v, n) * n; }
// A tangent vector turned by 60 degrees about the unit normal `n` (counterclockwise seen from its tip).
inline Vec3 rotate60(const Vec3& q, const Vec3& n) {
  static const double s = 0.5 * std::sqrt(3.0);
  return 0.5 * q + s * cross(n, q);
}

// The Dupin frame at a point: tangent vectors v map to D v = sigma (t.v) t + (b.v) b / sigma with b = n x t. The
// axis t runs along the principal direction of least |curvature|, and D has determinant 1, so that areas keep
// their size and a cell of edge h in the frame is one of about h in space. In D's image the Dupin indicatrix is a
// circle (up to the bound on its anisotropy, 1 / sigma^2).
struct Frame {
  Vec3 n = Vec3::UnitZ(), t = Vec3::UnitX();
  double sigma = 1;
  Vec3 b() const { return cross(n, t); }
  // Space -> Dupin frame, and back (tangent vectors; a normal component is dropped).
  Vec3 toDupin(const Vec3& v) const {
    const Vec3 bb = b();
    return sigma * dot(t, v) * t + dot(bb, v) / sigma * bb;
  }
  Vec3 fromDupin(const Vec3& v) const {
    const Vec3 bb = b();
    return dot(t, v) / sigma * t + sigma * dot(bb, v) * bb;
  }
  // A vector of the tangent plane as coordinates (t, b) of the Dupin frame (`dupin`: v is in space, mapped by D).
  Vec2 coords(const Vec3& v, bool dupin) const {
    return dupin ? Vec2(sigma * dot(t, v), dot(b(), v) / sigma) : Vec2(dot(t, v), dot(b(), v));
  }
  Vec3 vector(const Vec2& c) const { return c.x() * t + c.y() * b(); }
};

// The discrete Levi-Civita transport of a direction q (in a's Dupin frame) to b's Dupin frame along the edge
// e = x_b - x_a: the rotation that takes the edge's direction as a's frame sees it to the edge's direction as b's
// frame sees it (an isometry of the two frames, unlike D_b D_a^-1, which shears where the frames' axes turn).
inline Vec3 transport(const Vec3& q, const Frame& a, const Frame& b, const Vec3& e) {
  const Vec2 ea = a.coords(e, true), eb = b.coords(e, true), qa = a.coords(q, false);
  const double na = ea.norm(), nb = eb.norm();
  if (!(na > 0) || !(nb > 0)) return b.vector(qa);
  // (qa / ea) eb as complex numbers, ea and eb unit.
  const Vec2 rel((qa.x() * ea.x() + qa.y() * ea.y()) / na, (qa.y() * ea.x() - qa.x() * ea.y()) / na);
  return b.vector(Vec2((rel.x() * eb.x() - rel.y() * eb.y()) / nb, (rel.x() * eb.y() + rel.y() * eb.x()) / nb));
}

// The mesh the fields live on: the surface sampled finely (a few vertices per cell), each vertex with its frame.
// A triangle mesh's half-edges by their start, each row sorted: whether a -> b is one, by binary search (a hash
// set of them took 4 % of a run at 10k faces in the field mesh's topology, 5 ms in the extraction's notch closing).
class HalfEdges {
 public:
  HalfEdges(const Triangles& F, int vertices);
  bool has(int a, int b) const;

 private:
  std::vector<int> start_, ends_;
};

struct FieldMesh {
  Points V;                         // #V by 3 points on the surface
  Triangles F;                      // #F by 3, CCW seen from the normal side
  std::vector<Frame> frame;         // #V
  std::vector<double> area;         // #V: a third of the incident triangles' areas
  std::vector<double> curvature;    // #V: largest |principal curvature|
  std::vector<double> alignWeight;  // #V in [0, 1]: how anisotropic the (bounded) Dupin metric is
  // #V in [0, 1]: how anisotropic the curvature is (GlobalOptions::principalTrial's weight of the alignment,
  // taken where larger than alignWeight)
  std::vector<double> principalWeight;
  std::vector<int> start, adjacent; // vertex adjacency in compressed rows, each row sorted
  std::vector<std::vector<int>> loops;  // boundary loops, vertex ids in order with the surface on the left
  std::vector<char> boundary;       // #V
  std::vector<Vec3> boundaryTangent;  // #V: unit tangent of the boundary at boundary vertices (zero elsewhere)
  std::vector<int> component;       // #V: connected component
  // The coarser mesh the field mesh refines (an upload as it is, an analytic surface's parameter lattice): its
  // vertices are the field mesh's first ones, and `where` gives each field-mesh vertex's triangle of it and its
  // barycentric coordinates there. Smooth quantities (the cell's scale) are solved on it and interpolated.
  TriMesh coarse;
  std::vector<std::pair<int, Vec3>> where;
  int components = 0;
  double edgeMean = 0;
  int thinnedFrom = 0, thinnedTo = 0;  // an upload thinned first (thinned()): its vertices, and those left; else 0
  int thinnedSplit = 1;                // ... at this many field-mesh edges, then split as many times (thinnedSplit())
  int vertexCount() const { return static_cast<int>(V.rows()); }
  Vec3 point(int v) const { return V.row(v).transpose(); }
};

// Samples `surface` with edges of about `edge` (an uploaded mesh split k x k, an analytic surface on its parameter
// lattice) and sets the frames: the Dupin metric bounded to `anisotropy`, regularized where |curvature| is small
// against the surface's typical curvature.
FieldMesh fieldMesh(const Surface& surface, double edge, double anisotropy, double curvatureFloor, const CancelFlag* cancel);

// One level of the multiresolution hierarchy the fields are smoothed on (level 0: the field mesh itself).
struct Level {
  std::vector<Vec3> x;
  std::vector<Frame> frame;
  std::vector<double> area, alignWeight, scale;  // scale: the cell's factor at this vertex (curvature sizing)
  std::vector<Vec3> target;      // the alignment target, a tangent direction in space (zero: none)
  std::vector<char> fixed;       // 1: the direction is fixed to `target` (boundary)
  std::vector<int> start, adjacent;
  std::vector<int> colorStart, colorOrder;  // vertices grouped by colour: no two neighbours share one
  std::vector<int> parent;       // #x: its vertex on the next coarser level (empty on the coarsest)
  int size() const { return static_cast<int>(x.size()); }
};
std::vector<Level> hierarchy(const FieldMesh& mesh, const std::vector<double>& scale, bool freeAlignedBoundary = true,
                             const std::vector<double>* holdTo = nullptr);

// Vertices per thread in the sweeps (each costs about a microsecond).
constexpr int kSweepGrain = 1024;

// `sweeps` Gauss-Seidel sweeps over level L, one colour after another, the vertices of a colour over threads (no two
// are neighbours, so the result does not depend on the thread count), two at a time: update2(a, b), and update(v)
// for one left over. Being no neighbours, two vertices' updates may run interleaved, each the same as alone: the
// processor then overlaps their chains of dependent arithmetic, which one vertex's update leaves it waiting on.
template <typename Update2, typename Update>
void sweepLevelInPairs(const Level& L, int sweeps, const Update2& update2, const Update& update) {
  for (int s = 0; s < sweeps; ++s)
    for (int c = 0; c + 1 < static_cast<int>(L.colorStart.size()); ++c) {
      const int begin = L.colorStart[c], end = L.colorStart[c + 1];
      parallelRanges(end - begin, kSweepGrain, [&](int b, int e) {
        int k = begin + b;
        for (; k + 1 < begin + e; k += 2) update2(L.colorOrder[k], L.colorOrder[k + 1]);
        if (k < begin + e) update(L.colorOrder[k]);
      });
    }
}
// The same with update(v) for every vertex in turn.
template <typename Update>
void sweepLevel(const Level& L, int sweeps, const Update& update) {
  sweepLevelInPairs(L, sweeps, [&](int a, int b) { update(a), update(b); }, update);
}
// Sets the cell's factor on level 0 and, area-weighted, on the coarser levels.
void setScale(std::vector<Level>& levels, const std::vector<double>& scale);

// The uniform split k of a mesh of median edge `median` into field-mesh edges of `edge` (at least 1; fieldMesh caps
// it further by the surface's area).
int fieldSplit(double median, double edge);
// How many vertices a mesh of equilateral triangles of edge `edge` has over `area`.
double verticesAt(double area, double edge);

// An upload remeshed for the field mesh (remesh.cpp): to about `edge` (thinned; `kept` gets, per vertex left, its id in
// `mesh` where it did not move, else -1), at thinnedSplit(own edge, field edge) field-mesh edges, and the points split
// off the remeshed `thin` into `fine` (`where`: each point's triangle of thin) kept from folding over (untangleSplit:
// false where some triangle stays turned against its corners' normals).
int thinnedSplit(double own, double edge);
TriMesh thinned(const Surface& surface, const TriMesh& mesh, double edge, std::vector<int>& kept, const CancelFlag* cancel);
bool untangleSplit(const MeshSurface& mesh, const TriMesh& thin, const TriMesh& fine,
                   const std::vector<std::pair<int, Vec3>>& where, const std::vector<int>& kept,
                   std::vector<LocalGeometry>& geo);

// The 6-fold field: per level (level 0 first) and vertex, a unit tangent direction in the Dupin frame (the five others are it
// turned by multiples of 60 degrees). Smoothed coarse to fine by Gauss-Seidel sweeps over colours.
std::vector<std::vector<Vec3>> orientationField(std::vector<Level>& levels, double alignment, const ProgressFn& progress,
                                   const CancelFlag* cancel);
// Of the six lattice directions of q (Dupin frame at `a`) carried to `b` along e = x_b - x_a (transport), the one
// nearest `reference` (Dupin frame at b); `turns` gets which (q turned by turns x 60 degrees at a).
Vec3 matchDirection(const Vec3& reference, const Frame& b, const Vec3& q, const Frame& a, const Vec3& e,
                    int* turns = nullptr);
// The index (in sixths of a turn) of the field around triangle (i, j, k) of the field mesh: 0 where it is regular.
int singularityIndex(const FieldMesh& mesh, const std::vector<Vec3>& q, int i, int j, int k);
// Whether the principal directions turn by a quarter turn or more around the field-mesh triangle (i, j, k): an
// umbilic of the surface (or where noise makes the curvature isotropic).
bool principalTurns(const FieldMesh& mesh, int i, int j, int k);

// Per vertex of the field mesh, the factor of the cell that makes the lattice along the field `q` integrable where
// it can be (scale.cpp): e^phi with grad phi = -J omega in least squares, omega the field's turn against parallel
// transport, `strength` in [0, 1] scaling omega (0: uniform cells). Normalized to the uniform cell's mean area.
// Up to `directLimit` vertices of the mesh it is solved on (the coarse mesh the field mesh refines) its normal
// equations are factorized; above, solved by conjugate gradients, preconditioned on aggregates of vertices. The
// factorization's fill grows faster than the iterations' work: at 3000 faces on uploads of the bumps of 10k, 15k,
// 20k, 30k and 40k vertices 58 / 113 / 177 / 318 / 466 ms factorized against 54 / 97 / 137 / 211 / 281 iterated, the
// generated genus 2 (49k) 1.09 s against 0.50 s (laid twice at 1000 faces). Below 12000 (every run of the sweeps, the
// bench's upload at 10k faces, the shared models) the factorized solve stands, as before.
constexpr int kDirectScale = 12000;
std::vector<double> integrableScale(const FieldMesh& mesh, const std::vector<Vec3>& q, double strength,
                                    int directLimit = kDirectScale);

// The lattice of one vertex of level L: edge vectors U and V = U turned by 60 degrees in the Dupin frame, of the cell
// times its scale there, and the inverse of their Gram matrix (for the coordinates of a point in that basis).
struct Lattice {
  Vec3 U, V;
  double i00 = 0, i01 = 0, i11 = 0;
};
inline Lattice latticeAt(const Level& L, const std::vector<Vec3>& Q, int v, double cell) {
  const Frame& f = L.frame[v];
  const double h = cell * L.scale[v];
  Lattice lat{h * f.fromDupin(Q[v]), h * f.fromDupin(rotate60(Q[v], f.n))};
  const double uu = dot(lat.U, lat.U), uv = dot(lat.U, lat.V), vv = dot(lat.V, lat.V), det = uu * vv - uv * uv;
  if (det > 0) lat.i00 = vv / det, lat.i01 = -uv / det, lat.i11 = uu / det;
  return lat;
}
// The lattice point (ba, bb) nearest lattice coordinates (a, b), by a^2 + ab + b^2 (the squared length of a U + b V in
// units of the edge): the first of the least of the four corners around them, in the order (a0, b0), (a0 + 1, b0),
// (a0, b0 + 1), (a0 + 1, b0 + 1), chosen by selects rather than branches (which corner wins is a coin toss for the
// branch predictor; the position field's sweeps call this for every neighbour).
[[gnu::always_inline]] inline void nearestCorner(double a, double b, double& ba, double& bb) {
  const double a0 = std::floor(a), b0 = std::floor(b);
  auto cost = [&](double ca, double cb) {
    const double ea = a - ca, eb = b - cb;
    return ea * ea + ea * eb + eb * eb;
  };
  const double a1 = a0 + 1, b1 = b0 + 1;
  const double c0 = cost(a0, b0), c1 = cost(a1, b0), c2 = cost(a0, b1), c3 = cost(a1, b1);
  const bool first = !(c1 < c0), third = !(c3 < c2);
  const double m01 = first ? c0 : c1, m23 = third ? c2 : c3;
  const bool low = !(m23 < m01);
  ba = low ? (first ? a0 : a1) : (third ? a0 : a1), bb = low ? b0 : b1;
}

// The position field: per vertex of level 0, the lattice point nearest to it (a point of its tangent plane) of
// the triangular lattice of edge cell * scale along the field's directions (Dupin frame).
std::vector<Vec3> positionField(std::vector<Level>& levels, std::vector<std::vector<Vec3>>& fields, double cell,
                                const ProgressFn& progress, const CancelFlag* cancel);

// The position field's dislocations cancelled (dislocations.cpp): returns how many cores were joined with another,
// or moved into a singular point; `left` gets those left.
int cancelDislocations(const FieldMesh& mesh, const Level& level, const std::vector<Vec3>& q, std::vector<Vec3>& o,
                       double cell, int* left, const CancelFlag* cancel);

// The lattice's points as a triangle mesh: sites from the position field, boundary sites along the boundary
// loops, connected as the dual of their Voronoi regions on the field mesh. Notes say what was done.
struct Extraction {
  TriMesh mesh;
  std::vector<int> seeds;  // #V: a field-mesh vertex next to each vertex (its field and cell there)
  std::vector<std::string> notes;
  int repairs = 0;  // sites added or removed until the regions' dual was a manifold of the surface's topology
};
Extraction extractTriangulation(const Surface& surface, const FieldMesh& mesh, const std::vector<Vec3>& o,
                                const std::vector<double>& scale, double cell, const CancelFlag* cancel);

// Fits the interior vertices of `T` (boundary vertices stay) to the field: every edge as near as it can be to the
// lattice vector it stands for (the field's direction nearest to it, of the cell's length at its ends), in least
// squares over the whole mesh, then back onto `surface`; `rounds` times (relax.cpp). The position field's
// jitter goes, rows follow the field's lines, and where the lattice must bend (a singular point, a dislocation)
// the bend spreads. Connectivity is unchanged.
void fitToField(TriMesh& T, const std::vector<int>& seeds, const Surface& surface, const FieldMesh& mesh,
                const std::vector<Vec3>& q, const std::vector<double>& scale, double cell, int rounds,
                const CancelFlag* cancel);

// Flips edges of `T` where that brings its vertices' valences nearer 6 (4 on the boundary) in sum of squares, and the
// two new triangles stay on the surface's side and are no slivers (the lattice's local mix-ups: a vertex of valence
// 8 ringed by 5s); then, with `glide`, inside the boundary, sequences of flips that glide dislocations (a 5 next to a
// 7) along their rows until two of opposite sense meet and cancel, or one meets a singular vertex (relax.cpp). Returns
// how many were flipped.
int improveValences(TriMesh& T, const Surface& surface, bool glide, const CancelFlag* cancel);


}  // namespace phex::global
