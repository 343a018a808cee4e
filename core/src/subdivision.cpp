// phex — Loop subdivision and the §7 route for closed convex genus-0 surfaces.
#include "phex/subdivision.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "phex/duality.hpp"
#include "phex/error.hpp"
#include "phex/mesh_io.hpp"

namespace phex {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Edges of a manifold triangle mesh and, per vertex, what the Loop masks need.
struct EdgeTopology {
  // Edge -> its vertices (a, b) and the opposite vertices c, d of its triangles (a, b, c) and (b, a, d)
  // (d = -1 on the boundary); (a, b) runs as in the edge's first triangle.
  std::vector<std::array<int, 2>> ends;
  std::vector<std::array<int, 2>> opposite;
  std::vector<std::array<int, 3>> faceEdge;  // face f, corner k -> edge F(f, k) F(f, k + 1)
  std::vector<int> valence;                  // vertex -> number of edges
  std::vector<Vec3> neighbourSum;            // vertex -> sum of its neighbours
  std::vector<int> boundaryEdges;            // vertex -> number of boundary edges (0 or 2 on a manifold)
  std::vector<Vec3> boundaryNeighbourSum;    // vertex -> sum of its neighbours along the boundary

  int edgeCount() const { return static_cast<int>(ends.size()); }
  bool isBoundaryEdge(int e) const { return opposite[e][1] < 0; }
};

std::string edgeName(int a, int b) { return std::to_string(a) + "-" + std::to_string(b); }

// Throws Error(InvalidInput) naming the first defect that Loop's rules cannot handle.
EdgeTopology buildTopology(const TriMesh& mesh) {
  const int nv = static_cast<int>(mesh.V.rows()), nf = static_cast<int>(mesh.F.rows());
  for (int v = 0; v < nv; ++v)
    if (!mesh.V.row(v).allFinite())
      throw Error(ErrorCode::InvalidInput, "vertex " + std::to_string(v) + " has a non-finite coordinate");
  // Half-edges sorted by their undirected edge (then by corner, so the result is deterministic).
  std::vector<std::pair<long long, int>> halfEdges;
  halfEdges.reserve(static_cast<std::size_t>(nf) * 3);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.F(f, k), b = mesh.F(f, (k + 1) % 3);
      if (a < 0 || a >= nv || b < 0 || b >= nv)
        throw Error(ErrorCode::InvalidInput, "triangle " + std::to_string(f) + " has a vertex index out of range");
      if (a == b) throw Error(ErrorCode::InvalidInput, "triangle " + std::to_string(f) + " repeats vertex " + std::to_string(a));
      halfEdges.emplace_back(static_cast<long long>(std::min(a, b)) * nv + std::max(a, b), f * 3 + k);
    }
  std::sort(halfEdges.begin(), halfEdges.end());

  EdgeTopology t;
  t.faceEdge.resize(nf);
  t.valence.assign(nv, 0);
  t.neighbourSum.assign(nv, Vec3::Zero());
  t.boundaryEdges.assign(nv, 0);
  t.boundaryNeighbourSum.assign(nv, Vec3::Zero());
  for (std::size_t i = 0; i < halfEdges.size();) {
    std::size_t j = i;
    while (j < halfEdges.size() && halfEdges[j].first == halfEdges[i].first) ++j;
    const int f0 = halfEdges[i].second / 3, k0 = halfEdges[i].second % 3;
    const int a = mesh.F(f0, k0), b = mesh.F(f0, (k0 + 1) % 3);
    if (j - i > 2)
      throw Error(ErrorCode::InvalidInput, "edge " + edgeName(a, b) + " is used by " + std::to_string(j - i) +
                                               " triangles (non-manifold)");
    const int e = t.edgeCount();
    std::array<int, 2> opposite = {mesh.F(f0, (k0 + 2) % 3), -1};
    t.faceEdge[f0][k0] = e;
    if (j - i == 2) {
      const int f1 = halfEdges[i + 1].second / 3, k1 = halfEdges[i + 1].second % 3;
      if (mesh.F(f1, k1) == a)
        throw Error(ErrorCode::InvalidInput, "edge " + edgeName(a, b) + " is used twice in the same direction "
                                                 "(triangles " + std::to_string(f0) + " and " + std::to_string(f1) +
                                                 " are inconsistently oriented)");
      opposite[1] = mesh.F(f1, (k1 + 2) % 3);
      t.faceEdge[f1][k1] = e;
    }
    t.ends.push_back({a, b});
    t.opposite.push_back(opposite);
    const Vec3 pa = mesh.V.row(a).transpose(), pb = mesh.V.row(b).transpose();
    ++t.valence[a];
    ++t.valence[b];
    t.neighbourSum[a] += pb;
    t.neighbourSum[b] += pa;
    if (opposite[1] < 0) {
      ++t.boundaryEdges[a];
      ++t.boundaryEdges[b];
      t.boundaryNeighbourSum[a] += pb;
      t.boundaryNeighbourSum[b] += pa;
    }
    i = j;
  }
  for (int v = 0; v < nv; ++v)
    if (t.boundaryEdges[v] != 0 && t.boundaryEdges[v] != 2)
      throw Error(ErrorCode::InvalidInput, "vertex " + std::to_string(v) + " lies on " +
                                               std::to_string(t.boundaryEdges[v]) +
                                               " boundary edges (boundary curves meet there)");
  return t;
}

