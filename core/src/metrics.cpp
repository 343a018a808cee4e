#include "phex/metrics.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace phex {
namespace {

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

bool onSegment(const Vec2& p, const Vec2& q, const Vec2& x) {
  return std::min(p.x(), q.x()) <= x.x() && x.x() <= std::max(p.x(), q.x()) && std::min(p.y(), q.y()) <= x.y() &&
         x.y() <= std::max(p.y(), q.y());
}

// Segments pq and rs cross or touch.
bool segmentsCross(const Vec2& p, const Vec2& q, const Vec2& r, const Vec2& s) {
  auto sgn = [](double x) { return (x > 0) - (x < 0); };
  const int s1 = sgn(cross2(q - p, r - p)), s2 = sgn(cross2(q - p, s - p));
  const int s3 = sgn(cross2(s - r, p - r)), s4 = sgn(cross2(s - r, q - r));
  if (s1 * s2 < 0 && s3 * s4 < 0) return true;
  return (s1 == 0 && onSegment(p, q, r)) || (s2 == 0 && onSegment(p, q, s)) || (s3 == 0 && onSegment(r, s, p)) ||
         (s4 == 0 && onSegment(r, s, q));
}

}  // namespace

FacePlane leastSquaresPlane(const PolyMesh& mesh, int face) {
  const int n = mesh.faceSize(face);
  const int* ids = mesh.face(face);
  Vec3 c = Vec3::Zero();
  for (int i = 0; i < n; ++i) c += mesh.vertex(ids[i]);
  c /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Vec3 d = mesh.vertex(ids[i]) - c;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  return {c, es.eigenvectors().col(0)};
}

double facePlanarity(const PolyMesh& mesh, int face) {
  const int n = mesh.faceSize(face);
  if (n <= 3) return 0.0;
  const int* ids = mesh.face(face);
  const FacePlane pl = leastSquaresPlane(mesh, face);
  double maxDist = 0, edges = 0;
  for (int i = 0; i < n; ++i) {
    maxDist = std::max(maxDist, std::abs(pl.normal.dot(mesh.vertex(ids[i]) - pl.centroid)));
    edges += (mesh.vertex(ids[i]) - mesh.vertex(ids[(i + 1) % n])).norm();
  }
  return edges > 0 ? maxDist / (edges / n) : 0.0;
}

bool polygonSelfIntersects(const std::vector<Vec2>& p) {
  const int n = static_cast<int>(p.size());
  double scale = 0;
  for (const Vec2& q : p) scale = std::max(scale, q.norm());
  for (int i = 0; i < n; ++i)
    if ((p[i] - p[(i + 1) % n]).norm() <= 1e-12 * scale) return true;  // degenerate edge
  for (int i = 0; i < n; ++i)
    for (int k = i + 2; k < n; ++k) {
      if (i == 0 && k == n - 1) continue;  // adjacent through the wrap
      if (segmentsCross(p[i], p[(i + 1) % n], p[k], p[(k + 1) % n])) return true;
    }
  return false;
}

bool faceSelfIntersects(const PolyMesh& mesh, int face) {
  const int n = mesh.faceSize(face);
  const int* ids = mesh.face(face);
  const FacePlane pl = leastSquaresPlane(mesh, face);
  const Vec3 ex = (std::abs(pl.normal.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(pl.normal).normalized();
  const Vec3 ey = pl.normal.cross(ex);
  std::vector<Vec2> p(n);
  for (int i = 0; i < n; ++i) {
    const Vec3 d = mesh.vertex(ids[i]) - pl.centroid;
    p[i] = Vec2(d.dot(ex), d.dot(ey));
  }
  return polygonSelfIntersects(p);
}

MeshMetrics measure(const PolyMesh& mesh) {
  MeshMetrics m;
  m.vertexCount = static_cast<int>(mesh.V.rows());
  m.faceCount = mesh.faceCount();
  m.planarity.resize(m.faceCount);
  m.selfIntersecting.resize(m.faceCount);
  double sum = 0;
  for (int f = 0; f < m.faceCount; ++f) {
    m.planarity[f] = facePlanarity(mesh, f);
    m.selfIntersecting[f] = faceSelfIntersects(mesh, f) ? 1 : 0;
    m.facesBySize[mesh.faceSize(f)]++;
    m.planarityMax = std::max(m.planarityMax, m.planarity[f]);
    sum += m.planarity[f];
    m.selfIntersectingCount += m.selfIntersecting[f];
  }
  m.planarityMean = m.faceCount ? sum / m.faceCount : 0.0;
  return m;
}

MeshMetrics measure(const PolyMesh& mesh, const Surface& surface) {
  MeshMetrics m = measure(mesh);
  const double diagonal = surface.bounds().diagonal().norm();
  m.surfaceDistance.resize(m.vertexCount);
  double sum = 0;
  for (int v = 0; v < m.vertexCount; ++v) {
    const Vec3 p = mesh.vertex(v);
    m.surfaceDistance[v] = (surface.closestPoint(p).point - p).norm() / diagonal;
    m.surfaceDistanceMax = std::max(m.surfaceDistanceMax, m.surfaceDistance[v]);
    sum += m.surfaceDistance[v];
  }
  m.surfaceDistanceMean = m.vertexCount ? sum / m.vertexCount : 0.0;
  return m;
}

}  // namespace phex
