// phex — the fine mesh the global method's fields live on, with the Dupin frame at every vertex.
#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>

#include "global.hpp"
#include "phex/error.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/parallel.hpp"
#include "phex/triangulation.hpp"

namespace phex::global {
namespace {

// The field mesh stops being refined past this many triangles.
constexpr std::size_t kMaxFieldTriangles = std::size_t(6) << 20;
// An analytic surface's parameter lattice is laid at this many field-mesh edges and split as many times.
constexpr double kCoarseSplit = 3.0;
// Edges longer than this many field-mesh edges after the uniform split are bisected.
constexpr double kLongEdge = 1.3;
constexpr double kAreaSplitMargin = 4.0;
// An upload whose split (and bisected) mesh has over kThinAbove times the vertices a mesh of field-mesh edges has is
// remeshed first (remesh.cpp: thinned(), at thinnedSplit() field-mesh edges). A field mesh far finer than the cell
// lost the lattice hexagons and time: the bumps sampled as 500k triangles at 1000 and 3000 faces had 254 and 85
// field-mesh vertices a lattice point (7 from an analytic surface) and 84.4 and 89.7 % hexagons against 91.3 and
// 93.1 % from 20k triangles, in 4.7 and 4.8 s; thinned, 88.3 and 92.7 % in 1.4 and 1.8 s. Thinned at 1.5 times the
// density: 1.7 points fewer hexagons; from twice the density on: the bubble shell at 1000 faces (2.2 times) lost 1.6
// points.
constexpr double kThinAbove = 2.5;
// The half-width of the window a zigzag boundary's direction is taken over (zigzagWindow): at least
// kTangentWindow field-mesh edges (about a cell) and kToothWindow of the coarse mesh's boundary edges (a zigzag's
// teeth are two long: a tent as wide as a tooth cancels them), but at most kLongestWindow field-mesh edges (about 3
// cells): longer teeth are the boundary's own shape, which the lattice can follow. (A zigzag of 0.1 edges cut at
// 20 degrees through a lattice: 6 degrees off at most.) A loop zigzags where over kZigzagShare of its coarse
// vertices turn by over kToothTurn (sine) in the sense opposite to the next one's; a polygon of long straight edges
// (the bubble shell's 88) does not, and its rows follow each edge.
constexpr double kTangentWindow = 2.5;
constexpr double kToothWindow = 3.0, kLongestWindow = 8.0, kToothTurn = 0.17, kZigzagShare = 0.3;
// A boundary corner turns by more than this over the window on either side (cosine of 40 degrees).
constexpr double kCornerCos = 0.766;
// ... judged over chords this many windows long (over one, the teeth of a zigzag boundary turn by as much).
constexpr double kCornerWindow = 2.0;
// The Dupin frame's aspect (sqrt of |k| ratio, regularized) from which the field is aligned, and fully.
constexpr double kAlignFrom = 1.2, kAlignFull = 1.7;
// The regularization of the aspect that decides the alignment, as a share of the metric's.
constexpr double kAlignEps = 0.05;
// GlobalOptions::principalTrial's weight: from an aspect (square root of the ratio of the principal |curvature|s,
// regularized by kAlignEps) of kPrincipalFrom on, fully from kPrincipalFull. (On the 40 clean runs and the genus
// 0-3 set, held from 1.2 to 1.7, or from 1.1 to 1.5, gave the cyclide 3-4 points more hexagons and the bubble and
// the bumps 0.5-3 fewer, at 3000 and 5000 faces: hence a trial, kept by the singular points.)
constexpr double kPrincipalFrom = 1.2, kPrincipalFull = 1.7;

// Each triangle of `mesh` split k x k: the corners keep their ids, then come the edges' points, then the inner
// points. `where` gets, per vertex, a triangle of `mesh` holding it and its barycentric coordinates there, and
// `source` per triangle the triangle of `mesh` it lies in.
TriMesh split(const TriMesh& mesh, int k, std::vector<std::pair<int, Vec3>>& where, std::vector<int>& source) {
  const int nv = static_cast<int>(mesh.V.rows()), nf = static_cast<int>(mesh.F.rows());
  where.assign(nv, {-1, Vec3::Zero()});
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      Vec3 b = Vec3::Zero();
      b(c) = 1;
      if (where[mesh.F(f, c)].first < 0) where[mesh.F(f, c)] = {f, b};
    }
  std::vector<Vec3> points;
  for (int v = 0; v < nv; ++v) points.push_back(mesh.V.row(v).transpose());
  // Edge (a < b) -> id of its first inner point (from a), -1 until its first triangle comes: the edges indexed by
  // their place among a's larger neighbours, sorted (a hash map of them took a third of the split at 10k faces).
  std::vector<int> higherStart(nv + 1, 0), higher;
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) ++higherStart[std::min(mesh.F(f, c), mesh.F(f, (c + 1) % 3)) + 1];
  for (int v = 0; v < nv; ++v) higherStart[v + 1] += higherStart[v];
  higher.resize(higherStart[nv]);
  {
    std::vector<int> fill(higherStart.begin(), higherStart.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int c = 0; c < 3; ++c) {
        const int a = mesh.F(f, c), b = mesh.F(f, (c + 1) % 3);
        higher[fill[std::min(a, b)]++] = std::max(a, b);
      }
  }
  for (int v = 0; v < nv; ++v) {
    const auto b = higher.begin() + higherStart[v], e = higher.begin() + higherStart[v + 1];
    std::sort(b, e);
    // Duplicates (an edge's two triangles) stay: the lookup below finds the first of them.
  }
  auto edgeIndex = [&](int lo, int hi) {
    const auto b = higher.begin() + higherStart[lo], e = higher.begin() + higherStart[lo + 1];
    return static_cast<int>(std::lower_bound(b, e, hi) - higher.begin());
  };
  std::vector<int> edgeFirst(higher.size(), -1);
  std::vector<int> grid((k + 1) * (k + 2) / 2);
  auto at = [&](int i, int j) -> int& { return grid[j * (k + 1) - j * (j - 1) / 2 + i]; };  // i + j <= k
  std::vector<int> tri;
  source.clear();
  for (int f = 0; f < nf; ++f) {
    const int c[3] = {mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2)};
    auto inner = [&](int i, int j) {
      const Vec3 b(double(k - i - j) / k, double(i) / k, double(j) / k);
      points.push_back(b(0) * points[c[0]] + b(1) * points[c[1]] + b(2) * points[c[2]]);
      where.push_back({f, b});
      return static_cast<int>(points.size()) - 1;
    };
    // The s-th point (1 .. k - 1) of edge c[e] -> c[e + 1] counted from c[e], shared with the twin triangle.
    auto edgePoint = [&](int e, int s) {
      const int a = c[e], b = c[(e + 1) % 3], lo = std::min(a, b), hi = std::max(a, b);
      int& first = edgeFirst[edgeIndex(lo, hi)];
      if (first < 0) {
        first = static_cast<int>(points.size());
        for (int t = 1; t < k; ++t) {
          const double w = double(t) / k;
          points.push_back((1 - w) * points[lo] + w * points[hi]);
          Vec3 bc = Vec3::Zero();
          for (int q = 0; q < 3; ++q) bc(q) = c[q] == lo ? 1 - w : c[q] == hi ? w : 0;
          where.push_back({f, bc});
        }
      }
      return first + (a < b ? s : k - s) - 1;
    };
    for (int j = 0; j <= k; ++j)
      for (int i = 0; i + j <= k; ++i) {
        int id;
        if (i == 0 && j == 0) id = c[0];
        else if (i == k) id = c[1];
        else if (j == k) id = c[2];
        else if (j == 0) id = edgePoint(0, i);
        else if (i + j == k) id = edgePoint(1, j);
        else if (i == 0) id = edgePoint(2, k - j);
        else id = inner(i, j);
        at(i, j) = id;
      }
    for (int j = 0; j < k; ++j)
      for (int i = 0; i + j < k; ++i) {
        tri.insert(tri.end(), {at(i, j), at(i + 1, j), at(i, j + 1)});
        source.push_back(f);
        if (i + j + 1 < k) tri.insert(tri.end(), {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)}), source.push_back(f);
      }
  }
  TriMesh out;
  out.V.resize(static_cast<int>(points.size()), 3);
  for (int v = 0; v < static_cast<int>(points.size()); ++v) out.V.row(v) = points[v].transpose();
  out.F.resize(static_cast<int>(tri.size() / 3), 3);
  for (int f = 0; f < out.F.rows(); ++f)
    for (int q = 0; q < 3; ++q) out.F(f, q) = tri[3 * f + q];
  return out;
}


