// phex — an upload remeshed for the global method's field mesh: near the field's edge (thinned), at a whole number of
// field-mesh edges near its own (thinnedSplit), and the points split off it kept from folding over (untangleSplit).
#include <algorithm>
#include <array>
#include <cmath>

#include "global.hpp"
#include "phex/error.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/parallel.hpp"

namespace phex::global {
namespace {

// thinned(): kThinRounds rounds of splitting interior edges over kSplitAbove field-mesh edges, collapsing edges under
// kCollapseBelow while the edges made stay under kCollapsedMost and no triangle turns by more than kCollapseTurn
// degrees, flipping towards valence 6, and relaxing. The closed surfaces of genus 1-3 generated for the tests
// (marching tetrahedra, 37-59k vertices, long edges among short ones) at 3000 and 5000 faces: hexagons 93.3 / 94.1,
// 84.4 / 89.6 and 78.1 / 82.9 % -> 97.1 / 95.4, 90.6 / 92.4 and 90.4 / 92.2 %; the genus 3 at 1000 faces now planar
// (it stalled at 4e-2).
constexpr double kCollapseBelow = 0.9, kCollapsedMost = 1.3, kCollapseTurn = 30.0;
constexpr int kThinRounds = 3, kCollapseBuckets = 64;
constexpr double kSplitAbove = 1.3, kSplitMost = 2.0;
// Sweeps of untangleSplit at each of its steps (before the remeshing falls back to one field-mesh edge less).
constexpr int kUntangleSweeps = 5;
constexpr int kSplitPasses = 20;

}  // namespace

// An uneven upload is remeshed at this many field-mesh edges, its own edge over `edge` rounded (at least 1), and
// the remeshed mesh split as many times: an upload coarser than the field mesh is regularized at about its own edge
// rather than split edge by edge down to the field's (serial, each split point found on the surface). The generated
// genus 1-3 (marching tetrahedra, 37-59k vertices, median edges 1.7-3.4 field-mesh edges from 20k faces on) at 20k,
// 30k, 50k and 100k faces, remeshed at the field's edge against this: 11 runs 6.5-34.4 s and 339-1182 MB against
// 3.2-16.1 s and 186-582 MB (the genus 2 at 100k 32.8 -> 14.3 s, 1174 -> 555 MB), hexagons 93.63 -> 93.73 % on
// average (within 0.9 points either way), faces cut 902 -> 678 in all; below a median of 1.5 field-mesh edges (the
// genus set at up to 10k faces, the shared models at up to 10k) the same meshes.
int thinnedSplit(double median, double edge) {
  const double k = std::floor(median / edge + 0.5);
  return k >= 1 && k < 1e6 ? static_cast<int>(k) : 1;
}

// An upload finer or more uneven than the field mesh needs, remeshed to about the field mesh's edge (isotropic
// remeshing, kThinRounds rounds): interior edges over kSplitAbove field-mesh edges split at their midpoint on the
// surface where they are the longest of both their triangles; edges under kCollapseBelow collapse, shortest first, the
// two ends merging at their midpoint (an end on the boundary stays where it is; two on the boundary do not merge, so
// the boundary loops are the upload's), while the edges made stay under kCollapsedMost, no triangle around turns by
// more than kCollapseTurn and the two ends share exactly two neighbours (the link condition: the surface's topology
// stays); then edges flip where that brings valences nearer 6 (4 on the boundary), and interior vertices move to
// their neighbours' centroid within the tangent plane, onto the surface, where no triangle turns by more than
// kCollapseTurn. `kept` gets, per vertex left, its id in the upload where it did not move, else -1.
TriMesh thinned(const Surface& surface, const TriMesh& mesh, double edge, std::vector<int>& kept, const CancelFlag* cancel) {
  int nv = static_cast<int>(mesh.V.rows()), nf = static_cast<int>(mesh.F.rows());  // grow with the splits
  std::vector<std::array<int, 3>> tris(nf);
  std::vector<char> alive(nf, 1), removed(nv, 0), boundary(nv, 0), moved(nv, 0);
  std::vector<int> version(nv, 0);
  std::vector<Vec3> points(nv);
  for (int v = 0; v < nv; ++v) points[v] = mesh.V.row(v).transpose();
  std::vector<std::vector<int>> at(nv);  // each vertex's triangles (alive or not: filtered when read)
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) tris[f][c] = mesh.F(f, c), at[mesh.F(f, c)].push_back(f);
  {
    const HalfEdges half(mesh.F, nv);
    for (int f = 0; f < nf; ++f)
      for (int c = 0; c < 3; ++c)
        if (!half.has(mesh.F(f, (c + 1) % 3), mesh.F(f, c))) boundary[mesh.F(f, c)] = boundary[mesh.F(f, (c + 1) % 3)] = 1;
  }
  // The triangle's normal (times twice its area) with vertex `which` at p.
  auto normalOf = [&](const std::array<int, 3>& t, int which, const Vec3& p) {
    const Vec3 a = t[0] == which ? p : points[t[0]], b = t[1] == which ? p : points[t[1]], c = t[2] == which ? p : points[t[2]];
    return cross(b - a, c - a);
  };
  const double minArea = 1e-12 * edge * edge, turn = std::cos(kCollapseTurn * 3.141592653589793 / 180);
  auto turnsLittle = [&](const Vec3& before, const Vec3& after) {
    const double a = norm(before), b = norm(after);
    return b > minArea && dot(before, after) > turn * a * b;
  };
  std::vector<int> ringU, ringV;
  auto neighbours = [&](int v, std::vector<int>& out) {
    out.clear();
    std::vector<int>& list = at[v];
    list.erase(std::remove_if(list.begin(), list.end(), [&](int f) { return !alive[f]; }), list.end());
    for (int f : list)
      for (int c = 0; c < 3; ++c)
        if (tris[f][c] != v) out.push_back(tris[f][c]);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  };
  // The other triangle on edge a -> b of triangle f (b -> a in it; -1 on the boundary), `y` its third corner.
  auto across = [&](int f, int a, int b, int& y) {
    int g = -1;
    for (int h : at[b]) {
      if (!alive[h] || h == f) continue;
      for (int k = 0; k < 3; ++k)
        if (tris[h][k] == b && tris[h][(k + 1) % 3] == a) g = h, y = tris[h][(k + 2) % 3];
    }
    return g;
  };
  const double below = kCollapseBelow * edge, most = kCollapsedMost * edge;
  // u and v merged into v at p, where the checks above allow.
  auto collapse = [&](int u, int v) {
    if (boundary[u]) std::swap(u, v);
    if (boundary[u]) return false;
    neighbours(u, ringU);
    if (!std::binary_search(ringU.begin(), ringU.end(), v)) return false;
    neighbours(v, ringV);
    int common = 0;
    for (int w : ringU) common += std::binary_search(ringV.begin(), ringV.end(), w);
    if (common != 2) return false;
    const Vec3 p = boundary[v] ? points[v] : Vec3(0.5 * (points[u] + points[v]));  // onto the surface when relaxed
    for (const std::vector<int>* ring : {&ringU, &ringV})
      for (int w : *ring)
        if (w != u && w != v && (points[w] - p).norm() > most) return false;
    for (int x : {u, v})
      for (int f : at[x]) {
        const std::array<int, 3>& t = tris[f];
        const bool both = (t[0] == u || t[1] == u || t[2] == u) && (t[0] == v || t[1] == v || t[2] == v);
        if (!both && !turnsLittle(normalOf(t, -1, p), normalOf(t, x, p))) return false;
      }
    for (int f : at[u]) {
      std::array<int, 3>& t = tris[f];
      if (t[0] == v || t[1] == v || t[2] == v) {
        alive[f] = 0;
        continue;
      }
      for (int& c : t)
        if (c == u) c = v;
      at[v].push_back(f);
    }
    at[u].clear();
    removed[u] = 1;
    if (points[v] != p) points[v] = p, moved[v] = 1;
    ++version[v];
    return true;
  };
  // Edges to collapse, shortest first by buckets of kCollapseBuckets (a binary heap of a 500k-triangle upload's edges
  // took a fifth of the run): within a bucket in the order they came; an entry whose ends moved or went is stale.
  struct Entry {
    int a, b, va, vb;
  };
  std::vector<std::vector<Entry>> buckets(kCollapseBuckets);
  auto bucketOf = [&](double length) { return std::min(kCollapseBuckets - 1, static_cast<int>(length / below * kCollapseBuckets)); };
  long steps = 0;
  auto collapseShort = [&]() {
    for (std::vector<Entry>& b : buckets) b.clear();
    for (int f = 0; f < nf; ++f)
      if (alive[f])
        for (int c = 0; c < 3; ++c) {
          const int a = tris[f][c], b = tris[f][(c + 1) % 3];
          const double length = (points[a] - points[b]).norm();
          if (a < b && length < below) buckets[bucketOf(length)].push_back({a, b, version[a], version[b]});
        }
    std::vector<std::size_t> next(kCollapseBuckets, 0);  // each bucket's first entry not yet taken
    for (int bucket = 0;;) {
      while (bucket < kCollapseBuckets && next[bucket] == buckets[bucket].size()) ++bucket;
      if (bucket == kCollapseBuckets) break;
      if ((++steps & 0xffff) == 0) checkCancel(cancel);
      const Entry e = buckets[bucket][next[bucket]++];
      if (removed[e.a] || removed[e.b] || version[e.a] != e.va || version[e.b] != e.vb) continue;
      if (!collapse(e.a, e.b)) continue;
      const int into = removed[e.a] ? e.b : e.a;
      neighbours(into, ringU);
      for (int w : ringU) {
        const double length = (points[w] - points[into]).norm();
        if (length < below) {
          const int a = std::min(w, into), b = std::max(w, into), k = bucketOf(length);
          buckets[k].push_back({a, b, version[a], version[b]});
          bucket = std::min(bucket, k);
        }
      }
    }
  };