// Loop's original weight of each neighbour of an interior vertex of valence n.
double loopBeta(int n) {
  const double c = 3.0 / 8.0 + 0.25 * std::cos(2.0 * kPi / n);
  return (5.0 / 8.0 - c * c) / n;
}

// Throws Error(InvalidParameter) for levels < 0 or when `levels` subdivisions of `triangles` exceed
// kMaxSubdivisionTriangles; `what` names the level count in the message.
void checkSubdivisionSize(std::size_t triangles, int levels, const char* what) {
  if (levels < 0) throw Error(ErrorCode::InvalidParameter, std::string(what) + " must be >= 0, got " + std::to_string(levels));
  std::size_t count = triangles;
  for (int l = 0; l < levels; ++l) {
    count *= 4;
    if (count > kMaxSubdivisionTriangles)
      throw Error(ErrorCode::InvalidParameter,
                  std::string(what) + " = " + std::to_string(levels) + " would subdivide the " +
                      std::to_string(triangles) + " control triangles into more than " +
                      std::to_string(kMaxSubdivisionTriangles) + " triangles (the memory limit)");
  }
}

TriMesh subdivideOnce(const TriMesh& mesh) {
  const EdgeTopology t = buildTopology(mesh);
  const int nv = static_cast<int>(mesh.V.rows()), nf = static_cast<int>(mesh.F.rows()), ne = t.edgeCount();
  TriMesh out;
  out.V.resize(nv + ne, 3);
  for (int v = 0; v < nv; ++v) {
    const Vec3 p = mesh.V.row(v).transpose();
    const int n = t.valence[v];
    Vec3 q = p;
    if (t.boundaryEdges[v] == 2)
      q = 0.75 * p + 0.125 * t.boundaryNeighbourSum[v];
    else if (n > 0)
      q = (1.0 - n * loopBeta(n)) * p + loopBeta(n) * t.neighbourSum[v];
    out.V.row(v) = q.transpose();
  }
  for (int e = 0; e < ne; ++e) {
    const Vec3 a = mesh.V.row(t.ends[e][0]).transpose(), b = mesh.V.row(t.ends[e][1]).transpose();
    Vec3 q = 0.5 * (a + b);
    if (!t.isBoundaryEdge(e))
      q = 0.375 * (a + b) + 0.125 * (mesh.V.row(t.opposite[e][0]).transpose() + mesh.V.row(t.opposite[e][1]).transpose());
    out.V.row(nv + e) = q.transpose();
  }
  out.F.resize(4 * nf, 3);
  for (int f = 0; f < nf; ++f) {
    // m_k is the new vertex on edge F(f, k) F(f, k + 1).
    const int m0 = nv + t.faceEdge[f][0], m1 = nv + t.faceEdge[f][1], m2 = nv + t.faceEdge[f][2];
    out.F.row(4 * f + 0) << mesh.F(f, 0), m0, m2;
    out.F.row(4 * f + 1) << mesh.F(f, 1), m1, m0;
    out.F.row(4 * f + 2) << mesh.F(f, 2), m2, m1;
    out.F.row(4 * f + 3) << m0, m1, m2;
  }
  return out;
}

double meanEdgeLength(const TriMesh& mesh, const EdgeTopology& t) {
  double sum = 0;
  for (const auto& e : t.ends) sum += (mesh.V.row(e[0]) - mesh.V.row(e[1])).norm();
  return sum / std::max(1, t.edgeCount());
}