// `fine` (a refinement of `mesh`, each triangle in the triangle `source` of mesh) refined until no edge is longer than `edge`: every longer edge split at its midpoint, each triangle cut by
// the pattern of its split edges (one: two triangles, two: three, three: four), again until none is left (a
// conforming refinement, where a uniform k x k split would leave the longest triangles of a graded mesh
// under-sampled). `where` gets, per vertex, a triangle of `mesh` holding it and its barycentric coordinates there.
TriMesh refine(const TriMesh& mesh, const TriMesh& fine, std::vector<int> source, double edge, std::size_t maxTriangles,
               std::vector<std::pair<int, Vec3>>& where) {
  const int nv0 = static_cast<int>(fine.V.rows()), nf0 = static_cast<int>(fine.F.rows());
  std::vector<Vec3> points(nv0);
  for (int v = 0; v < nv0; ++v) points[v] = fine.V.row(v).transpose();
  std::vector<std::array<int, 3>> tris(nf0);
  for (int f = 0; f < nf0; ++f) tris[f] = {fine.F(f, 0), fine.F(f, 1), fine.F(f, 2)};
  // Barycentric coordinates of vertex v in source triangle s (v lies on it: a corner, or on its edges or inside).
  auto baryIn = [&](int v, int s) -> Vec3 {
    if (where[v].first == s) return where[v].second;
    for (int c = 0; c < 3; ++c)
      if (mesh.F(s, c) == v) {
        Vec3 b = Vec3::Zero();
        b(c) = 1;
        return b;
      }
    const Vec3 a = mesh.V.row(mesh.F(s, 0)), e1 = Vec3(mesh.V.row(mesh.F(s, 1))) - a, e2 = Vec3(mesh.V.row(mesh.F(s, 2))) - a;
    const Vec3 d = points[v] - a;
    const double g11 = dot(e1, e1), g12 = dot(e1, e2), g22 = dot(e2, e2), det = g11 * g22 - g12 * g12;
    const double b1 = det > 0 ? (g22 * dot(e1, d) - g12 * dot(e2, d)) / det : 0.0;
    const double b2 = det > 0 ? (g11 * dot(e2, d) - g12 * dot(e1, d)) / det : 0.0;
    return Vec3(1 - b1 - b2, b1, b2);
  };
  const double limit = edge * edge;
  for (int pass = 0; pass < 32; ++pass) {
    auto key = [](int a, int b) { return (std::uint64_t(std::min(a, b)) << 32) | std::uint64_t(std::max(a, b)); };
    // The long edges' half-edges (3 t + c) in order, with their edges' keys; each edge's midpoint is made where its
    // first half-edge comes (the one of least index: first among its key's once sorted), and its twin's shares it.
    // (A hash map of the edges took a third of the field mesh's time at 10k faces.)
    std::vector<std::pair<std::uint64_t, int>> longEdges;
    for (std::size_t t = 0; t < tris.size(); ++t)
      for (int c = 0; c < 3; ++c) {
        const int a = tris[t][c], b = tris[t][(c + 1) % 3];
        if ((points[a] - points[b]).squaredNorm() > limit) longEdges.push_back({key(a, b), static_cast<int>(3 * t + c)});
      }
    if (longEdges.empty()) break;
    // Each edge's midpoint id, by the place of its half-edges in longEdges: the edges' runs of half-edges once sorted
    // by key, the points made in the order of the runs' first half-edges.
    std::vector<int> idOf(longEdges.size(), -1);
    {
      std::vector<std::pair<std::uint64_t, int>> byKey(longEdges.size());  // (key, place in longEdges)
      for (std::size_t i = 0; i < longEdges.size(); ++i) byKey[i] = {longEdges[i].first, static_cast<int>(i)};
      std::sort(byKey.begin(), byKey.end());
      std::vector<std::pair<int, int>> firsts;  // (place of an edge's first half-edge, start of its run in byKey)
      for (std::size_t i = 0; i < byKey.size(); ++i)
        if (i == 0 || byKey[i].first != byKey[i - 1].first) firsts.push_back({byKey[i].second, static_cast<int>(i)});
      std::sort(firsts.begin(), firsts.end());
      for (const auto& [place, run] : firsts) {
        const int half = longEdges[place].second;
        const std::size_t t = half / 3;
        const int a = tris[t][half % 3], b = tris[t][(half % 3 + 1) % 3], id = static_cast<int>(points.size());
        points.push_back(0.5 * (points[a] + points[b]));
        where.push_back({source[t], 0.5 * (baryIn(a, source[t]) + baryIn(b, source[t]))});
        for (std::size_t i = run; i < byKey.size() && byKey[i].first == byKey[run].first; ++i) idOf[byKey[i].second] = id;
      }
    }
    std::size_t nextLong = 0;  // the triangles' half-edges come in order below, and longEdges holds them in order
    std::vector<std::array<int, 3>> next;
    std::vector<int> nextSource;
    next.reserve(tris.size() * 3);
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const auto& T = tris[t];
      int m[3];
      int split = 0;
      for (int c = 0; c < 3; ++c) {
        const bool isLong = nextLong < longEdges.size() && longEdges[nextLong].second == static_cast<int>(3 * t + c);
        m[c] = isLong ? idOf[nextLong++] : -1;
        split += m[c] >= 0;
      }
      auto add = [&](int a, int b, int c) { next.push_back({a, b, c}), nextSource.push_back(source[t]); };
      if (split == 0) {
        add(T[0], T[1], T[2]);
      } else if (split == 3) {
        add(T[0], m[0], m[2]), add(m[0], T[1], m[1]), add(m[2], m[1], T[2]), add(m[0], m[1], m[2]);
      } else {
        // Rotate so that edge 0 (T0 -> T1) is split; then edge 1 or 2 may be too.
        int r = 0;
        while (m[r] < 0) ++r;
        const int a = T[r], b = T[(r + 1) % 3], c = T[(r + 2) % 3];
        const int mab = m[r], mbc = m[(r + 1) % 3], mca = m[(r + 2) % 3];
        if (split == 1) {
          add(a, mab, c), add(mab, b, c);
        } else if (mbc >= 0) {
          add(a, mab, c), add(mab, b, mbc), add(mab, mbc, c);
        } else {  // mca
          add(a, mab, mca), add(mab, b, c), add(mab, c, mca);
        }
      }
    }
    tris.swap(next);
    source.swap(nextSource);
    if (tris.size() > maxTriangles) break;
  }
  TriMesh out;
  out.V.resize(static_cast<int>(points.size()), 3);
  for (int v = 0; v < static_cast<int>(points.size()); ++v) out.V.row(v) = points[v].transpose();
  out.F.resize(static_cast<int>(tris.size()), 3);
  for (int f = 0; f < out.F.rows(); ++f)
    for (int c = 0; c < 3; ++c) out.F(f, c) = tris[f][c];
  return out;
}

