// Closed test surfaces of any genus, as triangle meshes of implicit surfaces f(x) = 0 (marching tetrahedra).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include "phex/mesh.hpp"
#include "phex/mesh_io.hpp"

namespace phex::test {

// The zero set of f in the box [lo, hi] as a closed triangle mesh, oriented so that normals point where f > 0:
// the box in n^3 cubes, each cut into six tetrahedra along its main diagonal (a conforming tetrahedral grid), each
// crossed by the surface in one or two triangles whose corners are found on the edges by bisection.
inline TriMesh marchingTetrahedra(const std::function<double(const Vec3&)>& f, const Vec3& box0, const Vec3& box1, int n) {
  // The grid off the surfaces' planes of symmetry by an irrational share of a step: crossings placed
  // symmetrically fall in a line and make triangles of no area, whose dropping would leave holes.
  const Vec3 step = (box1 - box0) / (n - 1);
  const Vec3 lo = box0 - Vec3(0.3719, 0.4142, 0.2357).cwiseProduct(step), hi = lo + n * step;
  auto index = [n](int i, int j, int k) { return (std::int64_t(k) * (n + 1) + j) * (n + 1) + i; };
  auto point = [&](std::int64_t id) {
    const int i = int(id % (n + 1)), j = int((id / (n + 1)) % (n + 1)), k = int(id / (std::int64_t(n + 1) * (n + 1)));
    return Vec3(lo.x() + i * step.x(), lo.y() + j * step.y(), lo.z() + k * step.z());
  };
  std::vector<double> value(std::size_t(n + 1) * (n + 1) * (n + 1));
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const double v = f(point(index(i, j, k)));
        value[std::size_t(index(i, j, k))] = v == 0 ? 1e-300 : v;  // no corner exactly on the surface
      }
  std::vector<Vec3> points;
  std::unordered_map<std::uint64_t, int> crossing;  // grid edge -> its point
  auto edgePoint = [&](std::int64_t a, std::int64_t b) {
    if (a > b) std::swap(a, b);
    const std::uint64_t key = std::uint64_t(a) * std::uint64_t(value.size()) + std::uint64_t(b);
    const auto it = crossing.find(key);
    if (it != crossing.end()) return it->second;
    Vec3 p = point(a), q = point(b);
    double fp = value[std::size_t(a)];
    for (int s = 0; s < 40; ++s) {
      const Vec3 m = 0.5 * (p + q);
      const double fm = f(m);
      if ((fm > 0) == (fp > 0)) p = m, fp = fm;
      else q = m;
    }
    points.push_back(0.5 * (p + q));
    crossing.emplace(key, static_cast<int>(points.size()) - 1);
    return static_cast<int>(points.size()) - 1;
  };
  std::vector<std::array<int, 3>> triangles;
  auto gradient = [&](const Vec3& x) {
    const double e = 1e-4 * step.norm();
    return Vec3(f(x + Vec3(e, 0, 0)) - f(x - Vec3(e, 0, 0)), f(x + Vec3(0, e, 0)) - f(x - Vec3(0, e, 0)),
                f(x + Vec3(0, 0, e)) - f(x - Vec3(0, 0, e)));
  };
  auto emit = [&](int a, int b, int c) {
    if (a == b || b == c || a == c) return;
    const Vec3 A = points[a], B = points[b], C = points[c];
    if ((B - A).cross(C - A).dot(gradient((A + B + C) / 3)) < 0) std::swap(b, c);
    triangles.push_back({a, b, c});
  };
  // The six tetrahedra of a cube around its diagonal from corner 0 to corner 7 (corners numbered by bits x, y, z).
  static const int tets[6][4] = {{0, 1, 3, 7}, {0, 3, 2, 7}, {0, 2, 6, 7}, {0, 6, 4, 7}, {0, 4, 5, 7}, {0, 5, 1, 7}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        std::int64_t corner[8];
        for (int c = 0; c < 8; ++c) corner[c] = index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        for (const auto& t : tets) {
          std::int64_t in[4], out[4];
          int ni = 0, no = 0;
          for (int c : t) (value[std::size_t(corner[c])] < 0 ? in[ni++] : out[no++]) = corner[c];
          if (ni == 0 || no == 0) continue;
          if (ni == 1 || no == 1) {
            const std::int64_t lone = ni == 1 ? in[0] : out[0];
            const std::int64_t* others = ni == 1 ? out : in;
            emit(edgePoint(lone, others[0]), edgePoint(lone, others[1]), edgePoint(lone, others[2]));
          } else {  // two and two: a quad
            const int p0 = edgePoint(in[0], out[0]), p1 = edgePoint(in[0], out[1]), p2 = edgePoint(in[1], out[1]),
                      p3 = edgePoint(in[1], out[0]);
            emit(p0, p1, p2);
            emit(p0, p2, p3);
          }
        }
      }
  TriMesh raw;
  raw.V.resize(static_cast<int>(points.size()), 3);
  for (int v = 0; v < static_cast<int>(points.size()); ++v) raw.V.row(v) = points[v].transpose();
  raw.F.resize(static_cast<int>(triangles.size()), 3);
  for (int t = 0; t < static_cast<int>(triangles.size()); ++t)
    for (int c = 0; c < 3; ++c) raw.F(t, c) = triangles[t][c];
  return cleanTriMesh(raw, "implicit surface");
}

// A closed surface of genus g (0 .. 3): an ellipsoid, or g tori side by side blended into one (a smooth minimum
// of their distance functions), a surface with g handles.
inline TriMesh closedSurfaceOfGenus(int g, int resolution = 40) {
  if (g == 0)
    return marchingTetrahedra([](const Vec3& x) { return x.x() * x.x() / 1.44 + x.y() * x.y() + x.z() * x.z() / 0.64 - 1; },
                              Vec3(-1.3, -1.1, -0.9), Vec3(1.3, 1.1, 0.9), resolution);
  const double spacing = 1.7, R = 1.0, r = 0.35, k = 8.0;
  const double first = -0.5 * spacing * (g - 1);
  return marchingTetrahedra(
      [=](const Vec3& x) {
        double sum = 0;
        for (int i = 0; i < g; ++i) {
          const double cx = first + i * spacing, ring = std::hypot(x.x() - cx, x.y()) - R;
          sum += std::exp(-k * (std::hypot(ring, x.z()) - r));
        }
        return -std::log(sum) / k;
      },
      Vec3(first - R - r - 0.3, -R - r - 0.3, -r - 0.3), Vec3(-first + R + r + 0.3, R + r + 0.3, r + 0.3), resolution);
}

// V - E + F of a triangle mesh.
inline int eulerCharacteristic(const TriMesh& mesh) {
  std::vector<std::uint64_t> edges;
  for (int f = 0; f < mesh.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = mesh.F(f, k), b = mesh.F(f, (k + 1) % 3);
      edges.push_back(std::min(a, b) << 32 | std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return static_cast<int>(mesh.V.rows()) - static_cast<int>(edges.size()) + static_cast<int>(mesh.F.rows());
}

}  // namespace phex::test