  // Interior edges over kSplitAbove field-mesh edges split at their midpoint, on the surface (the upload's long edges
  // between short ones: a marching-tetrahedra mesh's), until none is left; boundary edges stay as they are.
  // An edge is split where it is the longest of both its triangles (longest-edge bisection: the angles stay bounded
  // and the splits end), in passes until none is left, and not past kSplitMost times the vertices edges of `edge`
  // would have.
  const int splitMost = static_cast<int>(std::min(1e9, kSplitMost * verticesAt(mesh.area(), edge)));
  auto longest = [&](int f, int a, int b) {
    const double ab = (points[a] - points[b]).norm();
    for (int c = 0; c < 3; ++c)
      if ((points[tris[f][c]] - points[tris[f][(c + 1) % 3]]).norm() > ab) return false;
    return true;
  };
  auto splitLong = [&]() {
    const double above = kSplitAbove * edge;
    int splits = 0;
    for (int pass = 0, done = -1; pass < kSplitPasses && done != 0; ++pass) {
      done = 0;
      for (int f = 0, count = nf; f < count; ++f) {
        if ((f & 0xffff) == 0) checkCancel(cancel);
        for (int c = 0; c < 3 && alive[f]; ++c) {
          const int a = tris[f][c], b = tris[f][(c + 1) % 3], x = tris[f][(c + 2) % 3];
          if (!((points[a] - points[b]).norm() > above) || splits >= splitMost || !longest(f, a, b)) continue;
          int y = -1;
          const int g = across(f, a, b, y);
          if (g < 0 || !longest(g, a, b)) continue;
          const Vec3 p = surface.closestPoint(0.5 * (points[a] + points[b])).point;
          if (!p.allFinite()) continue;
          const int m = nv++;
          points.push_back(p), at.emplace_back();
          removed.push_back(0), boundary.push_back(0), moved.push_back(1), version.push_back(0);
          // (a, b, x) -> (a, m, x) + (m, b, x); (b, a, y) -> (b, m, y) + (m, a, y).
          const int f2 = nf++, g2 = nf++;
          tris[f] = {a, m, x};
          tris[g] = {b, m, y};
          tris.push_back({m, b, x}), tris.push_back({m, a, y});
          alive.push_back(1), alive.push_back(1);
          at[b].erase(std::remove(at[b].begin(), at[b].end(), f), at[b].end());
          at[a].erase(std::remove(at[a].begin(), at[a].end(), g), at[a].end());
          at[b].push_back(f2), at[x].push_back(f2), at[a].push_back(g2), at[y].push_back(g2);
          at[m] = {f, f2, g, g2};
          ++version[a], ++version[b];
          ++splits, ++done;
          break;  // f changed: its edges in the next pass
        }
      }
    }
  };
  // Valences (neighbour counts) of the vertices left.
  std::vector<int> valence(nv, 0);
  auto countValences = [&]() {
    valence.resize(nv);
    for (int v = 0; v < nv; ++v) {
      if (removed[v]) continue;
      neighbours(v, ringU);
      valence[v] = static_cast<int>(ringU.size());
    }
  };
  auto flipTowardsSix = [&]() {
    countValences();
    for (int f = 0; f < nf; ++f) {
      if (!alive[f]) continue;
      for (int c = 0; c < 3; ++c) {
        const int a = tris[f][c], b = tris[f][(c + 1) % 3], x = tris[f][(c + 2) % 3];
        int y = -1;
        const int g = across(f, a, b, y);
        if (g < 0 || x == y) continue;
        auto off = [&](int v, int d) { const int ideal = boundary[v] ? 4 : 6; return (valence[v] + d - ideal) * (valence[v] + d - ideal); };
        const int before = off(a, 0) + off(b, 0) + off(x, 0) + off(y, 0), after = off(a, -1) + off(b, -1) + off(x, 1) + off(y, 1);
        if (after >= before) continue;
        neighbours(x, ringU);
        if (std::binary_search(ringU.begin(), ringU.end(), y)) continue;
        // (a, b, x) and (b, a, y) become (x, a, y) and (y, b, x).
        const std::array<int, 3> t1{x, a, y}, t2{y, b, x};
        const Vec3 n0 = normalOf(tris[f], -1, Vec3::Zero()) + normalOf(tris[g], -1, Vec3::Zero());
        if (!turnsLittle(n0, normalOf(t1, -1, Vec3::Zero())) || !turnsLittle(n0, normalOf(t2, -1, Vec3::Zero()))) continue;
        if ((points[x] - points[y]).norm() > most) continue;
        tris[f] = t1, tris[g] = t2;
        at[x].push_back(g), at[y].push_back(f);
        at[a].erase(std::remove(at[a].begin(), at[a].end(), g), at[a].end());
        at[b].erase(std::remove(at[b].begin(), at[b].end(), f), at[b].end());
        --valence[a], --valence[b], ++valence[x], ++valence[y];
        for (int v : {a, b, x, y}) ++version[v];
        break;  // f changed: on to the next triangle
      }
    }
  };
  // Each interior vertex's place: its neighbours' centroid in its tangent plane (the triangles' normal), on the
  // surface; found over threads from the places before, then taken in order where no triangle turns.
  std::vector<Vec3> target(nv);
  auto relax = [&]() {
    target.resize(nv);
    for (int v = 0; v < nv; ++v) {
      target[v] = points[v];
      if (removed[v] || boundary[v]) continue;
      neighbours(v, ringU);
      if (ringU.empty()) continue;
      Vec3 centroid = Vec3::Zero(), normal = Vec3::Zero();
      for (int w : ringU) centroid += points[w];
      centroid /= static_cast<double>(ringU.size());
      for (int f : at[v]) normal += normalOf(tris[f], -1, Vec3::Zero());
      if (!(norm(normal) > 0)) continue;
      normal = normalized(normal);
      target[v] = centroid - dot(centroid - points[v], normal) * normal;
    }
    parallelRanges(nv, kPointsPerThread, [&](int begin, int end) {
      for (int v = begin; v < end; ++v)
        if (!removed[v] && !boundary[v]) target[v] = surface.closestPoint(target[v]).point;
    });
    for (int v = 0; v < nv; ++v) {
      const Vec3& p = target[v];
      if (removed[v] || boundary[v] || p == points[v] || !p.allFinite()) continue;
      bool fine = true;
      for (int f : at[v]) fine = fine && (!alive[f] || turnsLittle(normalOf(tris[f], -1, p), normalOf(tris[f], v, p)));
      if (!fine) continue;
      points[v] = p, moved[v] = 1, ++version[v];
    }
  };
  for (int round = 0; round < kThinRounds; ++round) {
    splitLong();
    collapseShort();
    checkCancel(cancel);
    flipTowardsSix();
    relax();
  }
  std::vector<int> id(nv, -1);
  kept.clear();
  std::vector<Vec3> left;
  for (int v = 0; v < nv; ++v)
    if (!removed[v]) id[v] = static_cast<int>(kept.size()), kept.push_back(moved[v] ? -1 : v), left.push_back(points[v]);
  TriMesh out;
  out.V.resize(static_cast<Eigen::Index>(left.size()), 3);
  for (std::size_t i = 0; i < left.size(); ++i) out.V.row(static_cast<Eigen::Index>(i)) = left[i].transpose();
  const int live = static_cast<int>(std::count(alive.begin(), alive.end(), char(1)));
  out.F.resize(live, 3);
  for (int f = 0, row = 0; f < nf; ++f)
    if (alive[f]) out.F.row(row++) << id[tris[f][0]], id[tris[f][1]], id[tris[f][2]];
  return out;
}