// A boundary loop's vertices of the coarse mesh (ids under `coarse`), in order: the ends of its coarse edges.
std::vector<int> coarseCorners(const std::vector<int>& loop, int coarse) {
  std::vector<int> corners;
  for (int v : loop)
    if (v < coarse) corners.push_back(v);
  return corners;
}

// Whether a boundary loop zigzags: among its coarse corners, the share of consecutive pairs that turn by more than
// kToothTurn each and in opposite senses is over kZigzagShare.
bool zigzags(const FieldMesh& m, const std::vector<int>& loop, int coarse) {
  const std::vector<int> corners = coarseCorners(loop, coarse);
  const int n = static_cast<int>(corners.size());
  if (n < 6) return false;
  std::vector<int> sense(n, 0);
  for (int i = 0; i < n; ++i) {
    const int a = corners[(i + n - 1) % n], b = corners[i], c = corners[(i + 1) % n];
    const Vec3 in = m.point(b) - m.point(a), out = m.point(c) - m.point(b);
    const double lengths = norm(in) * norm(out);
    if (!(lengths > 0)) continue;
    const double sine = dot(cross(in, out), m.frame[b].n) / lengths;
    if (std::abs(sine) > kToothTurn) sense[i] = sine > 0 ? 1 : -1;
  }
  int alternating = 0;
  for (int i = 0; i < n; ++i) alternating += sense[i] * sense[(i + 1) % n] < 0;
  return alternating > kZigzagShare * n;
}

