// phex — a surface's boundary curve indexed for nearest-point queries.
#include "phex/boundary_curve.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>

#include "phex/metrics.hpp"
#include "phex/planarize.hpp"

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

BoundaryCurve::Closest BoundaryCurve::closest(const Vec3& x, const std::vector<int>& candidates) const {
  Closest best;
  for (int s : candidates) {
    const Vec3 p = closestPointOnSegment(x, segments_[s].a, segments_[s].b);
    const double d = (p - x).norm();
    if (d < best.distance) best = {s, p, d};
  }
  return best;
}

std::pair<Vec3, double> BoundaryCurve::nearest(const Vec3& x, const std::vector<int>& candidates) const {
  const Closest c = closest(x, candidates);
  return {c.segment >= 0 ? c.point : x, c.distance};
}

std::pair<Vec3, double> BoundaryCurve::nearest(const Vec3& x) const {
  std::vector<int> candidates;
  near(x, candidates);
  return nearest(x, candidates);
}

BoundaryCurve::Offset BoundaryCurve::offset(const Vec3& x, const std::vector<int>& candidates,
                                            const Surface& surface) const {
  Offset o;
  const Closest c = closest(x, candidates);
  if (c.segment < 0) return o;
  o.segment = c.segment, o.point = c.point;
  o.normal = surface.closestPoint(o.point).normal;
  const Vec3 r = x - o.point;
  o.across = (r - r.dot(o.normal) * o.normal).norm();
  return o;
}

std::vector<std::pair<int, int>> outlineEdges(const PolyMesh& mesh) {
  std::vector<std::pair<int, int>> edges, outline;
  for (int f = 0; f < mesh.faceCount(); ++f)
    for (int i = 0, n = mesh.faceSize(f); i < n; ++i) {
      const int a = mesh.face(f)[i], b = mesh.face(f)[(i + 1) % n];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) outline.push_back(edges[i]);
    i = j;
  }
  return outline;
}

