#include "phex/duality.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "phex/dupin.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/error.hpp"
#include "phex/metrics.hpp"
#include "phex/parallel.hpp"

namespace phex {

VertexRings vertexRings(const TriMesh& mesh) {
  const int nv = static_cast<int>(mesh.V.rows()), nf = static_cast<int>(mesh.F.rows());
  // Half-edge h = 3f + c runs from corner c of triangle f to corner c + 1 (CCW); F is row-major, so its start
  // is F.data()[h]. No hashing: the half-edges are bucketed by their start (CSR), and each vertex's star is
  // looked up in two scratch arrays indexed by the neighbour. The errors are those of reading the triangles
  // in order: the first half-edge with an invalid index, unless a directed edge used twice (a non-manifold
  // edge or an inconsistent orientation) is seen again before it.
  const int* F = mesh.F.data();
  auto next = [](int h) { return h % 3 == 2 ? h - 2 : h + 1; };
  auto prev = [](int h) { return h % 3 == 0 ? h + 2 : h - 1; };
  const int halfEdges = 3 * nf;
  int limit = halfEdges;  // the half-edges before the first invalid one
  for (int h = 0; h < halfEdges; ++h) {
    const int a = F[h], b = F[next(h)];
    if (a < 0 || a >= nv || b < 0 || b >= nv || a == b) {
      limit = h;
      break;
    }
  }
  const bool valid = limit == halfEdges;
  std::vector<int> first(nv + 1, 0);  // the half-edges from v are out[first[v] .. first[v + 1]), in order
  for (int h = 0; h < limit; ++h) ++first[F[h] + 1];
  for (int v = 0; v < nv; ++v) first[v + 1] += first[v];
  std::vector<int> out(limit);
  {
    std::vector<int> fill(first.begin(), first.end() - 1);
    for (int h = 0; h < limit; ++h) out[fill[F[h]]++] = h;
  }
  // For the vertex v at hand: outOf[b] is v's corner (3f + c) in the triangle with the directed edge v -> b,
  // inOf[a] its corner in the triangle with a -> v; -1 where there is none.
  std::vector<int> outOf(nv, -1), inOf(nv, -1);
  int repeated = limit, repeatedFrom = -1, repeatedTo = -1;  // the earliest second use of a directed edge
  VertexRings rings;
  rings.triangles.resize(nv);
  rings.closed.assign(nv, false);
  for (int v = 0; v < nv; ++v) {
    const int begin = first[v], end = first[v + 1];
    if (begin == end) continue;
    for (int k = begin; k < end; ++k) {
      const int h = out[k], b = F[next(h)];
      if (outOf[b] >= 0) {
        if (h < repeated) repeated = h, repeatedFrom = v, repeatedTo = b;
      } else {
        outOf[b] = h;
      }
      if (valid) inOf[F[prev(h)]] = h;
    }
    if (valid && repeatedFrom < 0) {
      const int any = out[end - 1];  // v's corner in the last triangle that has it
      // Walk clockwise to the first triangle of an open fan (or once around a closed one) ...
      int start = any;
      for (int steps = 0;; ++steps) {
        const int before = inOf[F[next(start)]];  // the triangle before shares edge (prev -> v)
        if (before < 0) break;
        if (before == any || steps > nf) { start = any; rings.closed[v] = true; break; }
        start = before;
      }
      // ... then counter-clockwise, collecting the fan.
      std::vector<int>& fan = rings.triangles[v];
      fan.reserve(end - begin);
      int h = start;
      for (int steps = 0; steps <= nf; ++steps) {
        fan.push_back(h / 3);
        const int after = outOf[F[prev(h)]];  // the next triangle has the directed edge v -> next
        if (after < 0 || after == start) break;
        h = after;
      }
    }
    for (int k = begin; k < end; ++k) {
      const int h = out[k];
      outOf[F[next(h)]] = -1;
      if (valid) inOf[F[prev(h)]] = -1;
    }
  }
  if (repeatedFrom >= 0)
    throw Error(ErrorCode::InvalidInput, "edge " + std::to_string(repeatedFrom) + "-" + std::to_string(repeatedTo) +
                                             " is non-manifold or inconsistently oriented");
  if (!valid) throw Error(ErrorCode::InvalidInput, "triangle " + std::to_string(limit / 3) + " has an invalid vertex index");
  return rings;
}

namespace {

struct TriangleFrame {
  Vec3 centroid = Vec3::Zero();
  double longestEdge = 0;
};

TriangleFrame frameOf(const std::vector<LocalGeometry>& geo, const TriMesh& T, int f) {
  TriangleFrame fr;
  for (int c = 0; c < 3; ++c) {
    fr.centroid += geo[T.F(f, c)].point / 3.0;
    fr.longestEdge = std::max(fr.longestEdge, (geo[T.F(f, c)].point - geo[T.F(f, (c + 1) % 3)].point).norm());
  }
  return fr;
}

// Singular values of the three tangent planes' normals below this fraction of the largest are left free
// (the point stays at the centroid's coordinate there) in a triangle at a parabolic curve.
constexpr double kStraddlingPlanes = 0.01;
// A triangle whose smallest |K| at a corner is below this fraction of its largest has that corner on a
// parabolic curve, for the dual point.
constexpr double kOnParabolic = 0.05;

// A dual vertex must stay near its triangle: a far one means an ill-posed construction (§6 fallback).
bool plausible(const Vec3& x, const TriangleFrame& fr) {
  return x.allFinite() && (x - fr.centroid).norm() <= 0.75 * fr.longestEdge;
}

// The point nearest to `start` that lies on all the given tangent planes, as far as they determine it: a
// minimum-norm least-squares correction, so directions the planes leave free (a developable's ruling, two
// nearly parallel planes) keep `start`'s coordinate instead of running off.
// Up to three planes: unused rows of `normals` are zero. Singular values below `threshold` times the largest
// count as zero.
Vec3 nearestOnPlanes(const Eigen::Matrix3d& normals, const Vec3& offsets, const Vec3& start, double threshold = 1e-9) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(normals, Eigen::ComputeFullU | Eigen::ComputeFullV);
  svd.setThreshold(threshold);
  return start + svd.solve(offsets - normals * start);
}

// Where the surface's boundary lies as seen from the midpoint of a boundary edge of the triangulation: the
// midpoint moved by the tangential part of the way to its closest point on the surface. On an edge along a
// boundary that bends away from the surface (the rim of a hole, a reflex corner) the edge is a chord across
// the hole and its midpoint lies off the surface; this is the rim beside it. Elsewhere the closest point
// lies along the normal (a chord of a curved surface) and the midpoint stays where it is.
Vec3 rimBeside(const Surface& surface, const Vec3& mid) {
  const LocalGeometry foot = surface.closestPoint(mid);
  const Vec3 away = foot.point - mid;
  return mid + away - away.dot(foot.normal) * foot.normal;
}

// §4.1: the three tangent planes at the triangle's corners meet in one point. Where they leave a direction
// free (a developable's ruling) the point nearest the centroid is taken; false where they are nearly parallel
// and the point runs off (then §6's fallback applies, and x is left as it was).
bool tangentPoint(const std::vector<LocalGeometry>& geo, const TriMesh& T, int f, const TriangleFrame& fr, Vec3& x,
                  double threshold = 1e-9) {
  Eigen::Matrix3d A;
  Vec3 b;
  for (int c = 0; c < 3; ++c) {
    const LocalGeometry& g = geo[T.F(f, c)];
    A.row(c) = g.normal.transpose();
    b(c) = g.normal.dot(g.point);
  }
  const Vec3 y = nearestOnPlanes(A, b, fr.centroid, threshold);
  if (!plausible(y, fr)) return false;
  x = y;
  return true;
}

// The dual polygon mesh (§4.1, §6 step 4): one face per vertex of the triangulation, through the dual points
// of its incident triangles in CCW order. A boundary vertex's open fan is closed into a proper polygon by the
// dual points of its two boundary edges — each on the line where the tangent planes at the edge's ends meet,
// nearest the edge's midpoint (or the rim beside it, rimBeside: a small hole's edges are chords across it, and
// on an uploaded hemisphere with a hole at its pole, two cells wide at 8000 faces, such a point lay 0.31 % of
// the diagonal off the surface, inside the hole), and shared with the neighbouring boundary face — and, where the boundary turns
// by more than 30 degrees, the vertex itself as the panel's corner. `U` holds the dual point of every
// triangle. Boundary faces lie in the vertex's tangent plane as interior ones do, so planarization treats
// them alike.
DualMesh assembleDual(const TriMesh& T, const VertexRings& rings, const Points& U, const std::vector<LocalGeometry>& geo,
                      const Surface& surface, int fallbacks) {
  const int nv = static_cast<int>(T.V.rows()), nf = static_cast<int>(T.F.rows());
  DualMesh dual;
  dual.fallbackCount = fallbacks;
  std::vector<int> triangleId(nf, -1);
  std::vector<Vec3> points;
  auto triangleVertex = [&](int f) {
    if (triangleId[f] < 0) {
      triangleId[f] = static_cast<int>(points.size());
      points.push_back(U.row(f).transpose());
      dual.vertexTriangle.push_back(f);
    }
    return triangleId[f];
  };
  // The point of each boundary edge, by the edge's one half-edge h = 3f + c (corner c to c + 1 of triangle f):
  // a boundary edge has no twin, so its two faces (one per end) name it alike. No hashing; filled on demand.
  std::vector<int> edgeId;
  auto edgeVertex = [&](int a, int b, int h) {
    if (edgeId.empty()) edgeId.assign(3 * static_cast<std::size_t>(nf), -1);
    const bool added = edgeId[h] < 0;
    if (added) {
      edgeId[h] = static_cast<int>(points.size());
      Eigen::Matrix3d N;
      N << geo[a].normal.transpose(), geo[b].normal.transpose(), Vec3::Zero().transpose();
      const Vec3 d(geo[a].normal.dot(geo[a].point), geo[b].normal.dot(geo[b].point), 0.0);
      const Vec3 mid = 0.5 * (geo[a].point + geo[b].point);
      Vec3 x = nearestOnPlanes(N, d, rimBeside(surface, mid));
      if (!x.allFinite() || (x - mid).norm() > 0.75 * (geo[a].point - geo[b].point).norm()) x = mid;
      points.push_back(x);
      dual.vertexTriangle.push_back(-1);
    }
    return edgeId[h];
  };
  auto corner = [&](int f, int v) {
    int k = 0;
    while (T.F(f, k) != v) ++k;
    return k;
  };
  std::vector<int> ids;
  for (int v = 0; v < nv; ++v) {
    const std::vector<int>& fan = rings.triangles[v];
    if (fan.empty() || (rings.closed[v] && fan.size() < 3)) continue;
    ids.clear();
    if (rings.closed[v]) {
      for (int f : fan) ids.push_back(triangleVertex(f));
    } else {
      const int kFirst = corner(fan.front(), v), kLast = (corner(fan.back(), v) + 2) % 3;
      const int first = T.F(fan.front(), (kFirst + 1) % 3);  // boundary edge v -> first (half-edge at kFirst)
      const int last = T.F(fan.back(), kLast);                // boundary edge v -> last (half-edge last -> v)
      ids.push_back(edgeVertex(v, first, 3 * fan.front() + kFirst));
      for (int f : fan) ids.push_back(triangleVertex(f));
      ids.push_back(edgeVertex(v, last, 3 * fan.back() + kLast));

      double fanAngle = 0;
      for (int f : fan) {
        const int k = corner(f, v);
        const Vec3 e1 = T.V.row(T.F(f, (k + 1) % 3)) - T.V.row(v), e2 = T.V.row(T.F(f, (k + 2) % 3)) - T.V.row(v);
        fanAngle += std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      }
      // The vertex as the panel's corner where the boundary turns sharply, unless the polygon would cross
      // itself with it (a lone skinny triangle at a sharp corner whose dual point lies outside it): then the
      // panel is cut off before it. Where it turns gently the vertex is a corner only if the panel crosses
      // itself without it: a dual point between the vertex and the chord of its two edge points (a short
      // fan whose triangle point fell next to the vertex).
      std::vector<Vec2> polygon;
      for (int id : ids) polygon.push_back(toTangentPlane(geo[v], points[id]));
      if (fanAngle < 150.0 * M_PI / 180.0 || polygonSelfIntersects(polygon)) {
        polygon.push_back(Vec2::Zero());
        if (!polygonSelfIntersects(polygon)) {
          ids.push_back(static_cast<int>(points.size()));
          points.push_back(geo[v].point);
          dual.vertexTriangle.push_back(-1);
        }
      }
    }
    dual.mesh.addFace(ids);
    dual.faceVertex.push_back(v);
    dual.boundaryFace.push_back(rings.closed[v] ? 0 : 1);
  }
  dual.mesh.V.resize(static_cast<int>(points.size()), 3);
  for (int i = 0; i < static_cast<int>(points.size()); ++i) dual.mesh.V.row(i) = points[i].transpose();
  if (dual.mesh.faceCount() == 0) throw Error(ErrorCode::CannotTile, "the triangulation has no vertex with a face around it");
  return dual;
}

}  // namespace

