#include "phex/duality.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "phex/dupin.hpp"
#include "phex/error.hpp"

namespace phex {

VertexRings vertexRings(const TriMesh& mesh) {
  const int nv = static_cast<int>(mesh.V.rows()), nf = static_cast<int>(mesh.F.rows());
  // Directed edge a->b -> the triangle in which it appears (CCW). A second use means a non-manifold edge
  // or inconsistent orientation.
  std::unordered_map<long long, int> edgeTriangle;
  edgeTriangle.reserve(static_cast<std::size_t>(nf) * 3);
  auto key = [nv](int a, int b) { return static_cast<long long>(a) * nv + b; };
  std::vector<int> anyTriangle(nv, -1);
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = mesh.F(f, c), b = mesh.F(f, (c + 1) % 3);
      if (a < 0 || a >= nv || b < 0 || b >= nv || a == b)
        throw Error(ErrorCode::InvalidInput, "triangle " + std::to_string(f) + " has an invalid vertex index");
      if (!edgeTriangle.emplace(key(a, b), f).second)
        throw Error(ErrorCode::InvalidInput, "edge " + std::to_string(a) + "-" + std::to_string(b) +
                                                 " is non-manifold or inconsistently oriented");
      anyTriangle[a] = f;
    }
  auto corner = [&](int f, int v) {
    for (int c = 0; c < 3; ++c)
      if (mesh.F(f, c) == v) return c;
    return -1;
  };
  VertexRings rings;
  rings.triangles.resize(nv);
  rings.closed.assign(nv, false);
  for (int v = 0; v < nv; ++v) {
    if (anyTriangle[v] < 0) continue;
    // Walk clockwise to the first triangle of an open fan (or once around a closed one) ...
    int start = anyTriangle[v];
    for (int steps = 0;; ++steps) {
      const int c = corner(start, v);
      const int prev = mesh.F(start, (c + 1) % 3);  // the triangle before shares edge (prev -> v)
      auto it = edgeTriangle.find(key(prev, v));
      if (it == edgeTriangle.end()) break;
      if (it->second == anyTriangle[v] || steps > nf) { start = anyTriangle[v]; rings.closed[v] = true; break; }
      start = it->second;
    }
    // ... then counter-clockwise, collecting the fan.
    int f = start;
    for (int steps = 0; steps <= nf; ++steps) {
      rings.triangles[v].push_back(f);
      const int c = corner(f, v);
      const int next = mesh.F(f, (c + 2) % 3);  // the next triangle has the directed edge v -> next
      auto it = edgeTriangle.find(key(v, next));
      if (it == edgeTriangle.end() || it->second == start) break;
      f = it->second;
    }
  }
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

// A dual vertex must stay near its triangle: a far one means an ill-posed construction (§6 fallback).
bool plausible(const Vec3& x, const TriangleFrame& fr) {
  return x.allFinite() && (x - fr.centroid).norm() <= 0.75 * fr.longestEdge;
}

// The dual polygon mesh: one face per interior vertex, through the points of its incident triangles in
// CCW order. `U` holds the dual point of every triangle.
DualMesh assembleDual(const TriMesh& T, const Points& U, int fallbacks) {
  const int nv = static_cast<int>(T.V.rows()), nf = static_cast<int>(T.F.rows());
  DualMesh dual;
  dual.fallbackCount = fallbacks;
  const VertexRings rings = vertexRings(T);
  std::vector<int> newId(nf, -1);
  std::vector<int> ids;
  for (int v = 0; v < nv; ++v) {
    if (!rings.closed[v] || rings.triangles[v].size() < 3) continue;
    ids.clear();
    for (int f : rings.triangles[v]) {
      if (newId[f] < 0) {
        newId[f] = static_cast<int>(dual.vertexTriangle.size());
        dual.vertexTriangle.push_back(f);
      }
      ids.push_back(newId[f]);
    }
    dual.mesh.addFace(ids);
    dual.faceVertex.push_back(v);
  }
  dual.mesh.V.resize(static_cast<int>(dual.vertexTriangle.size()), 3);
  for (int i = 0; i < static_cast<int>(dual.vertexTriangle.size()); ++i) dual.mesh.V.row(i) = U.row(dual.vertexTriangle[i]);
  if (dual.mesh.faceCount() == 0)
    throw Error(ErrorCode::CannotTile, "the triangulation has no interior vertex, so its dual has no face");
  return dual;
}

}  // namespace

DualMesh dupinDual(const Triangulation& tri, const Surface& surface) {
  const TriMesh& T = tri.mesh;
  const int nf = static_cast<int>(T.F.rows());
  const std::vector<LocalGeometry> geo = vertexGeometry(tri, surface);
  Points U(nf, 3);
  int fallbacks = 0;
  for (int f = 0; f < nf; ++f) {
    const TriangleFrame fr = frameOf(geo, T, f);
    const LocalGeometry* g[3] = {&geo[T.F(f, 0)], &geo[T.F(f, 1)], &geo[T.F(f, 2)]};
    // §6 step 1: parabolic region detection, made scale-free with the triangle size.
    const double h2 = fr.longestEdge * fr.longestEdge;
    bool parabolic = false;
    for (int c = 0; c < 3; ++c) {
      const double K = g[c]->gaussianCurvature();
      parabolic |= std::abs(K) * h2 < 1e-8 || (K > 0) != (g[0]->gaussianCurvature() > 0);
    }
    Vec3 x = fr.centroid;
    if (!parabolic) {
      // §6 steps 2-3: one conic centre per vertex, averaged.
      // The conic of vertex c passes through c itself and the vertical projections of the other two.
      Vec3 sum = Vec3::Zero();
      bool ok = true;
      for (int c = 0; c < 3 && ok; ++c) {
        const std::optional<Vec3> center = dupinCenter(*g[c], g[c]->point, g[(c + 1) % 3]->point, g[(c + 2) % 3]->point);
        ok = center.has_value();
        if (ok) sum += *center;
      }
      if (ok && plausible(sum / 3.0, fr)) x = sum / 3.0;
      else parabolic = true;
    }
    fallbacks += parabolic;
    U.row(f) = x.transpose();
  }
  return assembleDual(T, U, fallbacks);
}

DualMesh tangentDual(const Triangulation& tri, const Surface& surface) {
  const TriMesh& T = tri.mesh;
  const int nf = static_cast<int>(T.F.rows());
  const std::vector<LocalGeometry> geo = vertexGeometry(tri, surface);
  Points U(nf, 3);
  int fallbacks = 0;
  for (int f = 0; f < nf; ++f) {
    const TriangleFrame fr = frameOf(geo, T, f);
    Eigen::Matrix3d A;
    Vec3 b;
    for (int c = 0; c < 3; ++c) {
      const LocalGeometry& g = geo[T.F(f, c)];
      A.row(c) = g.normal.transpose();
      b(c) = g.normal.dot(g.point);
    }
    // §4.1: the three tangent planes meet in one point; near-parallel planes make that point run off
    // (or not exist), and then §6's fallback, the centroid, is used.
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(A);
    Vec3 x = lu.isInvertible() ? Vec3(lu.solve(b)) : fr.centroid;
    if (!lu.isInvertible() || !plausible(x, fr)) {
      x = fr.centroid;
      ++fallbacks;
    }
    U.row(f) = x.transpose();
  }
  return assembleDual(T, U, fallbacks);
}

}  // namespace phex