std::vector<char> boundaryNodes(const PolyMesh& mesh) {
  std::vector<char> on(static_cast<std::size_t>(mesh.V.rows()), 0);
  for (const auto& [a, b] : outlineEdges(mesh)) on[a] = on[b] = 1;
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

namespace {

// A loop of the boundary curve with the arc length at each of its points.
struct CurveLoop {
  const std::vector<Vec3>* points = nullptr;
  std::vector<double> at;
  double length = 0;
};

// Where a junction node of the clip ends: its position (moved or not) and the nearest point of the curve to it.
struct ClipEnd {
  Vec3 w = Vec3::Zero();
  bool moved = false;
  int loop = -1, segment = -1;  // segment: index within its loop
  double s = 0;                 // arc length along the loop
  Vec3 c = Vec3::Zero();        // the curve's point nearest w
};

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Douglas-Peucker: the points of p to keep so that the polyline through them stays within tol of every point.
std::vector<char> thinPolyline(const std::vector<Vec3>& p, double tol) {
  const int n = static_cast<int>(p.size());
  std::vector<char> keep(static_cast<std::size_t>(n), 0);
  if (n == 0) return keep;
  keep.front() = keep.back() = 1;
  std::vector<std::pair<int, int>> stack{{0, n - 1}};
  while (!stack.empty()) {
    const auto [lo, hi] = stack.back();
    stack.pop_back();
    double best = tol;
    int at = -1;
    for (int i = lo + 1; i < hi; ++i) {
      const double d = (closestPointOnSegment(p[i], p[lo], p[hi]) - p[i]).norm();
      if (d > best) best = d, at = i;
    }
    if (at < 0) continue;
    keep[at] = 1;
    stack.push_back({lo, at});
    stack.push_back({at, hi});
  }
  return keep;
}

// The point at arc length s along the polyline p (clamped to its ends).
Vec3 pointAlong(const std::vector<Vec3>& p, double s) {
  for (std::size_t q = 1; q < p.size(); ++q) {
    const double l = (p[q] - p[q - 1]).norm();
    if (s <= l) return l > 0 ? Vec3(p[q - 1] + (s / l) * (p[q] - p[q - 1])) : p[q - 1];
    s -= l;
  }
  return p.back();
}

}  // namespace

namespace {

BoundaryClip clipPanels(PolyMesh& mesh, const Surface& surface, bool mayRemove, std::vector<int>* faceOf) {
  BoundaryClip out;
  if (faceOf) {
    faceOf->resize(static_cast<std::size_t>(mesh.faceCount()));
    for (int f = 0; f < mesh.faceCount(); ++f) (*faceOf)[f] = f;
  }
  const int F = mesh.faceCount(), V = static_cast<int>(mesh.V.rows());
  const double h = mesh.meanEdgeLength();
  if (F == 0 || !(h > 0)) return out;
  const std::vector<std::vector<Vec3>> loopPoints = surface.boundaryCurves();
  const BoundaryCurve curve(loopPoints, 2 * h);
  if (curve.empty()) return out;
  // BoundaryCurve numbers its segments loop by loop, segment i from point i to i + 1.
  std::vector<CurveLoop> loops(loopPoints.size());
  std::vector<std::pair<int, int>> segmentOf;  // curve segment -> (loop, index in it)
  for (std::size_t l = 0; l < loopPoints.size(); ++l) {
    const std::vector<Vec3>& p = loopPoints[l];
    loops[l].points = &p;
    loops[l].at.resize(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) {
      loops[l].at[i] = loops[l].length;
      loops[l].length += (p[(i + 1) % p.size()] - p[i]).norm();
      segmentOf.emplace_back(static_cast<int>(l), static_cast<int>(i));
    }
  }

  // Edges with one face, and the faces at each node.
  const std::vector<std::pair<int, int>> outline = outlineEdges(mesh);
  std::vector<int> nodeFaces(static_cast<std::size_t>(V), 0);
  std::vector<std::array<int, 2>> twoFaces(static_cast<std::size_t>(V), {-1, -1});  // of nodes of two faces
  for (int f = 0; f < F; ++f)
    for (int i = 0, n = mesh.faceSize(f); i < n; ++i) {
      const int a = mesh.face(f)[i];
      if (nodeFaces[a] < 2) twoFaces[a][nodeFaces[a]] = f;
      ++nodeFaces[a];
    }
  std::vector<FacePlane> planes(static_cast<std::size_t>(F));
  std::vector<char> planed(static_cast<std::size_t>(F), 0);
  auto planeOf = [&](int f) -> const FacePlane& {
    if (!planed[f]) planes[f] = leastSquaresPlane(mesh, f), planed[f] = 1;
    return planes[f];
  };
  auto onBoundary = [&](int a, int b) {
    return std::binary_search(outline.begin(), outline.end(), std::make_pair(std::min(a, b), std::max(a, b)));
  };

  // Moved nodes stay as near the surface as the farthest node already is, or within half the goal.
  const double farthestNode = largestSurfaceDistance(mesh, surface);
  const double farthest = std::max(farthestNode, 0.5 * kSurfaceDistanceGoal * surface.bounds().diagonal().norm());
  std::vector<int> near;
  std::vector<Vec3> segmentNormal(curve.segments().size());  // the surface's normal at a segment's middle
  std::vector<char> normaled(curve.segments().size(), 0);
  // The curve's point nearest x, as an end.
  auto onCurve = [&](const Vec3& x, ClipEnd& e) {
    curve.near(x, near);
    const BoundaryCurve::Closest nearest = curve.closest(x, near);
    if (nearest.segment < 0) return;
    e.c = nearest.point;
    std::tie(e.loop, e.segment) = segmentOf[nearest.segment];
    const CurveLoop& L = loops[e.loop];
    e.s = L.at[e.segment] + (e.c - (*L.points)[e.segment]).norm();
  };
  // Node a, whose one edge into the surface comes from node t: onto the curve's wall along that edge's line
  // where it may move (a lone node, t = -1, stays).
  auto endOf = [&](int a, int t, bool mayMove) {
    ClipEnd e;
    const Vec3 x = mesh.vertex(a);
    e.w = x;
    if (mayMove && t >= 0 && nodeFaces[a] == 2) {
      Vec3 d = x - mesh.vertex(t);
      const double len = d.norm();
      curve.near(x, near);
      const BoundaryCurve::Offset at = curve.offset(x, near, surface);
      if (len > 0 && at.segment >= 0 && at.across > 1e-3 * h) {
        d /= len;
        // The wall over each segment near x is a plane (the segment and the surface normal at its middle); the
        // line meets the nearest one whose foot lies on its segment (at a corner of the curve, the side it
        // reaches first).
        double lambda = std::numeric_limits<double>::infinity();
        const std::vector<int> candidates = near;
        for (int k : candidates) {
          const BoundaryCurve::Segment& g = curve.segments()[k];
          const Vec3 e = g.b - g.a;
          const double el = e.norm();
          if (!(el > 0)) continue;
          if (!normaled[k]) segmentNormal[k] = surface.closestPoint(0.5 * (g.a + g.b)).normal, normaled[k] = 1;
          Vec3 m = segmentNormal[k].cross(e / el);
          if (!(m.norm() > 0.5)) continue;
          m.normalize();
          const double den = d.dot(m);
          if (!(std::abs(den) >= 0.3)) continue;  // the edge runs along this wall
          const double hit = -(x - g.a).dot(m) / den;
          const double along = (x + hit * d - g.a).dot(e) / (el * el);
          if (along >= -1e-9 && along <= 1 + 1e-9 && std::abs(hit) < std::abs(lambda)) lambda = hit;
        }
        bool ok = std::abs(lambda) <= kClipReach * h;
        if (ok) {  // and the curve's nearest point there is that segment's: the wall is not behind another side
          curve.near(x + lambda * d, near);
          ok = curve.offset(x + lambda * d, near, surface).across <= 1e-2 * h;
        }
        // Onto the line where the two panels' planes meet (the edge's direction is that line's only to the
        // planarity the solve reached, and a long move would carry the difference into both panels).
        Vec3 w = x + lambda * d;
        if (ok) {
          const FacePlane &p = planeOf(twoFaces[a][0]), &q = planeOf(twoFaces[a][1]);
          Eigen::Matrix<double, 2, 3> A;
          A.row(0) = p.normal.transpose();
          A.row(1) = q.normal.transpose();
          const Eigen::Vector2d r(p.normal.dot(p.centroid - w), q.normal.dot(q.centroid - w));
          const Eigen::Matrix2d G = A * A.transpose();
          if (G.determinant() > 1e-8) w += A.transpose() * G.inverse() * r;
          else w += 0.5 * (r(0) * p.normal + r(1) * q.normal);
        }
        if (ok && std::abs(lambda) <= kClipReach * h && (w - mesh.vertex(t)).dot(d) >= 0.1 * len) {
          const double off = (surface.closestPoint(w).point - w).norm();
          if (off <= std::max(farthest, (surface.closestPoint(x).point - x).norm())) e.w = w, e.moved = true;
        }
      }
    }
    onCurve(e.w, e);
    return e;
  };

  // Each boundary panel's clipped polygon: its node ids, with -1 - k for the k-th new point.
  struct Clipped {
    std::vector<int> ids;
    std::vector<Vec3> added;
    std::vector<int> junctions;  // the runs' ends
    // The corners for the fillers (kFillerOff) at the runs' ends left off the curve: (the end's node, the
    // corner's index in `added`), for the runs that start there (fromEnd) and those that end there (toEnd).
    std::vector<std::pair<int, int>> fromEnd, toEnd;
    bool ok = false;
    bool outside = false;  // the curve runs beyond the panel's other nodes: the whole panel lies outside it
  };
  std::vector<std::vector<ClipEnd>> cache(2, std::vector<ClipEnd>(static_cast<std::size_t>(V)));
  std::vector<std::vector<char>> cached(2, std::vector<char>(static_cast<std::size_t>(V), 0));
  std::vector<char> fixed(static_cast<std::size_t>(V), 0);
  auto end = [&](int a, int t) -> const ClipEnd& {
    const int k = fixed[a] ? 1 : 0;
    if (!cached[k][a]) cache[k][a] = endOf(a, t, k == 0), cached[k][a] = 1;
    return cache[k][a];
  };

  // The curve followed to `tolerance` mean edges; `fillers`: ends left off the curve get a filler's corner.
  auto clip = [&](int f, double tolerance, bool fillers) {
    Clipped c;
    const int n = mesh.faceSize(f);
    const int* ids = mesh.face(f);
    std::vector<char> e(static_cast<std::size_t>(n));
    int start = -1;
    for (int i = 0; i < n; ++i) e[i] = onBoundary(ids[i], ids[(i + 1) % n]);
    for (int i = 0; i < n; ++i)
      if (e[i] && !e[(i + n - 1) % n]) start = i;
    if (start < 0) return c;  // no boundary edge, or all of them
    FacePlane plane = leastSquaresPlane(mesh, f);
    plane.normal = normalLikeFace(mesh, f, plane.normal);
    auto project = [&](const Vec3& p) -> Vec3 { return p - (p - plane.centroid).dot(plane.normal) * plane.normal; };
    std::vector<Vec3> position;  // of c.ids
    for (int k = 0; k < n;) {
      const int i = (start + k) % n;
      if (!e[i]) {  // a node on an edge into the surface: the end of a run (moved with it) where one comes before
        c.ids.push_back(ids[i]);
        position.push_back(e[(i + n - 1) % n] ? end(ids[i], ids[(i + 1) % n]).w : mesh.vertex(ids[i]));
        ++k;
        continue;
      }
      int j = k;
      while (e[(start + j) % n]) ++j;  // j < n: the edge before `start` has two faces
      const int a = ids[i], b = ids[(start + j) % n];
      for (int m = k + 1; m < j; ++m)
        if (nodeFaces[ids[(start + m) % n]] != 1) return c;  // a node shared beyond the run: left as it is
      const ClipEnd& ea = end(a, ids[(i + n - 1) % n]);
      const ClipEnd& eb = end(b, ids[(start + j + 1) % n]);
      if (ea.loop < 0 || ea.loop != eb.loop) return c;
      // The curve from a's nearest point to b's, the shorter way round the loop.
      const CurveLoop& L = loops[ea.loop];
      const std::vector<Vec3>& P = *L.points;
      const int np = static_cast<int>(P.size());
      double ahead = eb.s - ea.s;
      if (ahead < 0) ahead += L.length;
      const bool forward = ahead <= L.length - ahead;
      const double arc = forward ? ahead : L.length - ahead;
      double chain = (ea.w - mesh.vertex(a)).norm() + (eb.w - mesh.vertex(b)).norm();
      for (int m = k; m < j; ++m) chain += (mesh.vertex(ids[(start + m + 1) % n]) - mesh.vertex(ids[(start + m) % n])).norm();
      if (!(arc <= 3 * chain + h)) return c;  // the ends' nearest points are not this run's stretch of the curve
      std::vector<Vec3> piece{ea.c};
      if (ea.segment != eb.segment || (forward ? ea.s > eb.s : ea.s < eb.s)) {
        if (forward)
          for (int q = (ea.segment + 1) % np;; q = (q + 1) % np) {
            piece.push_back(P[q]);
            if (q == eb.segment || static_cast<int>(piece.size()) > np) break;
          }
        else
          for (int q = ea.segment;; q = (q + np - 1) % np) {
            if (q == eb.segment) break;
            piece.push_back(P[q]);
            if (static_cast<int>(piece.size()) > np) break;
          }
      }
      piece.push_back(eb.c);
      // An end that stays off the curve (its shared edge runs along the wall) gets a corner on the curve
      // kFillerSpan mean edges along the run from its nearest point, for the filler panel between it and the
      // neighbouring panel's such corner (below); where the run is too short for the corners, it keeps its tooth.
      // (Only at a node of two panels: the filler makes it one of three.)
      bool offA = fillers && nodeFaces[a] == 2 && (ea.w - ea.c).norm() > kFillerOff * h;
      bool offB = fillers && nodeFaces[b] == 2 && (eb.w - eb.c).norm() > kFillerOff * h;
      if (offA || offB) {
        double length = 0;
        for (std::size_t q = 1; q < piece.size(); ++q) length += (piece[q] - piece[q - 1]).norm();
        // (Half the node's distance from the curve, where more: a deep tooth gets a filler about as wide as tall.)
        const double spanA = std::max(kFillerSpan * h, 0.5 * (ea.w - ea.c).norm());
        const double spanB = std::max(kFillerSpan * h, 0.5 * (eb.w - eb.c).norm());
        double from = offA ? spanA : 0.0, to = length - (offB ? spanB : 0.0);
        // A short run: its corner halfway, or where both ends are off, its two corners at its thirds (one corner
        // for both fillers would be a node of three panels on the outline, whose beams' axes could not turn to keep
        // the boundary beams planar).
        bool fits = to - from >= kClipSpacing * h;
        if (!fits && length >= kClipSpacing * h) {
          if (offA && offB) from = length / 3, to = 2 * length / 3;
          else if (offA) from = 0.5 * length;
          else to = 0.5 * length;
          fits = true;
        }
        if (fits) {
          std::vector<Vec3> trimmed{pointAlong(piece, from)};
          double at = 0;
          for (std::size_t q = 1; q + 1 < piece.size(); ++q) {
            at += (piece[q] - piece[q - 1]).norm();
            if (at > from && at < to) trimmed.push_back(piece[q]);
          }
          trimmed.push_back(pointAlong(piece, to));
          // (The corners no farther off the surface than the run's other corners may lie: the farthest node, or half
          // the distance goal. Held to the farthest node alone, the rows' boundary panels on the hyperboloid, the
          // vase and the hyperbolic paraboloid kept most of their teeth: the curve stands a little higher over a
          // panel's plane than a node fitted to the surface.)
          const bool nearA = !offA || (project(trimmed.front()) - trimmed.front()).norm() <= farthest;
          const bool nearB = !offB || (project(trimmed.back()) - trimmed.back()).norm() <= farthest;
          if (nearA && nearB) piece = std::move(trimmed);
          else offA = offB = false;  // the curve stands too high over the panel's plane there
        } else {
          offA = offB = false;
        }
      }
      const std::vector<char> keep = thinPolyline(piece, tolerance * h);
      c.junctions.push_back(a);
      c.ids.push_back(a);
      position.push_back(ea.w);
      auto addCorner = [&](const Vec3& x) {
        c.ids.push_back(-1 - static_cast<int>(c.added.size()));
        c.added.push_back(x);
        position.push_back(x);
        return static_cast<int>(c.added.size()) - 1;
      };
      Vec3 last = ea.w;  // the run's last corner so far
      if (offA) c.fromEnd.emplace_back(a, addCorner(last = project(piece.front())));
      const Vec3 stop = offB ? project(piece.back()) : eb.w;  // the run's last corner
      for (std::size_t q = 1; q + 1 < piece.size(); ++q) {
        if (!keep[q]) continue;
        const Vec3 x = project(piece[q]);
        // Not nearer than kClipSpacing to the corner before or the run's end (short edges would make the panel's
        // planarity, relative to its mean edge, look worse than it is), nor farther off the surface than the
        // moved nodes may go (the curve stands that high over the panel's plane there).
        if ((x - last).norm() < kClipSpacing * h || (x - stop).norm() < kClipSpacing * h) continue;
        if ((x - piece[q]).norm() > farthest) continue;
        addCorner(x);
        last = x;
      }
      if (offB) c.toEnd.emplace_back(b, addCorner(stop));
      c.junctions.push_back(b);  // b follows as the next interior-edge node
      k = j;
    }
    // In the plane: simple, turning as the panel did, and its fan from the first corner inside it (the viewers
    // fan polygons from their first corner): rotated to a corner from which it is, where one is.
    Vec3 u = plane.normal.unitOrthogonal(), v = plane.normal.cross(u);
    auto inPlane = [&](const Vec3& x) { return Vec2((x - plane.centroid).dot(u), (x - plane.centroid).dot(v)); };
    std::vector<Vec2> q;
    for (const Vec3& x : position) q.push_back(inPlane(x));
    const bool crosses = polygonSelfIntersects(q);
    if (crosses || !(signedArea(q) > 0)) {
      // A simple outline turned over, where the panel itself is simple and turns the right way: the curve passes
      // beyond the panel's nodes into the surface, so all of the panel lies outside it.
      if (!crosses) {
        std::vector<Vec2> own;
        for (int i = 0; i < n; ++i) own.push_back(inPlane(mesh.vertex(ids[i])));
        c.outside = !polygonSelfIntersects(own) && signedArea(own) > 0;
      }
      return c;
    }
    const int m = static_cast<int>(q.size());
    for (int r = 0; r < m; ++r) {
      bool fan = true;
      for (int i = 1; i + 1 < m && fan; ++i) fan = cross2(q[(r + i) % m] - q[r], q[(r + i + 1) % m] - q[r]) > 0;
      if (!fan) continue;
      std::rotate(c.ids.begin(), c.ids.begin() + r, c.ids.end());
      break;
    }
    c.ok = true;
    return c;
  };

  // Faces with a boundary run; a face whose clip fails holds its runs' ends in place, and its neighbours are
  // clipped again, until no face changes.
  std::vector<int> panels;
  for (int f = 0; f < F; ++f)
    for (int i = 0, n = mesh.faceSize(f); i < n; ++i)
      if (onBoundary(mesh.face(f)[i], mesh.face(f)[(i + 1) % n])) {
        panels.push_back(f);
        break;
      }
  // The curve followed closely, then with fewer corners (kClipRetryTolerances) where that fails.
  auto clipRetried = [&](int f, bool fillers) {
    Clipped c = clip(f, kClipTolerance, fillers);
    for (double tolerance : kClipRetryTolerances)
      if (!c.ok) c = clip(f, tolerance, fillers);
    return c;
  };
  std::vector<Clipped> result(panels.size());
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t k = 0; k < panels.size(); ++k) {
      result[k] = clipRetried(panels[k], true);
      // Without its fillers' corners (its ends then stay where they are, a notch in the outline beside the
      // neighbour's corner) rather than not at all; not a panel found outside the curve (removed below).
      if (!result[k].ok && !result[k].outside) {
        Clipped plain = clipRetried(panels[k], false);
        if (plain.ok) result[k] = std::move(plain);
      }
      if (result[k].ok) continue;
      // Its ends are those of the original runs: the face's boundary nodes next to a two-face edge.
      const int f = panels[k], n = mesh.faceSize(f);
      const int* ids = mesh.face(f);
      for (int i = 0; i < n; ++i) {
        const bool before = onBoundary(ids[(i + n - 1) % n], ids[i]), after = onBoundary(ids[i], ids[(i + 1) % n]);
        if (before != after && !fixed[ids[i]]) fixed[ids[i]] = 1, changed = true;
      }
    }
  }

  // Panels wholly outside the curve go, where the mesh stays a manifold without them, and the panels then on the
  // boundary are clipped afresh (once: what lies outside after that stays as it is).
  if (mayRemove) {
    std::vector<char> drop(static_cast<std::size_t>(F), 0);
    int dropped = 0;
    for (std::size_t k = 0; k < panels.size(); ++k)
      if (!result[k].ok && result[k].outside) drop[panels[k]] = 1, ++dropped;
    if (dropped > 0 && dropped < F) {
      PolyMesh rest;
      rest.V = mesh.V;
      std::vector<int> restOf;  // the remaining faces' indices in `mesh`
      for (int f = 0; f < F; ++f)
        if (!drop[f]) rest.addFace(std::vector<int>(mesh.face(f), mesh.face(f) + mesh.faceSize(f))), restOf.push_back(f);
      // Each node of a removed panel still on panels ends two outline edges (a fan with one gap), or none.
      std::vector<int> ends(static_cast<std::size_t>(V), 0);
      for (const auto& [a, b] : outlineEdges(rest)) ++ends[a], ++ends[b];
      bool manifold = true;
      for (int f = 0; f < F && manifold; ++f)
        for (int i = 0; drop[f] && i < mesh.faceSize(f); ++i) {
          const int e = ends[mesh.face(f)[i]];
          manifold = manifold && (e == 0 || e == 2);
        }
      if (manifold) {
        std::vector<int> inner;
        BoundaryClip again = clipPanels(rest, surface, false, faceOf ? &inner : nullptr);
        if (faceOf) {
          for (int& f : inner) f = f >= 0 ? restOf[f] : -1;
          *faceOf = std::move(inner);
        }
        again.removed = dropped;
        mesh = std::move(rest);
        return again;
      }
    }
  }

  // The new mesh: moved ends, added points, the replaced nodes dropped.
  std::vector<char> moved(static_cast<std::size_t>(V), 0);
  PolyMesh next;
  std::vector<Vec3> points;
  for (int v = 0; v < V; ++v) points.push_back(mesh.vertex(v));
  std::vector<std::vector<int>> faces(static_cast<std::size_t>(F));
  for (int f = 0; f < F; ++f) faces[f].assign(mesh.face(f), mesh.face(f) + mesh.faceSize(f));
  std::vector<int> fromCorner(static_cast<std::size_t>(V), -1), toCorner(static_cast<std::size_t>(V), -1);
  for (std::size_t k = 0; k < panels.size(); ++k) {
    const Clipped& c = result[k];
    if (!c.ok) {
      ++out.skipped;
      continue;
    }
    ++out.panels;
    const int base = static_cast<int>(points.size());
    for (const Vec3& x : c.added) points.push_back(x);
    out.nodesAdded += static_cast<int>(c.added.size());
    std::vector<int>& ids = faces[panels[k]];
    for (int id : ids)
      if (nodeFaces[id] == 1 && std::find(c.ids.begin(), c.ids.end(), id) == c.ids.end()) ++out.nodesRemoved;
    ids.clear();
    for (int id : c.ids) ids.push_back(id >= 0 ? id : base - 1 - id);
    for (int a : c.junctions) {
      const ClipEnd& e = cache[fixed[a] ? 1 : 0][a];
      if (e.moved && !moved[a]) points[a] = e.w, moved[a] = 1, ++out.nodesMoved;
    }
    for (const auto& [a, i] : c.fromEnd) fromCorner[a] = base + i;
    for (const auto& [a, i] : c.toEnd) toCorner[a] = base + i;
  }
  // The filler panels: a triangle from each end left off the curve to its two panels' corners on the curve (a
  // triangle is planar whatever its corners), so the outline follows the curve there too and the end becomes a
  // node of three panels. Where one of the two panels kept its edges, its neighbour's corner stays as it is.
  for (int a = 0; a < V; ++a)
    if (fromCorner[a] >= 0 && toCorner[a] >= 0) {
      faces.push_back({a, toCorner[a], fromCorner[a]});
      if (faceOf) faceOf->push_back(-1);
      ++out.fillers;
    }
  std::vector<int> index(points.size(), -1);  // the nodes still used, in their order
  for (const std::vector<int>& ids : faces)
    for (int id : ids) index[id] = 0;
  int used = 0;
  for (int& i : index)
    if (i == 0) i = used++;
  next.V.resize(used, 3);
  for (std::size_t v = 0; v < points.size(); ++v)
    if (index[v] >= 0) next.V.row(index[v]) = points[v].transpose();
  for (const std::vector<int>& ids : faces) {
    std::vector<int> renumbered;
    for (int id : ids) renumbered.push_back(index[id]);
    next.addFace(renumbered);
  }
  // The edge as drawn: how far the curve's points lie from the outline (the edges of one panel).
  {
    std::vector<std::vector<Vec3>> segments;
    for (const auto& [a, b] : outlineEdges(next)) segments.push_back({next.vertex(a), next.vertex(b)});
    const double edge = next.meanEdgeLength();  // of the clipped mesh, as the pipeline's other measures
    const BoundaryCurve drawn(segments, 2 * edge);
    for (const std::vector<Vec3>& loop : loopPoints)
      for (const Vec3& x : loop) out.gapMax = std::max(out.gapMax, std::min(drawn.nearest(x).second, 2 * edge) / edge);
  }
  mesh = std::move(next);
  return out;
}

}  // namespace

BoundaryClip clipBoundaryPanels(PolyMesh& mesh, const Surface& surface, std::vector<int>* faceOf) {
  return clipPanels(mesh, surface, true, faceOf);
}

}  // namespace phex
