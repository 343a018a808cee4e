// phex — local repair of invalid triangle stars (§4.2, Propositions 4 and 5).
//
// A laid triangulation can miss validity at a few stars: where a flow line bends sharply, near umbilics,
// where rows are resampled or fronts zipped, or where the discretization of an uploaded mesh disturbs the
// conjugate directions. Each such vertex is moved a little within the surface, to the position that makes
// its own star and its neighbours' stars valid, judged exactly as checkTriangulation judges them.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "phex/duality.hpp"
#include "phex/dupin.hpp"
#include "phex/ideal_triangle.hpp"
#include "phex/parallel.hpp"
#include "phex/triangulation.hpp"

namespace phex {
namespace {

// Below these the star is valid but close to the edge of validity; the repair prefers positions above them.
constexpr double kBarycentricMargin = 0.05;  // K > 0: Dupin centre this far inside (barycentric)
constexpr double kSectorMargin = 0.05;       // K < 0: II(e, e) / (kmax |e|^2) this far on each side of 0

// The star triangle (0, a, b) at g: whether it satisfies Prop. 4 / 5 (starValidity), and how far it is from
// satisfying it with the margins (0 when it does).
struct TriangleState {
  bool valid = false;
  double violation = 3.0;
};

TriangleState triangleState(const LocalGeometry& g, const Vec2& a, const Vec2& b) {
  const StarValidity s = starValidity(g, {Vec2(0, 0), a, b});
  TriangleState r;
  if (!s.judged) return r;
  r.valid = s.valid;
  if (g.k1 * g.k2 > 0) {
    double v = 0;
    for (double bi : s.measures) v += std::max(0.0, kBarycentricMargin - bi);
    r.violation = std::min(v, 3.0);
  } else {
    const double pos = *std::max_element(s.measures.begin(), s.measures.end());
    const double neg = -*std::min_element(s.measures.begin(), s.measures.end());
    r.violation = std::max(0.0, kSectorMargin - pos) + std::max(0.0, kSectorMargin - neg);
  }
  return r;
}

// The repair keeps, for every judged star, the state of each of its triangles (triangleState at the star's
// centre), and refreshes only the entries a move touches: a vertex's own star (its position and geometry
// changed) and the triangles of its neighbours' stars that have it as a corner. A candidate position is then
// judged by re-evaluating those triangles alone and summing the rest from the cache, in the order a full
// evaluation would sum them, so the sums — and every decision — are exactly those of a full evaluation.
class Repair {
 public:
  // `geometry`: of every vertex where it is now (vertexGeometry's), or empty to compute it.
  // `edgeMean`: the mean edge the points' kinds are classified by (the triangulation's where 0).
  Repair(Triangulation& t, const Surface& surface, std::vector<LocalGeometry> geometry = {},
         const std::vector<char>* only = nullptr, double edgeMean = 0)
      : t_(t), T_(t.mesh), surface_(surface), only_(only), edgeMean_(edgeMean > 0 ? edgeMean : t.mesh.meanEdgeLength()),
        rings_(vertexRings(t.mesh)), geo_(geometry.empty() ? vertexGeometry(t, surface) : std::move(geometry)) {
    parametric_ = dynamic_cast<const ParametricSurface*>(&surface);
    if (!parametric_ || static_cast<int>(t.uv.size()) != T_.V.rows()) parametric_ = nullptr;
    judge({});
  }

  // The same repair as one built afresh now, after this one ran (its moves) and, where `flipped`, after edges of
  // the triangulation were flipped: its stars judged again (a move across a parabolic curve changes which are),
  // their triangles' states kept where the star and its judgement are the same (the cache follows every move),
  // the rest evaluated. Bit for bit the state a new Repair of the triangulation and this geometry would have.
  void renew(bool flipped) {
    const int nv = static_cast<int>(T_.V.rows());
    std::vector<char> same(nv, 1);  // stars whose triangles (ids and corners) are as the cache has them
    if (flipped) {
      VertexRings rings = vertexRings(T_);
      for (int v = 0; v < nv; ++v) {
        bool unchanged = rings.triangles[v] == rings_.triangles[v] && rings.closed[v] == rings_.closed[v];
        for (std::size_t i = 0; unchanged && i < rings.triangles[v].size(); ++i)
          unchanged = T_.F.row(rings.triangles[v][i]) == judgedF_.row(rings.triangles[v][i]);
        same[v] = unchanged;
      }
      rings_ = std::move(rings);
    }
    judge(same);
    clock_ = 0;
  }