// Edges whose dihedral angle, measured inside a mesh with outward CCW faces, exceeds 180 degrees by more
// than round-off: (edge, interior angle in degrees).
std::vector<std::pair<int, double>> reflexEdges(const TriMesh& mesh, const EdgeTopology& t) {
  const double meanEdge = meanEdgeLength(mesh, t);
  std::vector<std::pair<int, double>> reflex;
  for (int e = 0; e < t.edgeCount(); ++e) {
    if (t.isBoundaryEdge(e)) continue;
    const Vec3 a = mesh.V.row(t.ends[e][0]).transpose(), b = mesh.V.row(t.ends[e][1]).transpose();
    const Vec3 c = mesh.V.row(t.opposite[e][0]).transpose(), d = mesh.V.row(t.opposite[e][1]).transpose();
    // Outward normals of the triangles (a, b, c) and (b, a, d): the edge is reflex when either opposite
    // vertex lies above the other triangle's plane.
    const Vec3 n = (b - a).cross(c - a).normalized(), m = (a - b).cross(d - b).normalized();
    if (n.dot(d - a) > 1e-9 * meanEdge || m.dot(c - b) > 1e-9 * meanEdge) {
      const double between = std::acos(std::clamp(n.dot(m), -1.0, 1.0)) * 180.0 / kPi;
      reflex.emplace_back(e, 180.0 + between);
    }
  }
  return reflex;
}

}  // namespace

TriMesh loopSubdivide(const TriMesh& control, int levels) {
  checkSubdivisionSize(static_cast<std::size_t>(control.F.rows()), levels, "levels");
  TriMesh mesh = control;
  for (int l = 0; l < levels; ++l) mesh = subdivideOnce(mesh);
  if (levels == 0) buildTopology(mesh);  // the same checks as for levels > 0
  return mesh;
}

TriMesh loopLimitPositions(const TriMesh& mesh) {
  const EdgeTopology t = buildTopology(mesh);
  TriMesh out = mesh;
  for (int v = 0; v < mesh.V.rows(); ++v) {
    const Vec3 p = mesh.V.row(v).transpose();
    const int n = t.valence[v];
    if (t.boundaryEdges[v] == 2) {
      out.V.row(v) = (2.0 / 3.0 * p + t.boundaryNeighbourSum[v] / 6.0).transpose();
    } else if (n > 0) {
      const double chi = 1.0 / (n + 3.0 / (8.0 * loopBeta(n)));
      out.V.row(v) = ((1.0 - n * chi) * p + chi * t.neighbourSum[v]).transpose();
    }
  }
  return out;
}

Points loopLimitNormals(const TriMesh& mesh) {
  buildTopology(mesh);
  const VertexRings rings = vertexRings(mesh);
  Points normals = Points::Zero(mesh.V.rows(), 3);
  for (int v = 0; v < mesh.V.rows(); ++v) {
    const std::vector<int>& ring = rings.triangles[v];
    if (ring.empty()) continue;
    if (!rings.closed[v])
      throw Error(ErrorCode::InvalidInput, "vertex " + std::to_string(v) +
                                               " is on the boundary: limit normals need a closed mesh");
    const int n = static_cast<int>(ring.size());
    Vec3 t1 = Vec3::Zero(), t2 = Vec3::Zero();
    for (int i = 0; i < n; ++i) {
      const int f = ring[i];
      int k = 0;
      while (mesh.F(f, k) != v) ++k;
      // Going CCW around v, triangle i's vertex after v is the i-th neighbour.
      const Vec3 p = mesh.V.row(mesh.F(f, (k + 1) % 3)).transpose();
      t1 += std::cos(2.0 * kPi * i / n) * p;
      t2 += std::sin(2.0 * kPi * i / n) * p;
    }
    normals.row(v) = t1.cross(t2).normalized().transpose();
  }
  return normals;
}

