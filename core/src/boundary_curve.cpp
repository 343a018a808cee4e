// phex — a surface's boundary curve indexed for nearest-point queries.
#include "phex/boundary_curve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace phex {

BoundaryCurve::BoundaryCurve(const std::vector<std::vector<Vec3>>& loops, double reach) {
  for (const std::vector<Vec3>& loop : loops)
    for (std::size_t i = 0; i < loop.size(); ++i) segments_.push_back({loop[i], loop[(i + 1) % loop.size()]});
  if (segments_.empty()) return;
  Box3 box;
  for (const Segment& s : segments_) box.extend(s.a), box.extend(s.b);
  lo_ = box.min();
  for (int k = 0; k < 3; ++k) {
    cell_[k] = std::max(reach > 0 && std::isfinite(reach) ? reach : 0.0, box.sizes()(k) / 1024);
    if (!(cell_[k] > 0)) cell_[k] = 1;
    dims_[k] = gridCell(box.sizes()(k) / cell_[k], 1024) + 1;
  }
  for (int s = 0; s < static_cast<int>(segments_.size()); ++s) {
    const Vec3 a = segments_[s].a.cwiseMin(segments_[s].b), b = segments_[s].a.cwiseMax(segments_[s].b);
    for (int i = cellOf(a, 0); i <= cellOf(b, 0); ++i)
      for (int j = cellOf(a, 1); j <= cellOf(b, 1); ++j)
        for (int k = cellOf(a, 2); k <= cellOf(b, 2); ++k) cells_.emplace_back(key(i, j, k), s);
  }
  std::sort(cells_.begin(), cells_.end());
}

void BoundaryCurve::near(const Vec3& x, std::vector<int>& out) const {
  out.clear();
  if (segments_.empty() || !x.allFinite()) return;
  for (int k = 0; k < 3; ++k) {  // beyond the cells next to the grid: nothing within reach
    const double at = (x(k) - lo_(k)) / cell_[k];
    if (at < -1 || at > dims_[k] + 1) return;
  }
  const int ci = cellOf(x, 0), cj = cellOf(x, 1), ck = cellOf(x, 2);
  for (int i = std::max(ci - 1, 0); i <= std::min(ci + 1, dims_[0] - 1); ++i)
    for (int j = std::max(cj - 1, 0); j <= std::min(cj + 1, dims_[1] - 1); ++j)
      for (int k = std::max(ck - 1, 0); k <= std::min(ck + 1, dims_[2] - 1); ++k) {
        const long long want = key(i, j, k);
        for (auto it = std::lower_bound(cells_.begin(), cells_.end(), std::make_pair(want, -1));
             it != cells_.end() && it->first == want; ++it)
          out.push_back(it->second);
      }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

std::pair<Vec3, double> BoundaryCurve::nearest(const Vec3& x, const std::vector<int>& candidates) const {
  std::pair<Vec3, double> best{x, std::numeric_limits<double>::infinity()};
  for (int s : candidates) {
    const Vec3 p = closestPointOnSegment(x, segments_[s].a, segments_[s].b);
    const double d = (p - x).norm();
    if (d < best.second) best = {p, d};
  }
  return best;
}

std::pair<Vec3, double> BoundaryCurve::nearest(const Vec3& x) const {
  std::vector<int> candidates;
  near(x, candidates);
  return nearest(x, candidates);
}

BoundaryCurve::Offset BoundaryCurve::offset(const Vec3& x, const std::vector<int>& candidates,
                                            const Surface& surface) const {
  Offset o;
  double best = std::numeric_limits<double>::infinity();
  for (int s : candidates) {
    const Vec3 p = closestPointOnSegment(x, segments_[s].a, segments_[s].b);
    const double d = (p - x).norm();
    if (d < best) best = d, o.segment = s, o.point = p;
  }
  if (o.segment < 0) return o;
  o.normal = surface.closestPoint(o.point).normal;
  const Vec3 r = x - o.point;
  o.across = (r - r.dot(o.normal) * o.normal).norm();
  return o;
}

std::vector<char> boundaryNodes(const PolyMesh& mesh) {
  std::vector<std::pair<int, int>> edges;
  for (int f = 0; f < mesh.faceCount(); ++f)
    for (int i = 0, n = mesh.faceSize(f); i < n; ++i) {
      const int a = mesh.face(f)[i], b = mesh.face(f)[(i + 1) % n];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  std::vector<char> on(static_cast<std::size_t>(mesh.V.rows()), 0);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) on[edges[i].first] = on[edges[i].second] = 1;
    i = j;
  }
  return on;
}

BoundaryOffset boundaryOffset(const PolyMesh& mesh, const Surface& surface) {
  BoundaryOffset out;
  const double edge = mesh.meanEdgeLength();
  if (!(edge > 0)) return out;
  const BoundaryCurve curve(surface.boundaryCurves(), 2 * edge);
  if (curve.empty()) return out;
  const std::vector<char> on = boundaryNodes(mesh);
  std::vector<double> offsets;
  std::vector<int> near;
  for (int v = 0; v < static_cast<int>(on.size()); ++v) {
    if (!on[v]) continue;
    curve.near(mesh.vertex(v), near);
    const double d = curve.offset(mesh.vertex(v), near, surface).across;
    if (std::isfinite(d)) offsets.push_back(d / edge);
  }
  if (offsets.empty()) return out;
  out.nodes = static_cast<int>(offsets.size());
  std::sort(offsets.begin(), offsets.end());
  out.max = offsets.back();
  out.median = offsets[offsets.size() / 2];
  return out;
}

}  // namespace phex