  // Per vertex, how many triangles of its star fail Prop. 4 / 5 (as starIsValid judges them), for the stars this
  // repair judges; -1 for the others.
  std::vector<int> failingTriangles() const {
    const int nv = static_cast<int>(T_.V.rows());
    std::vector<int> failing(nv, -1);
    for (int v = 0; v < nv; ++v)
      if (checkable_[v]) {
        failing[v] = 0;
        for (int i = cacheStart_[v]; i < cacheStart_[v + 1]; ++i) failing[v] += !cache_[i].valid;
      }
    return failing;
  }
  const std::vector<LocalGeometry>& geometry() const { return geo_; }

  // (Of the stars to mend: `only_`'s where given.)
  bool invalid(int v) const {
    if (!checkable_[v] || (only_ && !(*only_)[v])) return false;
    for (int i = cacheStart_[v]; i < cacheStart_[v + 1]; ++i)
      if (!cache_[i].valid) return true;
    return false;
  }
  int invalidCount() const {
    int count = 0;
    for (int v = 0; v < static_cast<int>(T_.V.rows()); ++v) count += invalid(v);
    return count;
  }

  // What the sweeps need besides the cache (left out when no star is invalid).
  void prepare() {
    const int nv = static_cast<int>(T_.V.rows());
    // Neighbours, flattened: neighbourStart_[v] .. neighbourStart_[v + 1] in neighbourList_, sorted.
    neighbourStart_.assign(nv + 1, 0);
    neighbourList_.clear();
    std::vector<int> ring;
    for (int v = 0; v < nv; ++v) {
      ring.clear();
      for (int f : rings_.triangles[v])
        for (int k = 0; k < 3; ++k)
          if (T_.F(f, k) != v) ring.push_back(T_.F(f, k));
      std::sort(ring.begin(), ring.end());
      ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
      neighbourList_.insert(neighbourList_.end(), ring.begin(), ring.end());
      neighbourStart_[v + 1] = static_cast<int>(neighbourList_.size());
    }
    original_ = T_.V;
    laidShortest_.resize(nv);
    for (int v = 0; v < nv; ++v) laidShortest_[v] = shortestEdge(v);
    minArea_.assign(nv, 0.0);
    movedAt_.assign(nv, 0);
    idleAt_.assign(nv, -1);
  }

  RepairResult run(int maxSweeps) {
    RepairResult r;
    const int nv = static_cast<int>(T_.V.rows());
    std::vector<int> bad;
    for (int v = 0; v < nv; ++v)
      if (invalid(v)) bad.push_back(v);
    r.invalidBefore = static_cast<int>(bad.size());
    if (bad.empty()) return r;
    prepare();
    std::vector<char> moved(nv, 0);
    std::vector<int> work, changed;
    for (int sweep = 0; sweep < maxSweeps && !bad.empty(); ++sweep) {
      ++r.sweeps;
      // The invalid stars' centres and their neighbours: moving any of them changes an invalid star.
      work.clear();
      for (int v : bad) {
        work.push_back(v);
        work.insert(work.end(), nbBegin(v), nbEnd(v));
      }
      std::sort(work.begin(), work.end());
      work.erase(std::unique(work.begin(), work.end()), work.end());
      bool progress = false;
      changed.clear();  // stars a move touched: the moved vertex's and its neighbours'
      for (int v : work)
        if (rings_.closed[v] && !rings_.triangles[v].empty() && improve(v)) {
          moved[v] = 1, progress = true;
          changed.push_back(v);
          changed.insert(changed.end(), nbBegin(v), nbEnd(v));
        }
      // Only the stars around moved vertices can have changed.
      changed.insert(changed.end(), bad.begin(), bad.end());
      std::sort(changed.begin(), changed.end());
      changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
      const std::size_t before = bad.size();
      bad.clear();
      for (int v : changed)
        if (invalid(v)) bad.push_back(v);
      // Done when nothing moved, or when a sweep fixed under 0.5 % of many stars left (the rest resist moves
      // this small; further sweeps cost more than they give).
      if (!progress || (sweep > 0 && before >= 200 && 200 * (before - std::min(before, bad.size())) < before)) break;
    }
    r.invalidAfter = static_cast<int>(bad.size());
    r.moved = static_cast<int>(std::count(moved.begin(), moved.end(), 1));
    return r;
  }