namespace {

// Interior faces of a Dupin dual that cross themselves: their stars straddle a parabolic curve, where no
// indicatrix judges the triangles (Props 4, 5 do not apply) and the points of neighbouring triangles are
// taken in different ways (a Dupin centre, the tangent planes' meeting point kept at the centroid along the
// zero-curvature direction). Each corner point of such a face tries the other placements of its triangle —
// the tangent planes' point with that direction kept or left free, and the centroid — and keeps the one
// under which fewest of the faces through it cross themselves, if fewer than now. Returns how many points
// moved.
int untangleDual(DualMesh& dual, const TriMesh& T, const std::vector<LocalGeometry>& geo) {
  PolyMesh& M = dual.mesh;
  const int nvd = static_cast<int>(M.V.rows()), nfd = M.faceCount();
  // Each point's faces, as compressed rows (a list per point took 10 ms a round at 100k faces).
  const FacesAtVertices at = facesAtVertices(M, [](int) { return true; });
  auto crossingAt = [&](int i) {
    int n = 0;
    for (int j = at.start[i]; j < at.start[i + 1]; ++j) n += faceSelfIntersects(M, at.faces[j]);
    return n;
  };
  // Which faces cross themselves as a sweep starts, over threads; in the sweep a face with a corner moved since is
  // measured again (so the sweep sees what measuring every face in turn would see). Between sweeps only the faces
  // with a corner the sweep moved are measured again: the others are as the sweep before found them.
  std::vector<char> touched(nvd, 0);
  std::vector<char> crossed = selfIntersectingFaces(M);
  int moved = 0;
  for (int sweep = 0; sweep < 4; ++sweep) {
    int changed = 0;
    if (sweep > 0)
      for (int f = 0; f < nfd; ++f)
        for (int k = 0; k < M.faceSize(f); ++k)
          if (touched[M.face(f)[k]]) {
            crossed[f] = faceSelfIntersects(M, f);
            break;
          }
    std::fill(touched.begin(), touched.end(), char(0));
    for (int f = 0; f < nfd; ++f) {
      if (dual.boundaryFace[f]) continue;
      bool dirty = false;
      for (int k = 0; k < M.faceSize(f) && !dirty; ++k) dirty = touched[M.face(f)[k]];
      if (!(dirty ? faceSelfIntersects(M, f) : crossed[f])) continue;
      for (int k = 0; k < M.faceSize(f); ++k) {
        const int i = M.face(f)[k], t = dual.vertexTriangle[i];
        if (t < 0) continue;
        const TriangleFrame fr = frameOf(geo, T, t);
        std::array<Vec3, 3> candidates;
        int n = 0;
        Vec3 x = fr.centroid;
        if (tangentPoint(geo, T, t, fr, x)) candidates[n++] = x;
        x = fr.centroid;
        if (tangentPoint(geo, T, t, fr, x, kStraddlingPlanes)) candidates[n++] = x;
        candidates[n++] = fr.centroid;
        const Vec3 now = M.V.row(i).transpose();
        int best = crossingAt(i);
        Vec3 bestPoint = now;
        for (int c = 0; c < n && best > 0; ++c) {
          M.V.row(i) = candidates[c].transpose();
          const int crossing = crossingAt(i);
          if (crossing < best) best = crossing, bestPoint = candidates[c];
        }
        M.V.row(i) = bestPoint.transpose();
        if (bestPoint != now) ++changed, touched[i] = 1;
        if (!faceSelfIntersects(M, f)) break;
      }
    }
    moved += changed;
    if (changed == 0) break;
  }
  return moved;
}

// A triangle on the boundary whose dual point lies beyond its boundary edge (a skinny one, or where the
// conjugate directions run slantwise to the boundary) would put a node off the surface, past its edge: the
// point is moved back across, onto the line of that edge in the triangle's plane. It leaves the triangle's
// tangent planes by as much, which the solve takes up. On the uploaded bumps at 3500 faces such a point lay
// 0.036 beyond the boundary and ended 1.1 % of the diagonal off the surface; moved back, 0.06 %. Where the
// edge is a chord across a hole (rimBeside), onto the parallel line through the rim beside it: on an uploaded
// saddle with an elliptic hole at 2000 faces, points moved back onto the chords at the hole's narrow end ended
// 0.31 % of the diagonal off the surface, 0.06 % now.
// With `alongRulings` (a developable's shared ruling planes, shareRulingPlanes) the point moves along the
// direction its three planes leave free, where that runs across the edge, so it stays on all three.
void keepWithinBoundary(const TriMesh& T, const VertexRings& rings, const std::vector<LocalGeometry>& geo, Points& U,
                        const Surface& surface, bool alongRulings = false) {
  auto pullBack = [&](int f, int a, int b) {  // boundary edge a -> b of triangle f
    int o = 0;
    while (T.F(f, o) == a || T.F(f, o) == b) ++o;
    const Vec3 pa = geo[a].point, pb = geo[b].point, po = geo[T.F(f, o)].point;
    const Vec3 along = pb - pa;
    if (!(along.norm() > 0)) return;
    const Vec3 e = along.normalized();
    Vec3 in = (po - pa) - e * e.dot(po - pa);  // across the edge, towards the third corner
    const double across = in.norm();
    // A triangle of no area has no side to be on: its `in` would be round-off, pointing anywhere (off the
    // surface too: a sloping plane's flat triangles sent points 7e-3 off it).
    if (!(across > 1e-9 * along.norm())) return;
    in /= across;
    const Vec3 x = U.row(f).transpose();
    const double rim = std::max(0.0, in.dot(rimBeside(surface, 0.5 * (pa + pb)) - 0.5 * (pa + pb)));
    const double depth = in.dot(x - pa) - rim;
    if (!(depth < 0)) return;
    if (alongRulings) {
      Eigen::Matrix3d N;
      N << geo[a].normal.transpose(), geo[b].normal.transpose(), geo[T.F(f, o)].normal.transpose();
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(N, Eigen::ComputeFullV);
      const Vec3 free = svd.matrixV().col(2);
      const double s = svd.singularValues()(2), slope = in.dot(free);
      if (s <= kStraddlingPlanes * svd.singularValues()(0) && std::abs(slope) >= 0.3) {
        U.row(f) = (x - (depth / slope) * free).transpose();
        return;
      }
    }
    U.row(f) = (x - depth * in).transpose();
  };
  const int nv = static_cast<int>(T.V.rows());
  for (int v = 0; v < nv; ++v) {
    const std::vector<int>& fan = rings.triangles[v];
    if (rings.closed[v] || fan.empty()) continue;
    // The open fan starts at the boundary edge v -> first, in its first triangle: every boundary edge is the
    // first of one fan, its start's.
    const int f = fan.front();
    int k = 0;
    while (T.F(f, k) != v) ++k;
    pullBack(f, v, T.F(f, (k + 1) % 3));
  }
}

// On a developable (§3, §5.3) the tangent plane is the same all along a ruling, so the hexagons of the
// vertices of one ruling lie in one plane, and each dual point of a strip between two rulings on the line
// where their planes meet: quad-shaped hexagons, planar by construction. The tangent planes a mesh's
// normals give differ a little along a ruling, and then the dual points scatter off those lines and the
// local solver crawls (the planes at a node nearly share a line). So where the triangulation's vertices are
// all but a few parabolic (kDevelopableRatio, kDevelopableShare), the vertices joined by edges
// along their zero-curvature direction (within about 10 degrees of it at one end, and off its line by at
// most a tenth of the mean edge) are grouped into rulings, and each group of two or more shares one plane:
// through their mean point, normal to their mean normal; the vertices move onto it. Returns how many groups
// share a plane. On an uploaded cylinder and cone laid by Method 2 every face comes out planar to round-off
// (0 solver iterations from 1000 to 10000 faces), where the local solver stalled at 1e-5 to 1e-3.
constexpr double kRulingCosine = 0.985;  // about 10 degrees
constexpr int kMergePasses = 64;
// A group's points off its shared plane, root mean square, at most this share of the mean edge: else the group is
// no ruling, and its vertices keep their own planes. On a lattice that runs near the rulings without following
// them (the global method's on a cone at 3000 faces) the edges along the zero-curvature direction chain into groups
// that wander across rulings, and the merges of neighbours meeting far off went on until all 2910 vertices shared
// one plane, their nodes up to 25 mean edges (21.7 % of the diagonal) off the cone. Groups along true rulings lie
// in their plane to round-off (Method 2 on the cylinder and cone), and a corrugated vault's merged neighbours about
// an inflection to a few thousandths of an edge.
constexpr double kSharedPlaneSpread = 0.02;
// The root mean square distance of `count` points (their sum and sum of p p^T) from the plane through their mean
// with normal `normal` (any length).
double spreadOffPlane(int count, const Vec3& sum, const Eigen::Matrix3d& squares, const Vec3& normal) {
  const double length = normal.norm();
  if (count < 2 || !(length > 0)) return 0.0;
  const Vec3 n = normal / length, mean = sum / count;
  const double meanSquare = n.dot(squares * n) / count - n.dot(mean) * n.dot(mean);
  return std::sqrt(std::max(0.0, meanSquare));
}
int shareRulingPlanes(const TriMesh& T, std::vector<LocalGeometry>& geo, bool rulingsEverywhere) {
  const int nv = static_cast<int>(geo.size());
  const double h = T.meanEdgeLength();
  const double curvedAbove = 1e-9 / h;  // below it, a planar point
  if (!samplesDevelopable(geo, curvedAbove)) return 0;
  auto zeroDirection = [](const LocalGeometry& g) { return std::abs(g.k1) < std::abs(g.k2) ? g.d1 : g.d2; };
  // The ruling direction at each vertex: its zero-curvature direction; at a planar point (on an inflection
  // ruling of a corrugated profile, both curvatures vanish and the principal directions are arbitrary) that
  // of its curved neighbours, which share the ruling's direction on a developable; none where it has none.
  // With `rulingsEverywhere` (an uploaded developable) planar points already carry the rulings around them
  // (MeshSurface), so that a flat apron's rows group too: else each of its vertices kept a plane of its own,
  // and the strips where they met the first tilted rows of the bend were left 5e-5 off planar.
  std::vector<Vec3> ruling(nv, Vec3::Zero());
  auto isCurved = [&](const LocalGeometry& g) {
    return rulingsEverywhere || g.largestCurvature() > curvedAbove;
  };
  for (int v = 0; v < nv; ++v)
    if (isCurved(geo[v])) ruling[v] = zeroDirection(geo[v]);
  std::vector<Vec3> borrowed(nv, Vec3::Zero());
  for (Eigen::Index f = 0; f < T.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = T.F(f, k), b = T.F(f, (k + 1) % 3);
      for (const auto& [to, from] : {std::pair{a, b}, std::pair{b, a}})
        if (!isCurved(geo[to]) && isCurved(geo[from])) {
          const Vec3& d = ruling[from];
          borrowed[to] += borrowed[to].dot(d) < 0 ? Vec3(-d) : d;
        }
    }
  for (int v = 0; v < nv; ++v)
    if (!isCurved(geo[v]) && borrowed[v].norm() > 0) ruling[v] = borrowed[v].normalized();
  std::vector<int> parent(nv);
  for (int v = 0; v < nv; ++v) parent[v] = v;
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (Eigen::Index f = 0; f < T.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = T.F(f, k), b = T.F(f, (k + 1) % 3);  // interior edges twice, boundary edges once
      // Along the ruling direction at one end at least (a boundary vertex's estimate may be off), and off
      // that line by a sliver of an edge only (two rulings' ends closer than an edge are two rows).
      const Vec3 e = geo[b].point - geo[a].point;
      const double length = e.norm();
      for (const int end : {a, b}) {
        const Vec3& d = ruling[end];
        if (length > 0 && d.norm() > 0 && std::abs(e.dot(d)) >= kRulingCosine * length && e.cross(d).norm() <= 0.1 * h) {
          parent[find(a)] = find(b);
          break;
        }
      }
    }
  std::vector<int> count(nv, 0);
  std::vector<Vec3> sumPoint(nv, Vec3::Zero()), sumNormal(nv, Vec3::Zero());
  std::vector<Eigen::Matrix3d> sumSquares(nv, Eigen::Matrix3d::Zero());  // sum of p p^T: the spread off a plane
  auto sumUp = [&]() {
    std::fill(count.begin(), count.end(), 0);
    std::fill(sumPoint.begin(), sumPoint.end(), Vec3::Zero());
    std::fill(sumNormal.begin(), sumNormal.end(), Vec3::Zero());
    std::fill(sumSquares.begin(), sumSquares.end(), Eigen::Matrix3d::Zero());
    for (int v = 0; v < nv; ++v) {
      const int r = find(v);
      ++count[r];
      sumPoint[r] += geo[v].point;
      sumSquares[r] += geo[v].point * geo[v].point.transpose();
      // Normals oriented alike (a mesh's are, but not necessarily to round-off at a fold).
      sumNormal[r] += geo[v].normal.dot(geo[r].normal) < 0 ? Vec3(-geo[v].normal) : geo[v].normal;
    }
  };
  sumUp();
  // Two neighbouring rulings about an inflection of the profile (a corrugated vault) have nearly parallel
  // planes that meet far off the surface: no point of their strip is on both near it, and its faces would
  // start off planar. Such neighbours share one plane (their faces are then not quite tangent, where the
  // surface is nearly flat). A corrugated height field stalled at 2e-7 to 9e-6 at 800, 1000, 1500 and 2000
  // faces; with the borrowed ruling directions above and this, 800, 1000 and 2000 are planar as laid.
  // Until no more merge: a merged group's plane is their mean, which may then meet a further neighbour's far
  // off (a vault on a flat apron: the apron's rows, exactly flat, against the first rows of the bend, merged
  // and tilted by 1e-4, left the strip between them 5e-5 off planar).
  // A merge adds the groups' sums at once, so that a chain of them (the apron's rows, one after another)
  // goes on within a pass; an edge whose two groups were found to meet near is looked at again only when
  // one of them has grown since (a 400 x 400 apron at 50k faces: the dual took 12 s in passes of every edge).
  struct Check {
    int ra = -1, rb = -1, va = 0, vb = 0;
  };
  std::vector<Check> checked(3 * static_cast<std::size_t>(T.F.rows()));
  std::vector<int> version(nv, 0);
  for (int pass = 0; pass < kMergePasses; ++pass) {
    bool merged = false;
    for (Eigen::Index f = 0; f < T.F.rows(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = T.F(f, k), b = T.F(f, (k + 1) % 3), ra = find(a), rb = find(b);
        if (ra == rb) continue;
        Check& last = checked[3 * f + k];
        if (last.ra == ra && last.rb == rb && last.va == version[ra] && last.vb == version[rb]) continue;
        Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
        N.row(0) = sumNormal[ra].normalized().transpose();
        N.row(1) = sumNormal[rb].normalized().transpose();
        const Vec3 d(N.row(0).dot(sumPoint[ra] / count[ra]), N.row(1).dot(sumPoint[rb] / count[rb]), 0.0);
        const Vec3 c = (geo[T.F(f, 0)].point + geo[T.F(f, 1)].point + geo[T.F(f, 2)].point) / 3;
        double longest = 0;
        for (int i = 0; i < 3; ++i) longest = std::max(longest, (geo[T.F(f, i)].point - geo[T.F(f, (i + 1) % 3)].point).norm());
        const Vec3 mergedNormal = sumNormal[rb] + (sumNormal[ra].dot(sumNormal[rb]) < 0 ? Vec3(-sumNormal[ra]) : sumNormal[ra]);
        if ((nearestOnPlanes(N, d, c) - c).norm() > 0.75 * longest &&
            spreadOffPlane(count[ra] + count[rb], sumPoint[ra] + sumPoint[rb], sumSquares[ra] + sumSquares[rb],
                           mergedNormal) <= kSharedPlaneSpread * h) {
          parent[ra] = rb;
          count[rb] += count[ra];
          sumPoint[rb] += sumPoint[ra];
          sumSquares[rb] += sumSquares[ra];
          sumNormal[rb] = mergedNormal;
          ++version[rb];
          merged = true;
        } else {
          last = {ra, rb, version[ra], version[rb]};
        }
      }
    if (!merged) break;
  }
  sumUp();
  int shared = 0;
  for (int v = 0; v < nv; ++v) {
    const int r = find(v);
    if (count[r] < 2 || !(sumNormal[r].norm() > 0)) continue;
    if (spreadOffPlane(count[r], sumPoint[r], sumSquares[r], sumNormal[r]) > kSharedPlaneSpread * h) continue;
    shared += r == v;
    Vec3 n = sumNormal[r].normalized();
    if (n.dot(geo[v].normal) < 0) n = -n;
    const Vec3 c = sumPoint[r] / count[r];
    geo[v].normal = n;
    geo[v].point -= n.dot(geo[v].point - c) * n;  // onto the shared plane
  }
  return shared;
}

// The dual mesh with every triangle's point placed by `place(f, frame, x)`, which returns false where it fell
// back to the centroid (x is then the centroid).
template <typename Place>
DualMesh dualWith(const Triangulation& tri, const Surface& surface, Place place, bool untangle = false,
                  GeometryCache* cache = nullptr) {
  const TriMesh& T = tri.mesh;
  const int nf = static_cast<int>(T.F.rows());
  std::vector<LocalGeometry> geo = vertexGeometry(tri, surface, cache);
  const auto* mesh = dynamic_cast<const MeshSurface*>(&surface);
  const bool rulings = shareRulingPlanes(T, geo, mesh && mesh->developable()) > 0;
  const VertexRings rings = vertexRings(T);
  Points U(nf, 3);
  std::vector<char> fellBack(nf, 0);  // each triangle on its own, over threads
  parallelRanges(nf, kPointsPerThread, [&](int begin, int end) {
    for (int f = begin; f < end; ++f) {
      const TriangleFrame fr = frameOf(geo, T, f);
      Vec3 x = fr.centroid;
      fellBack[f] = !place(geo, f, fr, x);
      U.row(f) = x.transpose();
    }
  });
  const int fallbacks = static_cast<int>(std::count(fellBack.begin(), fellBack.end(), char(1)));
  keepWithinBoundary(T, rings, geo, U, surface, rulings);
  DualMesh dual = assembleDual(T, rings, U, geo, surface, fallbacks);
  if (untangle) dual.untangled = untangleDual(dual, T, geo);
  return dual;
}

}  // namespace

DualMesh dupinDual(const Triangulation& tri, const Surface& surface, bool untangle, GeometryCache* cache) {
  const TriMesh& T = tri.mesh;
  return dualWith(tri, surface, [&](const std::vector<LocalGeometry>& geo, int f, const TriangleFrame& fr, Vec3& x) {
    const LocalGeometry* g[3] = {&geo[T.F(f, 0)], &geo[T.F(f, 1)], &geo[T.F(f, 2)]};
    // §6 step 1: parabolic region detection, made scale-free with the triangle size.
    const double h2 = fr.longestEdge * fr.longestEdge;
    bool parabolic = false, straddles = false;
    const double K0 = g[0]->gaussianCurvature();
    double smallestK = std::abs(K0), largestK = std::abs(K0);
    for (int c = 0; c < 3; ++c) {
      const double K = g[c]->gaussianCurvature();
      parabolic |= std::abs(K) * h2 < 1e-8 || (K > 0) != (K0 > 0);
      straddles |= (K > 0) != (K0 > 0);
      smallestK = std::min(smallestK, std::abs(K));
      largestK = std::max(largestK, std::abs(K));
    }
    // A triangle across a parabolic curve, or with a corner on it (|K| there under kOnParabolic of its
    // largest): its tangent planes nearly share the zero-curvature direction, so where they meet is
    // ill-determined along it, and a Dupin conic through a corner on the curve is nearly two parallel lines
    // whose centre runs off along it. The point taken keeps the centroid's coordinate along the direction
    // the planes determine weakly (singular values under kStraddlingPlanes of the largest: the
    // zero-curvature one) and lies on the planes otherwise, so the faces there stay bricks with their long
    // sides along it (see the laying's base family). The far intersection, the bare centroid or a far Dupin
    // centre, mixed between neighbours, folded them or left them unplanar. At 0.1 the other tangent
    // direction was dropped too at fine cells: the torus took 11 Gauss-Newton sweeps instead of 9, Ceres
    // 18 instead of 9. Not on a developable or a plane (K = 0 at every corner).
    if (largestK * h2 >= 1e-8 && (straddles || smallestK < kOnParabolic * largestK))
      return tangentPoint(geo, T, f, fr, x, kStraddlingPlanes);
    if (!parabolic) {
      // §6 steps 2-3: one conic centre per vertex, averaged. The conic of vertex c passes through c itself
      // and the vertical projections of the other two.
      Vec3 sum = Vec3::Zero();
      bool ok = true;
      for (int c = 0; c < 3 && ok; ++c) {
        const std::optional<Vec3> center = dupinCenter(*g[c], g[c]->point, g[(c + 1) % 3]->point, g[(c + 2) % 3]->point);
        ok = center.has_value();
        if (ok) sum += *center;
      }
      if (ok && plausible(sum / 3.0, fr)) {
        x = sum / 3.0;
        return true;
      }
    }
    // Where the Dupin conic is undefined the tangent planes may still meet well; §6's centroid is the last resort.
    // On a developable (K = 0 at every corner, curved) two corners on one ruling share their tangent plane, up
    // to the estimate on an uploaded mesh: the point goes on the line where it meets the third corner's,
    // nearest the centroid, the ruling direction left free (kStraddlingPlanes) as at a parabolic curve.
    if (parabolic && !straddles && largestK * h2 < 1e-8) {
      double kmax = 0;
      for (int c = 0; c < 3; ++c) kmax = std::max({kmax, std::abs(g[c]->k1), std::abs(g[c]->k2)});
      if (kmax * fr.longestEdge > 1e-6) return tangentPoint(geo, T, f, fr, x, kStraddlingPlanes);
    }
    return tangentPoint(geo, T, f, fr, x);
  }, untangle, cache);
}

DualMesh tangentDual(const Triangulation& tri, const Surface& surface) {
  return dualWith(tri, surface, [&](const std::vector<LocalGeometry>& geo, int f, const TriangleFrame& fr, Vec3& x) {
    return tangentPoint(geo, tri.mesh, f, fr, x);
  });
}

}  // namespace phex