// The half-width of the window a zigzag loop's direction is taken over (see kToothWindow), for field-mesh edges of
// `edge`: the coarse mesh's boundary edges are the steps between the loops' consecutive coarse corners.
double zigzagWindow(const FieldMesh& m, int coarse, double edge) {
  std::vector<double> lengths;
  for (const std::vector<int>& loop : m.loops) {
    const std::vector<int> corners = coarseCorners(loop, coarse);
    for (std::size_t i = 0; i < corners.size(); ++i)
      lengths.push_back((m.coarse.V.row(corners[i]) - m.coarse.V.row(corners[(i + 1) % corners.size()])).norm());
  }
  double median = 0;
  if (!lengths.empty()) {
    std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
    median = lengths[lengths.size() / 2];
  }
  return std::max(kTangentWindow * edge, std::min(kToothWindow * median, kLongestWindow * edge));
}

}  // namespace

HalfEdges::HalfEdges(const Triangles& F, int vertices) : start_(vertices + 1, 0), ends_(3 * static_cast<std::size_t>(F.rows())) {
  const int nf = static_cast<int>(F.rows());
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) ++start_[F(f, c) + 1];
  for (int v = 0; v < vertices; ++v) start_[v + 1] += start_[v];
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) ends_[fill[F(f, c)]++] = F(f, (c + 1) % 3);
  for (int v = 0; v < vertices; ++v) std::sort(ends_.begin() + start_[v], ends_.begin() + start_[v + 1]);
}

bool HalfEdges::has(int a, int b) const {
  return std::binary_search(ends_.begin() + start_[a], ends_.begin() + start_[a + 1], b);
}