 private:
  // The stars checkTriangulation judges, and the cache of their triangles' states: entry cacheStart_[u] + i for
  // the i-th triangle of u's star (judged u only). Where `same` says a star is as the cache has it (renew), a
  // star judged before keeps its entries.
  void judge(const std::vector<char>& same) {
    const int nv = static_cast<int>(T_.V.rows());
    std::vector<char> checkable = judgedStars(T_, rings_, geo_, edgeMean_);
    std::vector<int> start(nv + 1, 0);
    for (int v = 0; v < nv; ++v)
      start[v + 1] = start[v] + (checkable[v] ? static_cast<int>(rings_.triangles[v].size()) : 0);
    if (!same.empty() && checkable == checkable_ && start == cacheStart_) {  // the same layout: in place
      parallelRanges(nv, kPointsPerThread, [&](int begin, int end) {
        for (int v = begin; v < end; ++v)
          if (checkable_[v] && !same[v])
            for (std::size_t i = 0; i < rings_.triangles[v].size(); ++i)
              cache_[cacheStart_[v] + i] = starTriangle(v, rings_.triangles[v][i]);
      });
      judgedF_ = T_.F;
      return;
    }
    std::vector<TriangleState> cache(start[nv]);
    parallelRanges(nv, kPointsPerThread, [&](int begin, int end) {  // each entry on its own
      for (int v = begin; v < end; ++v) {
        if (!checkable[v]) continue;
        if (!same.empty() && same[v] && checkable_[v]) {
          std::copy(cache_.begin() + cacheStart_[v], cache_.begin() + cacheStart_[v + 1], cache.begin() + start[v]);
          continue;
        }
        for (std::size_t i = 0; i < rings_.triangles[v].size(); ++i)
          cache[start[v] + i] = starTriangle(v, rings_.triangles[v][i]);
      }
    });
    checkable_ = std::move(checkable);
    cacheStart_ = std::move(start);
    cache_ = std::move(cache);
    judgedF_ = T_.F;
  }

  const int* nbBegin(int v) const { return neighbourList_.data() + neighbourStart_[v]; }
  const int* nbEnd(int v) const { return neighbourList_.data() + neighbourStart_[v + 1]; }

  // Triangle f of u's star, judged at u with u's geometry.
  TriangleState starTriangle(int u, int f) const {
    const LocalGeometry& g = geo_[u];
    int k = 0;
    while (T_.F(f, k) != u) ++k;
    const Vec2 a = toTangentPlane(g, T_.V.row(T_.F(f, (k + 1) % 3)).transpose());
    const Vec2 b = toTangentPlane(g, T_.V.row(T_.F(f, (k + 2) % 3)).transpose());
    return triangleState(g, a, b);
  }

  // After v moved: its own star's entries and its neighbours' triangles with v as a corner.
  void refresh(int v) {
    if (checkable_[v])
      for (std::size_t i = 0; i < rings_.triangles[v].size(); ++i)
        cache_[cacheStart_[v] + i] = starTriangle(v, rings_.triangles[v][i]);
    for (const int* u = nbBegin(v); u != nbEnd(v); ++u) {
      if (!checkable_[*u]) continue;
      const std::vector<int>& tris = rings_.triangles[*u];
      for (std::size_t i = 0; i < tris.size(); ++i)
        if (T_.F(tris[i], 0) == v || T_.F(tris[i], 1) == v || T_.F(tris[i], 2) == v)
          cache_[cacheStart_[*u] + i] = starTriangle(*u, tris[i]);
    }
  }

  // (stars with an invalid triangle, total violation) over the judged stars that v's position affects — its
  // own and its neighbours' — from the cache (up to date with the positions now).
  std::pair<int, double> cachedLocalState(int v) const {
    int count = 0;
    double total = 0;
    auto add = [&](int u) {
      if (!checkable_[u]) return;
      int c = 0;
      double s = 0;
      for (int i = cacheStart_[u]; i < cacheStart_[u + 1]; ++i) {
        c += !cache_[i].valid;
        s += cache_[i].violation;
      }
      count += c > 0;
      total += s;
    };
    add(v);
    for (const int* u = nbBegin(v); u != nbEnd(v); ++u) add(*u);
    return {count, total};
  }

  // The same with v where it is now (a candidate position, geometry in geo_[v]) while the cache still holds
  // its previous position: v's star and the touched_ triangles are evaluated afresh, the rest read. Both
  // sums only grow star by star (violations are >= 0), so as soon as the partial state cannot beat `best`
  // (by the acceptance test of improve) the evaluation stops and returns false; else true with the state.
  bool candidateState(int v, const std::pair<int, double>& best, std::pair<int, double>& out) const {
    const double threshold = best.second * (1 - 1e-9) - 1e-15;
    int count = 0;
    double total = 0;
    auto beaten = [&] { return count > best.first || (count == best.first && !(total < threshold)); };
    if (checkable_[v]) {
      int c = 0;
      double s = 0;
      for (int f : rings_.triangles[v]) {
        const TriangleState st = starTriangle(v, f);
        c += !st.valid;
        s += st.violation;
      }
      count += c > 0;
      total += s;
      if (beaten()) return false;
    }
    std::size_t next = 0;  // touched_ is grouped by neighbour, in neighbour order, ascending within
    for (const int* pu = nbBegin(v); pu != nbEnd(v); ++pu) {
      const int u = *pu;
      if (!checkable_[u]) continue;
      int c = 0;
      double s = 0;
      const int n = cacheStart_[u + 1] - cacheStart_[u];
      for (int i = 0; i < n; ++i) {
        if (next < touched_.size() && touched_[next].first == u && touched_[next].second == i) {
          ++next;
          const TriangleState st = starTriangle(u, rings_.triangles[u][i]);
          c += !st.valid;
          s += st.violation;
        } else {
          const TriangleState& st = cache_[cacheStart_[u] + i];
          c += !st.valid;
          s += st.violation;
        }
      }
      count += c > 0;
      total += s;
      if (beaten()) return false;
    }
    out = {count, total};
    return true;
  }