// The points split off a remeshed upload's triangles (`thin`, split into `fine`, `where` each point's triangle of it;
// ids from kept.size() on), placed at their closest points: where the upload's facets meet at a concave edge, the
// closest points of a triangle's grid can fold over (a genus 2 of 21k vertices remeshed at 3 field-mesh edges: 3 of
// 360k triangles, on the inner side of a handle). Each corner of such a triangle that is no upload vertex (`kept`
// -1) moves to the closest point of its neighbours' centroid, kUntangleSweeps sweeps; where that leaves some turned,
// points stay on their remeshed triangles (below). Returns whether no triangle is left turned against its corners'
// normals (else the caller remeshes at one field-mesh edge less).
bool untangleSplit(const MeshSurface& mesh, const TriMesh& thin, const TriMesh& fine, const std::vector<std::pair<int, Vec3>>& where,
                   const std::vector<int>& kept, std::vector<LocalGeometry>& geo) {
  const Triangles& F = fine.F;
  const int fixed = static_cast<int>(kept.size());
  const int nf = static_cast<int>(F.rows()), nv = static_cast<int>(geo.size());
  auto turned = [&](int f) {
    const Vec3 &a = geo[F(f, 0)].point, &b = geo[F(f, 1)].point, &c = geo[F(f, 2)].point;
    return dot(cross(b - a, c - a), geo[F(f, 0)].normal + geo[F(f, 1)].normal + geo[F(f, 2)].normal) <= 0;
  };
  std::vector<int> bad(nf);
  auto findTurned = [&] {
    parallelRanges(nf, kPointsPerThread, [&](int begin, int end) {
      for (int f = begin; f < end; ++f) bad[f] = turned(f);
    });
    return std::count(bad.begin(), bad.end(), 1) > 0;
  };
  std::vector<char> moving(nv);
  std::vector<Vec3> sum(nv);
  std::vector<int> count(nv);
  for (int sweep = 0; sweep < kUntangleSweeps; ++sweep) {
    if (!findTurned()) return true;
    std::fill(moving.begin(), moving.end(), 0);
    for (int f = 0; f < nf; ++f)
      if (bad[f])
        for (int c = 0; c < 3; ++c) moving[F(f, c)] = F(f, c) >= fixed || kept[F(f, c)] < 0;
    std::fill(sum.begin(), sum.end(), Vec3::Zero());
    std::fill(count.begin(), count.end(), 0);
    for (int f = 0; f < nf; ++f)
      for (int c = 0; c < 3; ++c) {
        const int v = F(f, c);
        if (!moving[v]) continue;
        for (int d : {1, 2}) sum[v] += geo[F(f, (c + d) % 3)].point, count[v] += 1;
      }
    for (int v = 0; v < nv; ++v)
      if (moving[v] && count[v] > 0) geo[v] = mesh.closestPoint(sum[v] / count[v]);
  }
  // Left turned: the split points of the remeshed triangles holding those triangles, and of the remeshed triangles
  // around them, stay where the split put them, on the remeshed triangles (off the surface by their sagitta), with
  // the geometry of their closest points: a patch split evenly, where points moved one by one leave slivers (the
  // genus 2 at 100k faces: its lattice's regions then came out non-manifold there, laid again 1.6 times finer).
  if (!findTurned()) return true;
  const std::vector<LocalGeometry> swept = geo;
  std::vector<char> patch(thin.F.rows(), 0), corner(thin.V.rows(), 0);
  for (int f = 0; f < nf; ++f)
    if (bad[f])
      for (int c = 0; c < 3; ++c)
        if (const int t = where[F(f, c)].first; t >= 0)
          for (int k = 0; k < 3; ++k) corner[thin.F(t, k)] = 1;
  for (int t = 0; t < thin.F.rows(); ++t) patch[t] = corner[thin.F(t, 0)] || corner[thin.F(t, 1)] || corner[thin.F(t, 2)];
  for (int v = fixed; v < nv; ++v)
    if (const int t = where[v].first; t >= 0 && patch[t]) geo[v].point = fine.V.row(v).transpose();
  // Else, where the remeshed triangles themselves turn against the points' normals (a refined upload whose cubic fits
  // fold between slivers: the generated genus 3 refined 2 x 2 at 100k faces), from the sweeps' places, the split
  // points of each triangle left turned alone, in turn.
  if (!findTurned()) return true;
  geo = swept;
  for (int sweep = 0; sweep < kUntangleSweeps; ++sweep) {
    if (!findTurned()) return true;
    for (int f = 0; f < nf; ++f)
      if (bad[f])
        for (int c = 0; c < 3; ++c)
          if (const int v = F(f, c); v >= fixed) geo[v].point = fine.V.row(v).transpose();
  }
  return !findTurned();
}

}  // namespace phex::global