namespace {

void buildTopology(FieldMesh& m, double fieldEdge, int coarse) {
  const int nv = m.vertexCount(), nf = static_cast<int>(m.F.rows());
  // Adjacency.
  std::vector<int> count(nv + 1, 0);
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) count[m.F(f, c) + 1] += 2;
  std::vector<int> start(nv + 1, 0);
  for (int v = 0; v < nv; ++v) start[v + 1] = start[v] + count[v + 1];
  std::vector<int> fill(start.begin(), start.end() - 1), all(start.back());
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = m.F(f, c), b = m.F(f, (c + 1) % 3);
      all[fill[a]++] = b;
      all[fill[b]++] = a;
    }
  m.start.assign(nv + 1, 0);
  m.adjacent.clear();
  for (int v = 0; v < nv; ++v) {
    std::sort(all.begin() + start[v], all.begin() + start[v + 1]);
    const auto end = std::unique(all.begin() + start[v], all.begin() + start[v + 1]);
    m.adjacent.insert(m.adjacent.end(), all.begin() + start[v], end);
    m.start[v + 1] = static_cast<int>(m.adjacent.size());
  }
  // Boundary: half-edges a -> b with no b -> a. Their next one starts at b (one per boundary vertex: manifold).
  const HalfEdges halfEdges(m.F, nv);
  std::vector<int> next(nv, -1);
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = m.F(f, c), b = m.F(f, (c + 1) % 3);
      if (!halfEdges.has(b, a)) next[a] = b;
    }
  m.boundary.assign(nv, 0);
  m.loops.clear();
  for (int v = 0; v < nv; ++v) {
    if (next[v] < 0 || m.boundary[v]) continue;
    std::vector<int> loop;
    for (int w = v; w >= 0 && !m.boundary[w]; w = next[w]) m.boundary[w] = 1, loop.push_back(w);
    m.loops.push_back(std::move(loop));
  }
  // The boundary's direction at each of its vertices: the chord through its two neighbours on the loop; on a loop
  // that zigzags at the scale of its coarse mesh's triangles (a lattice cut off along a curve: zigzags()), over a
  // window of zigzagWindow() on either side instead — the edge vectors of the loop weighted by a tent of that
  // half-width about the vertex (by arc length) — so that it gives the direction of the curve and not of each
  // tooth, which the field, held to it, would otherwise turn by up to 30 degrees from one boundary vertex to the
  // next (the uploaded bumps at 10k faces had 131 singular points, nearly all in pairs along the boundary; now 26).
  // The window stops at the loop's corners — where the chords kCornerWindow windows long behind and ahead of a
  // vertex turn by more than 40 degrees (kCornerCos), most there within as far — and a corner takes the chord.
  m.boundaryTangent.assign(nv, Vec3::Zero());
  double window = -1;  // zigzagWindow's, taken at the first loop that zigzags
  for (const std::vector<int>& loop : m.loops) {
    const int n = static_cast<int>(loop.size());
    if (!zigzags(m, loop, coarse)) {
      for (int i = 0; i < n; ++i) {
        const Vec3 d = m.point(loop[(i + 1) % n]) - m.point(loop[(i + n - 1) % n]);
        m.boundaryTangent[loop[i]] = normalized(tangential(d, m.frame[loop[i]].n));
      }
      continue;
    }
    std::vector<Vec3> edge(n);
    std::vector<double> at(n + 1, 0.0);  // arc length at each vertex of the loop, and its perimeter at n
    for (int i = 0; i < n; ++i) {
      edge[i] = m.point(loop[(i + 1) % n]) - m.point(loop[i]);
      at[i + 1] = at[i] + norm(edge[i]);
    }
    if (window < 0) window = zigzagWindow(m, coarse, fieldEdge);
    const double perimeter = at[n], w = std::min(window, 0.25 * perimeter);
    // Arc length from vertex i forward to vertex j.
    auto ahead = [&](int i, int j) { return j >= i ? at[j] - at[i] : perimeter - at[i] + at[j]; };
    // The point of the loop at arc length s past vertex i (s may be negative).
    auto pointAt = [&](int i, double s) {
      int j = i;
      if (s >= 0) {
        for (int k = 0; k < n; ++k, j = (j + 1) % n) {
          const double e = norm(edge[j]), from = ahead(i, j);
          if (from + e >= s) return Vec3(m.point(loop[j]) + edge[j] * ((s - from) / std::max(e, 1e-300)));
        }
      } else {
        for (int k = 0; k < n; ++k) {
          const int p = (j - 1 + n) % n;
          const double e = norm(edge[p]), to = ahead(j, i);
          if (to + e >= -s) return Vec3(m.point(loop[j]) - edge[p] * ((-s - to) / std::max(e, 1e-300)));
          j = p;
        }
      }
      return m.point(loop[i]);
    };
    std::vector<double> turn(n, 0.0);
    for (int i = 0; i < n; ++i) {
      const Vec3 x = m.point(loop[i]), behind = x - pointAt(i, -kCornerWindow * w), forward = pointAt(i, kCornerWindow * w) - x;
      const double b = norm(behind), f = norm(forward);
      turn[i] = b > 0 && f > 0 ? 1 - dot(behind, forward) / (b * f) : 0.0;  // 1 - cos of the turn
    }
    std::vector<char> corner(n, 0);
    for (int i = 0; i < n; ++i) {
      if (!(turn[i] > 1 - kCornerCos)) continue;
      bool most = true;
      for (int k = 1; k < n && most && ahead(i, (i + k) % n) <= kCornerWindow * w; ++k) most = turn[(i + k) % n] < turn[i];
      for (int k = 1; k < n && most && ahead((i - k + n) % n, i) <= kCornerWindow * w; ++k) most = turn[(i - k + n) % n] <= turn[i];
      corner[i] = most;
    }
    for (int i = 0; i < n; ++i) {
      Vec3 d = edge[i] + edge[(i + n - 1) % n];
      if (!corner[i]) {
        d = Vec3::Zero();
        // The edges ahead (j = i, i+1, ...) and behind (i-1, i-2, ...) whose middles lie within the window, up to a corner.
        for (int k = 0; k < n; ++k) {
          const int j = (i + k) % n;
          const double weight = 1 - (ahead(i, j) + 0.5 * norm(edge[j])) / std::max(w, 1e-300);
          if (k > 0 && (weight <= 0 || corner[j])) break;
          d += std::max(weight, 1e-3) * edge[j];
        }
        for (int k = 1; k < n; ++k) {
          const int j = (i - k + n) % n;
          const double weight = 1 - (ahead((j + 1) % n, i) + 0.5 * norm(edge[j])) / std::max(w, 1e-300);
          if (k > 1 && (weight <= 0 || corner[(j + 1) % n])) break;
          d += std::max(weight, 1e-3) * edge[j];
        }
      }
      m.boundaryTangent[loop[i]] = normalized(tangential(d, m.frame[loop[i]].n));
    }
  }
  // Components.
  m.component.assign(nv, -1);
  m.components = 0;
  std::vector<int> stack;
  for (int v = 0; v < nv; ++v) {
    if (m.component[v] >= 0) continue;
    m.component[v] = m.components;
    stack.push_back(v);
    while (!stack.empty()) {
      const int w = stack.back();
      stack.pop_back();
      for (int i = m.start[w]; i < m.start[w + 1]; ++i)
        if (m.component[m.adjacent[i]] < 0) m.component[m.adjacent[i]] = m.components, stack.push_back(m.adjacent[i]);
    }
    ++m.components;
  }
  // Areas and the mean edge.
  m.area.assign(nv, 0.0);
  double edges = 0;
  for (int f = 0; f < nf; ++f) {
    const Vec3 a = m.point(m.F(f, 0)), b = m.point(m.F(f, 1)), c = m.point(m.F(f, 2));
    const double A = 0.5 * norm(cross(b - a, c - a));
    for (int q = 0; q < 3; ++q) m.area[m.F(f, q)] += A / 3;
    edges += norm(b - a) + norm(c - b) + norm(a - c);
  }
  m.edgeMean = nf > 0 ? edges / (3.0 * nf) : 0.0;
}

}  // namespace