  // The orientation of v's triangles seen along the surface normal at v: all must keep theirs.
  bool foldsOver(int v) const {
    const Vec3 n = geo_[v].normal;
    int i = 0;
    for (int f : rings_.triangles[v]) {
      const Vec3 a = T_.V.row(T_.F(f, 0)), b = T_.V.row(T_.F(f, 1)), c = T_.V.row(T_.F(f, 2));
      const double s = (b - a).cross(c - a).dot(n);
      if ((s > 0 ? 1 : -1) != signs_[i++] || std::abs(s) < 1e-3 * minArea_[v]) return true;
    }
    return false;
  }

  double shortestEdge(int v) const {
    double shortest = std::numeric_limits<double>::infinity();
    for (const int* u = nbBegin(v); u != nbEnd(v); ++u) shortest = std::min(shortest, (T_.V.row(*u) - T_.V.row(v)).norm());
    return shortest;
  }

  // Whether improve(v) is known to leave v where it is: it did last time, and nothing it reads has changed
  // since — it reads the positions and geometry of v, its neighbours and theirs (their stars' corners).
  bool knownIdle(int v) const {
    const long idle = idleAt_[v];
    if (idle < 0 || movedAt_[v] > idle) return false;
    for (const int* u = nbBegin(v); u != nbEnd(v); ++u) {
      if (movedAt_[*u] > idle) return false;
      for (const int* w = nbBegin(*u); w != nbEnd(*u); ++w)
        if (movedAt_[*w] > idle) return false;
    }
    return true;
  }

  // improveAt unless known idle; true when v's position changed.
  bool improve(int v) {
    movedPosition_ = false;
    if (knownIdle(v)) return false;
    if (improveAt(v)) {
      movedAt_[v] = ++clock_;
      refresh(v);
    } else {
      idleAt_[v] = clock_;
    }
    return movedPosition_;
  }