TriMesh icosahedronControl(double radius) {
  if (!(radius > 0) || !std::isfinite(radius))
    throw Error(ErrorCode::InvalidParameter, "icosahedron radius must be positive and finite");
  // A vertex at each pole and two rings of five at heights +-1/sqrt(5), the lower ring turned by 36 degrees.
  TriMesh m;
  m.V.resize(12, 3);
  const double z = 1.0 / std::sqrt(5.0), r = 2.0 / std::sqrt(5.0);
  m.V.row(0) << 0, 0, 1;
  m.V.row(11) << 0, 0, -1;
  for (int i = 0; i < 5; ++i) {
    m.V.row(1 + i) << r * std::cos(2 * kPi * i / 5), r * std::sin(2 * kPi * i / 5), z;
    m.V.row(6 + i) << r * std::cos(2 * kPi * (i + 0.5) / 5), r * std::sin(2 * kPi * (i + 0.5) / 5), -z;
  }
  m.V *= radius;
  m.F.resize(20, 3);
  for (int i = 0; i < 5; ++i) {
    const int u0 = 1 + i, u1 = 1 + (i + 1) % 5, l0 = 6 + i, l1 = 6 + (i + 1) % 5;
    m.F.row(i) << 0, u0, u1;            // upper cap
    m.F.row(5 + i) << u0, l0, u1;       // band, pointing down
    m.F.row(10 + i) << u1, l0, l1;      // band, pointing up
    m.F.row(15 + i) << 11, l1, l0;      // lower cap
  }
  return m;
}

TriMesh stretchedIcosahedronControl(const Vec3& semiAxes) {
  if (!(semiAxes.array() > 0).all() || !semiAxes.allFinite())
    throw Error(ErrorCode::InvalidParameter, "stretched icosahedron semi-axes must be positive and finite");
  TriMesh m = icosahedronControl(1.0);
  m.V = m.V * semiAxes.asDiagonal();
  return m;
}

TriMesh eggControl(double top, double bottom) {
  if (!(top > 0) || !(bottom > 0) || !std::isfinite(top) || !std::isfinite(bottom))
    throw Error(ErrorCode::InvalidParameter, "egg control stretches must be positive and finite");
  TriMesh m = icosahedronControl(1.0);
  for (int v = 0; v < m.V.rows(); ++v) m.V(v, 2) *= m.V(v, 2) > 0 ? top : bottom;
  return m;
}