double verticesAt(double area, double edge) { return 2 * area / (std::sqrt(3.0) * edge * edge); }

int fieldSplit(double median, double edge) {
  const double k = std::ceil(median / edge - 0.2);
  return k >= 1 && k < 1e6 ? static_cast<int>(k) : 1;
}

FieldMesh fieldMesh(const Surface& surface, double edge, double anisotropy, double curvatureFloor, const CancelFlag* cancel) {
  FieldMesh m;
  std::vector<LocalGeometry> geo;
  if (const auto* mesh = dynamic_cast<const MeshSurface*>(&surface)) {
    // The upload split k x k (k from the median edge, or `given` where positive), its longer edges bisected: `base`
    // is the mesh split.
    auto sampled = [&](const TriMesh& base, int given, TriMesh& fine) {
      // Nor finer than kAreaSplitMargin times the triangles of the surface's area at `edge` need: a mesh of needles,
      // whose median edge is their length, was split into a hundred times as many (a two-triangle needle at 32
      // faces: 14k field-mesh vertices and 1.6 s to refuse it); the long edges are bisected below all the same.
      const double needed = kAreaSplitMargin * base.area() / (std::sqrt(3.0) / 4 * edge * edge);
      const double most = std::floor(std::sqrt(std::min(double(kMaxFieldTriangles), std::max(1.0, needed)) /
                                               std::max<double>(1.0, double(base.F.rows()))));
      const int k = given > 0 ? given : std::clamp(fieldSplit(base.medianEdgeLength(), edge), 1, static_cast<int>(std::max(1.0, most)));
      std::vector<int> source;
      m.where.clear();
      const TriMesh split = global::split(base, k, m.where, source);
      fine = refine(base, split, std::move(source), kLongEdge * edge, kMaxFieldTriangles, m.where);
    };
    TriMesh fine, thin;
    sampled(mesh->mesh(), 0, fine);
    // Where that leaves many more vertices than the field needs (an upload finer than the cell, or one of long and
    // short edges mixed, whose long ones the bisection splits: a marching-tetrahedra mesh), the upload is remeshed to
    // the field's edge or a whole multiple of it (thinnedSplit; thinned: `kept` its vertices' ids in the upload) and
    // split again, that many times.
    const double wanted = verticesAt(mesh->mesh().area(), edge);
    std::vector<int> kept;
    const bool thinning = double(fine.V.rows()) > kThinAbove * wanted;
    // What is remeshed: the upload, also where it was refined into a smooth surface (MeshSurface::refined: its first
    // vertices are the upload's, moved onto the blend), its points then found on that surface. The refinement keeps an uneven upload's
    // long edges among short ones: the generated genus 1 (36k vertices) refined 3 x 3 at 100k faces laid its field on
    // 1.9M field-mesh vertices, 3.6 times those its area needs (27.5 s, 1.6 GB).
    const MeshSurface::Refinement& from = mesh->refinement();
    TriMesh refinedFrom;
    if (thinning && from.k > 1) refinedFrom.V = mesh->mesh().V.topRows(from.vertices), refinedFrom.F = from.F;
    const TriMesh& upload = from.k > 1 && thinning ? refinedFrom : mesh->mesh();
    // An upload vertex's own geometry; a point split off an upload triangle, by its place there; a point of the
    // remeshed upload that moved or was split off, the surface's at its closest point.
    auto place = [&](const TriMesh& base) {
      geo.resize(fine.V.rows());
      parallelRanges(static_cast<int>(fine.V.rows()), kPointsPerThread, [&](int begin, int end) {
        for (int v = begin; v < end; ++v) {
          const int upload = v >= base.V.rows() ? -1 : thinning ? kept[v] : v;
          geo[v] = upload >= 0 ? mesh->vertexGeometry(upload)
                   : thinning  ? mesh->closestPoint(fine.V.row(v).transpose())
                               : mesh->geometryInTriangle(m.where[v].first, m.where[v].second);
        }
      });
    };
    if (thinning) {
      // At thinnedSplit field-mesh edges, fewer where the split points fold over (untangleSplit).
      // The upload's edge: its median, or its triangles' size where smaller (a needle's median edge is its length).
      const double own = std::min(upload.medianEdgeLength(), upload.triangleSize());
      for (int times = thinnedSplit(own, edge);; --times) {
        thin = thinned(surface, upload, times * edge, kept, cancel);
        sampled(thin, times, fine);
        place(thin);
        m.thinnedFrom = static_cast<int>(upload.V.rows());
        m.thinnedTo = static_cast<int>(thin.V.rows());
        m.thinnedSplit = times;
        if (times == 1 || untangleSplit(*mesh, thin, fine, m.where, kept, geo)) break;
      }
    } else {
      place(mesh->mesh());
    }
    const TriMesh& base = thinning ? thin : mesh->mesh();
    m.coarse = base;
    // A refinement of a coarser upload (refined(k), k x k per triangle, in order): that upload is the coarse
    // mesh, each field-mesh vertex's place carried from the refined triangle into its upload triangle.
    if (!thinning && from.k > 1 && from.F.rows() * from.k * from.k == base.F.rows()) {
      const int r = from.k;
      // Per triangle of one split, its corners' barycentric coordinates in the triangle split (refined()'s order).
      std::vector<std::array<Vec3, 3>> corners;
      auto grid = [r](int i, int j) { return Vec3(double(r - i - j) / r, double(i) / r, double(j) / r); };
      for (int j = 0; j < r; ++j)
        for (int i = 0; i + j < r; ++i) {
          corners.push_back({grid(i, j), grid(i + 1, j), grid(i, j + 1)});
          if (i + j + 1 < r) corners.push_back({grid(i + 1, j), grid(i + 1, j + 1), grid(i, j + 1)});
        }
      for (std::pair<int, Vec3>& w : m.where) {
        if (w.first < 0) continue;
        const std::array<Vec3, 3>& c = corners[static_cast<std::size_t>(w.first % (r * r))];
        w = {w.first / (r * r), w.second(0) * c[0] + w.second(1) * c[1] + w.second(2) * c[2]};
      }
      m.coarse.V = base.V.topRows(from.vertices);
      m.coarse.F = from.F;
    }
    m.V = std::move(fine.V);
    m.F = std::move(fine.F);
  } else if (const auto* parametric = dynamic_cast<const ParametricSurface*>(&surface)) {
    // The parameter lattice at kCoarseSplit edges, split k x k: its points in parameter space (periodic directions
    // unwrapped about each triangle's first corner), so that their geometry is exact.
    Triangulation t = latticeTriangulation(*parametric, kCoarseSplit * edge, LatticeRows::Auto, true);
    const ParametricSurface::Domain d = parametric->domain();
    std::vector<int> source;
    const TriMesh fine = global::split(t.mesh, static_cast<int>(kCoarseSplit), m.where, source);
    geo.resize(fine.V.rows());
    const int nc = static_cast<int>(t.mesh.V.rows());
    parallelRanges(static_cast<int>(fine.V.rows()), kPointsPerThread, [&](int begin, int end) {
      for (int v = begin; v < end; ++v) {
        if (v < nc) {
          geo[v] = parametric->geometryAt(t.uv[v].x(), t.uv[v].y());
          continue;
        }
        const auto& [f, b] = m.where[v];
        const Vec2 first = t.uv[t.mesh.F(f, 0)];
        Vec2 uv = Vec2::Zero();
        for (int c = 0; c < 3; ++c) {
          Vec2 corner = t.uv[t.mesh.F(f, c)];
          if (d.periodicU && std::abs(corner.x() - first.x()) > 0.5 * (d.u1 - d.u0))
            corner.x() += corner.x() < first.x() ? d.u1 - d.u0 : d.u0 - d.u1;
          if (d.periodicV && std::abs(corner.y() - first.y()) > 0.5 * (d.v1 - d.v0))
            corner.y() += corner.y() < first.y() ? d.v1 - d.v0 : d.v0 - d.v1;
          uv += b(c) * corner;
        }
        uv = parametric->normalize(uv);
        geo[v] = parametric->geometryAt(uv.x(), uv.y());
      }
    });
    m.coarse = t.mesh;
    m.V = fine.V;
    m.F = fine.F;
  } else {
    throw Error(ErrorCode::InvalidParameter, "the global method needs an uploaded mesh or an analytic surface");
  }
  checkCancel(cancel);
  const int nv = m.vertexCount();
  if (nv == 0 || m.F.rows() == 0) throw Error(ErrorCode::CannotTile, "the surface has no triangles to lay a field on");
  for (int v = 0; v < nv; ++v) m.V.row(v) = geo[v].point.transpose();

  // The Dupin metric, bounded: the frame's axes scale as the square roots of |k| + eps, where eps is
  // `curvatureFloor` (by default a quarter) of the surface's median largest |curvature| (flat parts and parabolic
  // curves: the metric tends to the isotropic one there instead of degenerating), and their ratio is at most
  // `anisotropy`.
  m.curvature.resize(nv);
  for (int v = 0; v < nv; ++v) m.curvature[v] = geo[v].largestCurvature();
  std::vector<double> sorted = m.curvature;
  std::nth_element(sorted.begin(), sorted.begin() + nv / 2, sorted.end());
  const double typical = sorted[nv / 2];
  const double eps = curvatureFloor * typical;
  m.frame.resize(nv);
  m.alignWeight.assign(nv, 0.0);
  m.principalWeight.assign(nv, 0.0);
  for (int v = 0; v < nv; ++v) {
    const LocalGeometry& g = geo[v];
    Frame& fr = m.frame[v];
    fr.n = normalized(g.normal);
    const bool firstFlatter = std::abs(g.k1) <= std::abs(g.k2);
    fr.t = normalized(tangential(firstFlatter ? g.d1 : g.d2, fr.n));
    if (!(norm(fr.t) > 0.5)) fr.t = normalized(tangential(std::abs(fr.n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY(), fr.n));
    const double flat = std::min(std::abs(g.k1), std::abs(g.k2)), steep = std::max(std::abs(g.k1), std::abs(g.k2));
    const double ratio = eps > 0 ? std::sqrt((steep + eps) / (flat + eps)) : 1.0;  // >= 1: the Dupin frame's aspect
    fr.sigma = 1 / std::sqrt(std::min(ratio, anisotropy));
    // Where the indicatrix is elongated beyond the bound, an equilateral triangle of the bounded frame is valid in
    // any orientation only up to a remaining aspect of sqrt 3 (Props. 4, 5); with an edge along the flatter
    // direction, at any aspect. So the field is held to that direction from kAlignFrom on, fully from kAlignFull.
    // The aspect the bounded frame leaves, against the indicatrix itself (nearly unregularized: Props. 4 and 5 judge
    // by the true curvature, and near a parabolic curve its aspect grows without bound).
    const double aspect = eps > 0 ? std::sqrt((steep + kAlignEps * eps) / (flat + kAlignEps * eps)) : 1.0;
    const double beyond = aspect / std::min(ratio, anisotropy);
    m.alignWeight[v] = std::clamp((beyond - kAlignFrom) / (kAlignFull - kAlignFrom), 0.0, 1.0);
    m.principalWeight[v] = std::clamp((aspect - kPrincipalFrom) / (kPrincipalFull - kPrincipalFrom), 0.0, 1.0);
  }
  buildTopology(m, edge, static_cast<int>(m.coarse.V.rows()));
  return m;
}

}  // namespace phex::global