  // Moves v to its best candidate; true when a candidate was taken (v's position or geometry changed).
  bool improveAt(int v) {
    const Vec3 p0 = T_.V.row(v).transpose();
    const LocalGeometry g0 = geo_[v];
    const Vec2 uv0 = parametric_ ? t_.uv[v] : Vec2::Zero();
    std::pair<int, double> best = cachedLocalState(v);
    if (best.first == 0 && best.second == 0) return false;
    // Orientation of the triangles now, and the ring's size.
    signs_.clear();
    double ringEdge = 0, area = std::numeric_limits<double>::infinity();
    for (int f : rings_.triangles[v]) {
      const Vec3 a = T_.V.row(T_.F(f, 0)), b = T_.V.row(T_.F(f, 1)), c = T_.V.row(T_.F(f, 2));
      const double s = (b - a).cross(c - a).dot(g0.normal);
      signs_.push_back(s > 0 ? 1 : -1);
      area = std::min(area, std::abs(s));
    }
    Vec3 centroid = Vec3::Zero();
    const int valence = static_cast<int>(nbEnd(v) - nbBegin(v));
    for (const int* u = nbBegin(v); u != nbEnd(v); ++u) {
      centroid += T_.V.row(*u).transpose();
      ringEdge += (T_.V.row(*u).transpose() - p0).norm();
    }
    centroid /= static_cast<double>(valence);
    ringEdge /= static_cast<double>(valence);
    minArea_[v] = area;
    const double cap = 0.4 * ringEdge;  // never further than this from where the laying put the vertex
    const double laidShortest = laidShortest_[v];  // nor shortening its edges much: no narrow layers made
    // The neighbours' triangles with v as a corner: the only entries of their stars a candidate changes.
    touched_.clear();
    for (const int* u = nbBegin(v); u != nbEnd(v); ++u) {
      if (!checkable_[*u]) continue;
      const std::vector<int>& tris = rings_.triangles[*u];
      for (int i = 0; i < static_cast<int>(tris.size()); ++i)
        if (T_.F(tris[i], 0) == v || T_.F(tris[i], 1) == v || T_.F(tris[i], 2) == v) touched_.emplace_back(*u, i);
    }

    std::array<Vec3, 27> candidates;
    int nc = 0;
    const Vec3 toCentroid = centroid - p0;
    for (double s : {1.0, 0.5, 0.25}) candidates[nc++] = p0 + s * toCentroid;
    for (double step : {0.15, 0.05, 0.3})
      for (int i = 0; i < 8; ++i) {
        const double angle = i * 3.141592653589793 / 4;
        candidates[nc++] = p0 + step * ringEdge * (std::cos(angle) * g0.d1 + std::sin(angle) * g0.d2);
      }

    bool taken = false;
    Vec3 bestPoint = p0;
    LocalGeometry bestGeometry = g0;
    Vec2 bestUv = uv0;
    const Vec3 origin = original_.row(v).transpose();
    for (const Vec3& c : candidates) {
      if ((c - origin).norm() > 1.5 * cap) continue;  // would land beyond the cap
      Vec2 uv = uv0;
      LocalGeometry g;
      if (parametric_) {
        uv = parametric_->project(c, uv0);
        g = parametric_->geometryAt(uv.x(), uv.y());
      } else {
        g = surface_.closestPoint(c);
      }
      if (!g.point.allFinite() || (g.point - origin).norm() > cap) continue;
      T_.V.row(v) = g.point.transpose();
      geo_[v] = g;
      if (foldsOver(v) || shortestEdge(v) < 0.75 * laidShortest) continue;
      std::pair<int, double> s;
      if (candidateState(v, best, s)) {  // fewer invalid stars, or as many further from the edge of validity
        best = s;
        bestPoint = g.point;
        bestGeometry = g;
        bestUv = uv;
        taken = true;
        if (s.first == 0 && s.second == 0) break;  // every star around is valid with its margins: done
      }
    }
    T_.V.row(v) = bestPoint.transpose();
    geo_[v] = bestGeometry;
    if (parametric_) t_.uv[v] = bestUv;
    // A taken candidate at the very same point would still change v's geometry: count it as a move here;
    // what the caller reports as moved is the position.
    movedPosition_ = bestPoint != p0;
    return taken;
  }