TriMesh checkConvexControl(const TriMesh& control) {
  const TriMesh mesh = cleanTriMesh(control, "control mesh");
  const EdgeTopology t = buildTopology(mesh);
  const int nv = static_cast<int>(mesh.V.rows()), nf = static_cast<int>(mesh.F.rows()), ne = t.edgeCount();

  // Connected components by union-find over the edges.
  std::vector<int> root(nv);
  std::iota(root.begin(), root.end(), 0);
  auto find = [&](int v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  int components = nv;
  for (const auto& e : t.ends) {
    const int a = find(e[0]), b = find(e[1]);
    if (a != b) root[a] = b, --components;
  }
  if (components != 1)
    throw Error(ErrorCode::CannotTile, "control mesh has " + std::to_string(components) +
                                           " connected components; the §7 subdivision route needs one closed "
                                           "convex surface");

  int boundary = 0, firstBoundary = -1;
  for (int e = 0; e < ne; ++e)
    if (t.isBoundaryEdge(e)) {
      if (firstBoundary < 0) firstBoundary = e;
      ++boundary;
    }
  if (boundary > 0)
    throw Error(ErrorCode::CannotTile, "control mesh is not closed: " + std::to_string(boundary) +
                                           " boundary edges, e.g. edge " +
                                           edgeName(t.ends[firstBoundary][0], t.ends[firstBoundary][1]) +
                                           " borders a single triangle; the §7 subdivision route needs a "
                                           "closed convex surface");

  const int euler = nv - ne + nf;
  if (euler != 2)
    throw Error(ErrorCode::CannotTile, "control mesh is not genus 0: V - E + F = " + std::to_string(nv) + " - " +
                                           std::to_string(ne) + " + " + std::to_string(nf) + " = " +
                                           std::to_string(euler) + " (genus " + std::to_string((2 - euler) / 2) +
                                           "); the §7 subdivision route needs a sphere-like closed surface");

  const auto reflex = reflexEdges(mesh, t);
  if (!reflex.empty()) {
    const auto& [e, angle] = reflex.front();
    throw Error(ErrorCode::CannotTile, "control mesh is not convex: " + std::to_string(reflex.size()) +
                                           " reflex edges, e.g. edge " + edgeName(t.ends[e][0], t.ends[e][1]) +
                                           " with an inside dihedral angle of " + std::to_string(angle) +
                                           " degrees (cleaned vertex ids); the §7 subdivision route needs a "
                                           "convex control polyhedron");
  }
  return mesh;
}

int subdivisionLevels(const TriMesh& control, int faces, double cell) {
  if (!std::isfinite(cell) || cell < 0)
    throw Error(ErrorCode::InvalidParameter, "cell must be a finite edge length >= 0 (0: use faces)");
  if (cell == 0 && faces < 1) throw Error(ErrorCode::InvalidParameter, "faces must be >= 1 when cell is 0");
  const TriMesh mesh = checkConvexControl(control);
  // The most levels whose surface (kSubdivisionSurfaceExtraLevels finer) stays within the memory limit.
  int maxLevels = 0;
  for (std::size_t surface = std::size_t(mesh.F.rows()) << (2 * kSubdivisionSurfaceExtraLevels);
       surface * 4 <= kMaxSubdivisionTriangles; surface *= 4)
    ++maxLevels;

  // Size of the triangulation per level: for cell > 0 its mean edge length at limit positions (measured,
  // since the limit surface is smaller than the control), else its vertex count (V' = V + E, E' = 2E + 3F,
  // F' = 4F under Loop's split).
  TriMesh current = mesh;
  double vertices = mesh.V.rows(), edges = buildTopology(mesh).edgeCount(), triangles = mesh.F.rows();
  auto size = [&] {
    if (cell == 0) return vertices;
    const TriMesh limit = loopLimitPositions(current);
    return meanEdgeLength(limit, buildTopology(limit));
  };
  auto subdivide = [&] {
    if (cell > 0) current = subdivideOnce(current);
    vertices += edges;
    edges = 2 * edges + 3 * triangles;
    triangles *= 4;
  };
  const double target = cell > 0 ? cell : faces;
  auto logDistance = [&](double s) { return std::abs(std::log(s / target)); };
  // Edge lengths fall and vertex counts grow with the level: refine while that brings the size nearer.
  int level = 0;
  for (double now = size(); (cell > 0 ? now > target : now < target) && level <= maxLevels;) {
    subdivide();
    const double next = size();
    if (logDistance(next) >= logDistance(now)) break;
    ++level;
    now = next;
  }
  if (level > maxLevels)
    throw Error(ErrorCode::InvalidParameter,
                (cell > 0 ? "cell " + std::to_string(cell) + " is too small"
                          : "faces " + std::to_string(faces) + " is too many") +
                    " for this control: it needs more than " + std::to_string(maxLevels) +
                    " Loop levels, beyond the memory limit of " + std::to_string(kMaxSubdivisionTriangles) +
                    " surface triangles");
  return level;
}

SubdivisionTriangulation subdivisionTriangulation(const TriMesh& control, int levels) {
  const TriMesh mesh = checkConvexControl(control);
  checkSubdivisionSize(static_cast<std::size_t>(mesh.F.rows()), levels + kSubdivisionSurfaceExtraLevels,
                          "levels + 2 (the surface's subdivision)");
  SubdivisionTriangulation result;
  result.levels = levels;
  const TriMesh subdivided = loopSubdivide(mesh, levels);
  result.triangulation.mesh = loopLimitPositions(subdivided);
  // Vertex i of the finer mesh is vertex i of `subdivided`, and limit points do not move under further
  // subdivision, so the triangulation's vertices are vertices of the surface.
  result.surface = std::make_shared<MeshSurface>(
      loopLimitPositions(loopSubdivide(subdivided, kSubdivisionSurfaceExtraLevels)), "loop limit surface");

  const EdgeTopology t = buildTopology(result.triangulation.mesh);
  std::map<int, int> valences;
  for (int n : t.valence) ++valences[n];
  std::string valenceText;
  for (const auto& [n, count] : valences)
    valenceText += (valenceText.empty() ? "" : ", ") + std::to_string(count) + " of valence " + std::to_string(n);
  result.triangulation.notes.push_back("§7 Loop subdivision: " + std::to_string(levels) + " levels of a control with " +
                                       std::to_string(mesh.V.rows()) + " vertices and " +
                                       std::to_string(mesh.F.rows()) + " triangles, vertices at their limit points (" +
                                       valenceText + ")");
  // §7 rests on the subdivided mesh being convex; say so if a shape defeats it.
  const auto reflex = reflexEdges(result.triangulation.mesh, t);
  if (!reflex.empty())
    result.triangulation.notes.push_back(std::to_string(reflex.size()) +
                                         " edges of the triangulation are reflex: the limit surface is not convex "
                                         "there and the dual may have invalid faces");
  return result;
}


bool closedConvexUpload(const MeshSurface& surface) {
  const TriMesh& m = surface.mesh();
  const Eigen::Index nv = m.V.rows();
  if (!surface.isClosed() || surface.eulerCharacteristic() != 2) return false;  // closed, genus 0
  const Vec3 centre = m.V.colwise().mean().transpose();
  // Strictly convex: K > 0 at kConvexShare of the vertices. Where the surface flattens (a rounded box's sides
  // and the cylinders between them) the Dupin conics stretch, and the geodesic's near-equilateral triangles
  // give invalid stars (Props 4, 5): a rounded box at 1000 faces had 208.
  Eigen::Index elliptic = 0;
  for (Eigen::Index v = 0; v < nv; ++v) {
    const LocalGeometry& g = surface.vertexGeometry(static_cast<int>(v));
    if (!(g.normal.dot(g.point - centre) > 0)) return false;  // not seen outward from the centre: not convex
    elliptic += g.gaussianCurvature() > 0;
  }
  return elliptic >= kConvexShare * nv;
}

Triangulation geodesicTriangulation(const MeshSurface& surface, int frequency) {
  if (frequency < 1) throw Error(ErrorCode::InvalidParameter, "geodesic frequency must be at least 1");
  const int n = frequency;
  const TriMesh ico = icosahedronControl(1.0);
  // Points of the geodesic sphere, shared along the icosahedron's edges and at its vertices: merged by
  // their rounded position on the unit sphere.
  std::vector<Vec3> points;
  std::map<std::array<long long, 3>, int> id;
  auto pointAt = [&](const Vec3& p) {
    const Vec3 u = p.normalized();
    const std::array<long long, 3> key = {std::llround(u.x() * 1e9), std::llround(u.y() * 1e9), std::llround(u.z() * 1e9)};
    const auto it = id.find(key);
    if (it != id.end()) return it->second;
    points.push_back(u);
    return id[key] = static_cast<int>(points.size()) - 1;
  };
  std::vector<Eigen::Vector3i> faces;
  for (int f = 0; f < 20; ++f) {
    const Vec3 a = ico.V.row(ico.F(f, 0)), b = ico.V.row(ico.F(f, 1)), c = ico.V.row(ico.F(f, 2));
    auto at = [&](int i, int j) { return pointAt((double(n - i - j) * a + double(i) * b + double(j) * c) / n); };
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        faces.emplace_back(at(i, j), at(i + 1, j), at(i, j + 1));
        if (i + j + 1 < n) faces.emplace_back(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
      }
  }
  // The sphere onto an ellipsoid of the surface's principal axes and extents, then onto the surface.
  const TriMesh& m = surface.mesh();
  const Vec3 centre = m.V.colwise().mean().transpose();
  const Eigen::MatrixXd centred = m.V.rowwise() - centre.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(centred.transpose() * centred);
  Eigen::Matrix3d axes = pca.eigenvectors();
  if (axes.determinant() < 0) axes.col(0) = -axes.col(0);
  const Eigen::MatrixXd local = centred * axes;
  const Vec3 extent = local.cwiseAbs().colwise().maxCoeff().transpose();
  Triangulation t;
  t.mesh.V.resize(static_cast<Eigen::Index>(points.size()), 3);
  double outward = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3 x = centre + axes * extent.cwiseProduct(points[i]);
    const LocalGeometry g = surface.closestPoint(x);
    t.mesh.V.row(static_cast<Eigen::Index>(i)) = g.point.transpose();
    outward += g.normal.dot(g.point - centre);
  }
  // The icosahedron's faces are CCW seen from outside: turned where the surface's normals point inwards.
  t.mesh.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f)
    t.mesh.F.row(static_cast<Eigen::Index>(f)) = outward >= 0 ? faces[f].transpose() : Eigen::RowVector3i(faces[f](0), faces[f](2), faces[f](1));
  t.notes.push_back("§7 on a closed convex upload: a geodesic icosahedron of frequency " + std::to_string(n) + " (" +
                    std::to_string(points.size()) + " vertices, all of valence 6 but the icosahedron's 12 of "
                    "valence 5, which become pentagons) mapped onto the surface by its principal axes");
  return t;
}

}  // namespace phex