  Triangulation& t_;
  TriMesh& T_;
  const Surface& surface_;
  const std::vector<char>* only_ = nullptr;  // the stars to mend (all where null)
  double edgeMean_ = 0;
  const ParametricSurface* parametric_ = nullptr;
  VertexRings rings_;
  std::vector<LocalGeometry> geo_;
  std::vector<char> checkable_;
  std::vector<int> neighbourStart_, neighbourList_;
  std::vector<double> minArea_;
  Points original_;
  std::vector<double> laidShortest_;  // each vertex's shortest edge as laid
  std::vector<int> cacheStart_;
  std::vector<TriangleState> cache_;
  Triangles judgedF_;  // the triangles as the cache's stars were taken (renew compares)
  std::vector<long> movedAt_, idleAt_;  // clock_ of v's last move; of the last improve(v) that left it
  long clock_ = 0;
  // Scratch of improveAt.
  std::vector<int> signs_;
  std::vector<std::pair<int, int>> touched_;  // (neighbour, index in its star)
  bool movedPosition_ = false;
};

// Edge flips around the stars the moves left invalid: which diagonal a quad of two triangles takes decides
// whether its four corners' stars are valid, and where rows meet at an angle (seams between systems, zipped
// fronts, resampled rows) no position of the vertices makes up for the wrong one. An interior edge of a
// triangle at an invalid star is flipped when that leaves fewer of the four corners' stars failing Prop. 4 /
// 5 (or as many, with fewer failing triangles), both new triangles stand upright over the surface with a
// height of at least kFlipHeight of their longest edge, no vertex drops below valence 4 and none rises
// above 8. Stars are judged at their own vertex's geometry, parabolic or planar ones not at all (as
// checkTriangulation). Returns how many edges were flipped. `known` (where given) holds each star's failing
// triangles as the repair judged them (-1 where it did not): such a star is not evaluated again before the first
// sweep (its count is the same: starIsValid at the same geometry and corners), only whether it is judged here at
// all.
constexpr double kFlipHeight = 0.3;
int flipAtInvalidStars(Triangulation& t, const std::vector<LocalGeometry>& geo, const std::vector<int>* known = nullptr,
                       const std::vector<char>* only = nullptr, double edgeMean = 0) {
  TriMesh& T = t.mesh;
  const int nv = static_cast<int>(T.V.rows()), nf = static_cast<int>(T.F.rows());
  if (!(edgeMean > 0)) edgeMean = T.meanEdgeLength();
  std::vector<std::vector<int>> incident(nv);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) incident[T.F(f, k)].push_back(f);
  std::vector<char> judgeable(nv, 0);
  for (int v = 0; v < nv; ++v) {
    const PointType type = classify(geo[v], 1e-6, edgeMean);
    judgeable[v] = type == PointType::Elliptic || type == PointType::Hyperbolic;
  }
  auto at = [&](int v) -> Vec3 { return T.V.row(v).transpose(); };
  auto triangleWith = [&](int a, int b) {  // the triangle with the directed edge a -> b, or -1
    for (int f : incident[a])
      for (int k = 0; k < 3; ++k)
        if (T.F(f, k) == a && T.F(f, (k + 1) % 3) == b) return f;
    return -1;
  };
  // Whether v's fan closes around it (an interior vertex): every edge out of v has its twin.
  auto closed = [&](int v) {
    for (int f : incident[v]) {
      int k = 0;
      while (T.F(f, k) != v) ++k;
      if (triangleWith(T.F(f, (k + 2) % 3), v) < 0) return false;
    }
    return !incident[v].empty();
  };
  auto judge = [&](int v, bool first) {
    // (A star the repair found valid counts 0 whether its fan closes or not: not looked at again.)
    if (!judgeable[v] || (first && known && (*known)[v] == 0) || !closed(v)) return 0;
    if (first && known && (*known)[v] > 0) return (*known)[v];
    const LocalGeometry& g = geo[v];
    int bad = 0;
    for (int f : incident[v]) {
      int k = 0;
      while (T.F(f, k) != v) ++k;
      bad += !starIsValid(g, {Vec2(0, 0), toTangentPlane(g, at(T.F(f, (k + 1) % 3))),
                              toTangentPlane(g, at(T.F(f, (k + 2) % 3)))});
    }
    return bad;
  };
  auto upright = [&](int x, int y, int z) {
    const Vec3 n = geo[x].normal + geo[y].normal + geo[z].normal;
    const Vec3 e = at(y) - at(x), f = at(z) - at(x);
    const double area2 = e.cross(f).dot(n) / n.norm();
    const double longest = std::max({e.squaredNorm(), f.squaredNorm(), (at(z) - at(y)).squaredNorm()});
    return area2 > kFlipHeight * longest;
  };
  auto detach = [&](int f) {
    for (int k = 0; k < 3; ++k) {
      std::vector<int>& list = incident[T.F(f, k)];
      list.erase(std::find(list.begin(), list.end(), f));
    }
  };
  // Each vertex's count as last judged (-1: to judge): it changes only where the vertex's own triangles do (a
  // flip's four corners), so every sweep after the first judges those alone.
  std::vector<int> judged(nv, -1);
  auto failing = [&](int v) {
    if (judged[v] < 0) judged[v] = judge(v, false);
    return judged[v];
  };
  auto attach = [&](int f) {
    for (int k = 0; k < 3; ++k) incident[T.F(f, k)].push_back(f), judged[T.F(f, k)] = -1;
  };
  // Every vertex judged once before the first sweep, over threads (a judgement reads the mesh alone).
  // (Where only some stars are to be mended, the others are judged when a flip next to a marked one asks.)
  parallelRanges(nv, kPointsPerThread, [&](int begin, int end) {
    for (int v = begin; v < end; ++v)
      if (!only || (*only)[v]) judged[v] = judge(v, true);
  });
  // The sweep in which a flip last changed each vertex's triangles (-1: none). A flip around v is judged by the
  // triangles of vertices within two edges of v alone: where none of them changed since the sweep before, which
  // tried every flip around v and took none, this one would take none either (most invalid stars resist flips:
  // on the bumps upload at 10k faces about 470, each sweep after the first took 7-9 ms for none).
  std::vector<int> changedIn(nv, -1);
  auto changedNear = [&](int v, int since) {
    for (int f : incident[v])
      for (int k = 0; k < 3; ++k)
        for (int g : incident[T.F(f, k)])
          for (int j = 0; j < 3; ++j)
            if (changedIn[T.F(g, j)] >= since) return true;
    return false;
  };
  int flipped = 0;
  for (int sweep = 0; sweep < 4; ++sweep) {
    std::vector<int> bad;
    for (int v = 0; v < nv; ++v)
      if ((!only || (*only)[v]) && failing(v) > 0) bad.push_back(v);
    int flips = 0;
    for (int v : bad) {
      if (failing(v) == 0) continue;  // a flip at a neighbour made it valid
      if (sweep > 0 && !changedNear(v, sweep - 1)) continue;
      bool again = true;
      while (again) {
        again = false;
        const std::vector<int> fan = incident[v];
        for (int f1 : fan) {
          for (int k = 0; k < 3 && !again; ++k) {
            const int x = T.F(f1, k), y = T.F(f1, (k + 1) % 3), p = T.F(f1, (k + 2) % 3);
            const int f2 = triangleWith(y, x);
            if (f2 < 0) continue;
            int j = 0;
            while (T.F(f2, j) != y) ++j;
            const int q = T.F(f2, (j + 2) % 3);
            if (q == p || triangleWith(p, q) >= 0 || triangleWith(q, p) >= 0) continue;
            if (incident[x].size() <= 4 || incident[y].size() <= 4 || incident[p].size() >= 8 || incident[q].size() >= 8)
              continue;
            if (!upright(x, q, p) || !upright(q, y, p)) continue;
            const int corners[4] = {x, y, p, q};
            int starsBefore = 0, trianglesBefore = 0, before[4];
            for (int i = 0; i < 4; ++i) {
              const int n = before[i] = failing(corners[i]);
              starsBefore += n > 0, trianglesBefore += n;
            }
            if (starsBefore == 0) continue;
            const Eigen::Vector3i old1 = T.F.row(f1), old2 = T.F.row(f2);
            detach(f1);
            detach(f2);
            T.F.row(f1) = Eigen::RowVector3i(x, q, p);
            T.F.row(f2) = Eigen::RowVector3i(q, y, p);
            attach(f1);
            attach(f2);
            int starsAfter = 0, trianglesAfter = 0;
            for (int c : corners) {
              const int n = failing(c);
              starsAfter += n > 0, trianglesAfter += n;
            }
            if (starsAfter < starsBefore || (starsAfter == starsBefore && trianglesAfter < trianglesBefore)) {
              ++flips;
              for (int c : corners) changedIn[c] = sweep;
              again = failing(v) > 0;  // v's fan changed: look at it afresh
              break;
            }
            detach(f1);
            detach(f2);
            T.F.row(f1) = old1.transpose();
            T.F.row(f2) = old2.transpose();
            attach(f1);
            attach(f2);
            // The four stars as before the flip (only the order of their triangles in `incident` changed, which
            // a judgement does not depend on): their counts as judged then, not judged again.
            for (int i = 0; i < 4; ++i) judged[corners[i]] = before[i];
          }
          if (again) break;
        }
      }
    }
    flipped += flips;
    if (flips == 0) break;
  }
  return flipped;
}

}  // namespace

namespace {

RepairResult repairAll(Triangulation& triangulation, const Surface& surface, int maxSweeps, GeometryCache* cache,
                       const std::vector<char>* only, double edgeMean);

// The stars `only` marks mended on the part of the triangulation around them: the triangles at vertices within
// kAroundRings edges of a marked one, their vertices numbered in the same order (and the triangles), the points'
// kinds classified by the whole triangulation's mean edge. A repair reads no further than that: it moves the marked
// stars' centres and their neighbours, judging their neighbours' stars, and flips the edges of the marked stars'
// triangles and of their neighbours', judging the four corners' stars; every star it judges is whole in the part.
// So the same moves and flips as on the whole triangulation, which the rounds against folds built again each round
// (at 100k faces, for a few thousand stars marked: 0.3 s a round).
constexpr int kAroundRings = 3;
RepairResult repairAround(Triangulation& triangulation, const Surface& surface, int maxSweeps, GeometryCache* cache,
                          const std::vector<char>& only) {
  TriMesh& T = triangulation.mesh;
  const int nv = static_cast<int>(T.V.rows()), nf = static_cast<int>(T.F.rows());
  std::vector<char> near(only);
  markWithinEdges(T, near, kAroundRings);
  std::vector<int> faces, id(nv, -1), vertices;
  for (int f = 0; f < nf; ++f)
    if (near[T.F(f, 0)] || near[T.F(f, 1)] || near[T.F(f, 2)]) {
      faces.push_back(f);
      for (int k = 0; k < 3; ++k) id[T.F(f, k)] = 0;
    }
  for (int v = 0; v < nv; ++v)
    if (id[v] == 0) id[v] = static_cast<int>(vertices.size()), vertices.push_back(v);
  if (faces.empty()) return {};
  Triangulation part;
  const int pv = static_cast<int>(vertices.size()), pf = static_cast<int>(faces.size());
  part.mesh.V.resize(pv, 3);
  part.mesh.F.resize(pf, 3);
  std::vector<char> partOnly(pv, 0);
  for (int i = 0; i < pv; ++i) {
    part.mesh.V.row(i) = T.V.row(vertices[i]);
    partOnly[i] = only[vertices[i]];
  }
  if (static_cast<int>(triangulation.uv.size()) == nv)
    for (int v : vertices) part.uv.push_back(triangulation.uv[v]);
  for (int i = 0; i < pf; ++i)
    for (int k = 0; k < 3; ++k) part.mesh.F(i, k) = id[T.F(faces[i], k)];
  const RepairResult r = repairAll(part, surface, maxSweeps, cache, &partOnly, T.meanEdgeLength());
  for (int i = 0; i < pv; ++i) {
    T.V.row(vertices[i]) = part.mesh.V.row(i);
    if (!part.uv.empty()) triangulation.uv[vertices[i]] = part.uv[i];
  }
  for (int i = 0; i < pf; ++i)
    for (int k = 0; k < 3; ++k) T.F(faces[i], k) = vertices[part.mesh.F(i, k)];
  for (std::string& note : part.notes) triangulation.notes.push_back(std::move(note));
  return r;
}

}  // namespace

RepairResult repairStars(Triangulation& triangulation, const Surface& surface, int maxSweeps, GeometryCache* cache,
                         const std::vector<char>* only) {
  if (triangulation.mesh.F.rows() == 0 || maxSweeps <= 0) return {};
  if (only) return repairAround(triangulation, surface, maxSweeps, cache, *only);
  return repairAll(triangulation, surface, maxSweeps, cache, nullptr, 0);
}

namespace {

RepairResult repairAll(Triangulation& triangulation, const Surface& surface, int maxSweeps, GeometryCache* cache,
                       const std::vector<char>* only, double edgeMean) {
  // One repair throughout: after its flips and its moves it is judged again in place (renew), as a repair built
  // afresh would judge it, keeping the triangle states that still hold (on the uploaded bumps at 10k faces, each
  // of the rounds against folds built three repairs of 4-6 ms and judged every star again for the flips: 12-17 ms).
  Repair repair(triangulation, surface, vertexGeometry(triangulation, surface, cache), only, edgeMean);
  RepairResult r = repair.run(maxSweeps);
  // Stars the moves could not make valid: flip edges around them, then move again (the vertices' geometry as
  // the moves left it: a flip moves none).
  int flips = 0;
  if (r.invalidAfter > 0) {
    const std::vector<int> failing = repair.failingTriangles();
    flips = flipAtInvalidStars(triangulation, repair.geometry(), &failing, only, edgeMean);
    if (flips > 0) {
      repair.renew(true);
      const RepairResult s = repair.run(maxSweeps);
      r.invalidAfter = s.invalidAfter;
      r.moved += s.moved;
      r.sweeps += s.sweeps;
    }
  }
  // A repair judges the stars it was built with. A move across a parabolic curve changes a vertex's kind, and
  // with it which stars checkTriangulation judges (a star is judged where its corners share its kind): judged
  // afresh, stars can be invalid that the repair never saw. Method 1 on the torus without the lower bound at
  // 2000 faces counted 48 of 48 repaired, and the check found 46 invalid next to the parabolic circle. So
  // where vertices moved the stars are judged again, and where that finds more invalid ones than the repair
  // left, it runs again, and again while that mends some, up to kRejudges times; the count it leaves is the
  // check's (but after the last of those runs). Stars a repair left without any newly judged are not tried
  // again: another run rarely mends them (the uploaded cyclide at 1000 faces: 31 -> 29 for 220 ms).
  constexpr int kRejudges = 4;
  for (int round = 0, moved = r.moved; round < kRejudges && moved > 0; ++round) {
    repair.renew(false);
    const int judged = repair.invalidCount();
    if (judged == 0 || (round == 0 && judged <= r.invalidAfter)) {
      r.invalidAfter = judged;
      break;
    }
    if (judged > r.invalidAfter) r.invalidBefore += judged - r.invalidAfter;  // newly judged invalid
    const RepairResult s = repair.run(maxSweeps);
    r.invalidAfter = s.invalidAfter;
    r.moved += s.moved;
    r.sweeps += s.sweeps;
    moved = s.moved;
    if (s.invalidAfter >= s.invalidBefore) break;  // mended none
  }
  r.flips = flips;
  if (r.invalidBefore > 0)
    triangulation.notes.push_back("repaired " + std::to_string(r.invalidBefore - r.invalidAfter) + " of " +
                                  std::to_string(r.invalidBefore) + " invalid stars by moving " +
                                  std::to_string(r.moved) + " vertices within the surface (" +
                                  std::to_string(r.sweeps) + " sweeps)" +
                                  (flips > 0 ? " and flipping " + std::to_string(flips) + " edges" : ""));
  return r;
}

}  // namespace
}  // namespace phex
