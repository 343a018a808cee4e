// phex — the position field's dislocations cancelled before the extraction.
//
// Each field-mesh edge carries the integer translation between its two ends' lattice points (in the lattice
// coordinates of its lower end) and the turn between their lattices (a multiple of 60 degrees). Around a triangle
// whose turns compose to none, the translations add up to zero where the lattice is whole; where they do not, the
// sum is the Burgers vector of a dislocation whose core the triangle holds, and the extraction turns it into a
// vertex of five next to one of seven. The position field (6-PoSy) leaves many: local sweeps cannot move a core,
// and where the lattice must change its count of rows (the cell scale varies, the field turns) they settle where the
// sweeps left them, not in pairs. Here each core is taken away: joined with a core of the opposite Burgers vector
// (the translations along a path of edges between them change by it: a half row the lattice had too many or too
// few between them), moved into a singular point of the field (a singular point of +-1/6 takes any Burgers vector:
// I - R is unimodular for the turn R by 60 degrees). Then the lattice points around the changed edges are solved
// again in least squares from the translations, and each is settled on its own lattice's point nearest its vertex.
// The torus laid at 3000 faces: 60 -> 0 irregular vertices (the bubble 139 -> 63). Cores let out through the
// boundary as well left vertices of 5 and 7 next to it, where the boundary's own sites meet the rows: on the 40
// clean runs 97.03 against 97.32 % hexagons, the helicoid at 2000 faces a boundary node 1.26 mean edges off its curve.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include "global.hpp"

namespace phex::global {
namespace {

using Int2 = std::array<int, 2>;
using Int22 = std::array<int, 4>;  // a 2 x 2 integer matrix, row-major

// The turns of the triangular lattice in its own coordinates (a U + b V, V being U turned by 60 degrees): R^k for
// R = {{0, -1}, {1, 1}}, which takes U to V and V to V - U.
constexpr Int22 kTurns[6] = {{1, 0, 0, 1}, {0, -1, 1, 1}, {-1, -1, 1, 0}, {-1, 0, 0, -1}, {0, 1, -1, -1}, {1, 1, -1, 0}};
constexpr Int22 kIdentity = kTurns[0];

Int2 times(const Int22& m, const Int2& v) { return {m[0] * v[0] + m[1] * v[1], m[2] * v[0] + m[3] * v[1]}; }
Int22 times(const Int22& a, const Int22& b) {
  return {a[0] * b[0] + a[1] * b[2], a[0] * b[1] + a[1] * b[3], a[2] * b[0] + a[3] * b[2], a[2] * b[1] + a[3] * b[3]};
}
// The inverse of a unimodular matrix (determinant +-1); the identity's determinant otherwise, which the callers
// never meet (every matrix here is a product of turns and their negatives).
Int22 inverse(const Int22& m) {
  const int det = m[0] * m[3] - m[1] * m[2];
  return {m[3] * det, -m[1] * det, -m[2] * det, m[0] * det};
}
Int2 plus(const Int2& a, const Int2& b) { return {a[0] + b[0], a[1] + b[1]}; }
Int2 negated(const Int2& a) { return {-a[0], -a[1]}; }
bool isZero(const Int2& a) { return a[0] == 0 && a[1] == 0; }
// One of the six shortest lattice vectors: +-U, +-V, +-(U - V).
bool isUnit(const Int2& a) { return std::abs(a[0]) + std::abs(a[1]) == 1 || (a[0] == -a[1] && std::abs(a[0]) == 1); }

// A vertex's lattice (latticeAt) with its normal.
struct Basis {
  Lattice lat;
  Vec3 n;
  // The lattice coordinates of w's tangential part.
  Vec2 coords(const Vec3& w) const {
    const Vec3 t = w - dot(w, n) * n;
    const double du = dot(lat.U, t), dv = dot(lat.V, t);
    return Vec2(lat.i00 * du + lat.i01 * dv, lat.i01 * du + lat.i11 * dv);
  }
  Vec3 vector(const Int2& c) const { return double(c[0]) * lat.U + double(c[1]) * lat.V; }
};

// The angle of (x, y) in turns, in (-1/2, 1/2], from +, -, *, / alone (libm's atan2 may differ between platforms in
// the last bit, and the seeds it gives decide roundings): atan on [0, 1] by a polynomial within 2e-4 radians (a
// seed's accuracy), the octants by symmetry.
double turns(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y), hi = std::max(ax, ay);
  if (!(hi > 0)) return 0.0;
  const double a = std::min(ax, ay) / hi, s = a * a;
  constexpr double kPi = 3.14159265358979323846;
  double r = ((-0.0464964749 * s + 0.15931422) * s - 0.327622764) * s * a + a;
  if (ay > ax) r = kPi / 2 - r;
  if (x < 0) r = kPi - r;
  if (y < 0) r = -r;
  return r / (2 * kPi);
}

// The integer point nearest (a, b) in the lattice's own metric (nearestCorner).
Int2 roundLattice(const Vec2& c) {
  double a, b;
  nearestCorner(c.x(), c.y(), a, b);
  return {static_cast<int>(a), static_cast<int>(b)};
}

// Breadth-first reaches, in steps between neighbouring field-mesh triangles (about five a cell), of the searches
// for a partner core or a singular point: the near ones first, so that close pairs are joined before a farther
// search takes one of them; then each core left goes down the distance to the nearest singular point; the last
// searches look for partners alone, within kSearchShare visits per triangle in all (a closed
// surface without singular points: the torus). (A middle reach of 96 instead of 48: the same hexagons on the
// sweeps, the bench's upload at 100k faces 0.08 s more.)
constexpr int kNearReach = 24, kMiddleReach = 48, kFarReach = 400;
constexpr long long kSearchShare = 8;
// The lattice points solved again: those within about a path's length of its changed edges, kNearestRings field-mesh
// edges at least and kResolveRings at most (narrower bands strain the lattice more: 6 at most cost 0.4-1.6 points of
// hexagons on the genus 2 upload, the cyclide and the vase at 3000 faces). Conjugate gradients from the moves'
// displacements, to kResolveResidual of the right-hand side or kResolveIterations: from there the error is smooth,
// and 300 iterations instead of 30 gave the same hexagons on the 40 clean runs (97.19 against 97.07 %, within the
// runs' scatter) for 0.5 s more at 100k faces.
constexpr int kNearestRings = 4, kResolveRings = 12;
constexpr double kResolveResidual = 1e-5;
constexpr int kResolveIterations = 30;

class Dislocations {
 public:
  Dislocations(const FieldMesh& m, const Level& L, const std::vector<Vec3>& Q, std::vector<Vec3>& O, double cell)
      : m_(m), L_(L), Q_(Q), O_(O), cell_(cell), nv_(m.vertexCount()), nf_(static_cast<int>(m.F.rows())) {
    // Per compressed-row entry lo -> hi (lo < hi): the turn taking hi's coordinates to lo's, and the translation.
    const std::size_t entries = m.adjacent.size();
    turn_.assign(entries, -1);
    shift_.assign(entries, {0, 0});
    parallelRanges(nv_, kSweepGrain, [&](int begin, int end) {
      for (int lo = begin; lo < end; ++lo) {
        const Basis a = basis(lo);
        for (int k = m.start[lo]; k < m.start[lo + 1]; ++k) {
          const int hi = m.adjacent[k];
          if (hi < lo) continue;
          const Basis b = basis(hi);
          const Int2 u = roundLattice(a.coords(b.lat.U)), v = roundLattice(a.coords(b.lat.V));
          const Int22 t{u[0], v[0], u[1], v[1]};  // columns: hi's U and V in lo's coordinates
          for (int r = 0; r < 6; ++r)
            if (kTurns[r] == t) turn_[k] = static_cast<signed char>(r);
          const Int2 s = roundLattice(a.coords(O[hi] - O[lo]));
          shift_[k] = {static_cast<std::int16_t>(s[0]), static_cast<std::int16_t>(s[1])};
        }
      }
    });
  }

  int run(int* left, const CancelFlag* cancel) {
    // Each triangle's edges (entries of a-b, b-c, c-a), the triangles across each entry, and the cores.
    edges_.resize(nf_);
    across_.assign(m_.adjacent.size(), {-1, -1});
    for (int f = 0; f < nf_; ++f)
      for (int c = 0; c < 3; ++c) {
        const int k = entry(m_.F(f, c), m_.F(f, (c + 1) % 3));
        edges_[f][c] = k;
        (across_[k][0] < 0 ? across_[k][0] : across_[k][1]) = f;
      }
    singular_.assign(nf_, 0);
    core_.assign(nf_, 0);
    for (int f = 0; f < nf_; ++f) {
      singular_[f] = !regular(f);
      core_[f] = !singular_[f] && !isZero(burgers(f));
    }
    seen_.assign(nf_, 0), from_.assign(nf_, -1), via_.assign(nf_, -1), depth_.assign(nf_, 0), carried_.assign(nf_, {0, 0});
    radius_.assign(nv_, 0);
    int cancelled = 0;
    // Partners and singular points near each core, then farther.
    for (const int reach : {kNearReach, kMiddleReach})
      for (int f = 0; f < nf_; ++f) {
        if ((f & 0xffff) == 0) checkCancel(cancel);
        if (core_[f]) cancelled += searchFrom(f, reach, true, nullptr);
      }
    // The cores left down the distance to the nearest singular point.
    descendToSinks(cancelled, cancel);
    // Partners far off, within a budget of visits.
    long long budget = kSearchShare * nf_;
    for (int f = 0; f < nf_ && budget > 0; ++f) {
      if ((f & 0xffff) == 0) checkCancel(cancel);
      if (core_[f]) cancelled += searchFrom(f, kFarReach, false, &budget);
    }
    int remaining = 0;
    for (int f = 0; f < nf_; ++f) remaining += core_[f];
    if (left) *left = remaining;
    // (The search's arrays are not needed by the solve: released first, for the largest runs' peak memory.)
    std::vector<std::array<int, 3>>().swap(edges_);
    std::vector<std::array<int, 2>>().swap(across_);
    for (std::vector<int>* a : {&seen_, &from_, &via_, &depth_, &queue_}) std::vector<int>().swap(*a);
    std::vector<Int2>().swap(carried_);
    if (cancelled > 0) resolve(cancel);
    return cancelled;
  }

 private:
  Basis basis(int v) const { return {latticeAt(L_, Q_, v, cell_), L_.frame[v].n}; }
  // The entry of neighbour `other` in vertex `row`'s row of the compressed adjacency.
  int entryIn(int row, int other) const {
    const auto first = m_.adjacent.begin() + m_.start[row], last = m_.adjacent.begin() + m_.start[row + 1];
    return static_cast<int>(std::lower_bound(first, last, other) - m_.adjacent.begin());
  }
  // The entry of edge (a, b) in the row of its lower end, where its turn and translation are kept.
  int entry(int a, int b) const { return entryIn(std::min(a, b), std::max(a, b)); }
  // (a <- b): b's coordinates into a's, for entry k of edge (a, b).
  Int22 into(int a, int b, int k) const { return a < b ? kTurns[turn_[k]] : kTurns[(6 - turn_[k]) % 6]; }
  // shift(a -> b) in a's coordinates as a matrix times the stored shift(lo -> hi): the identity, or (hi <- lo)
  // negated (shift(hi -> lo) = -(hi <- lo) shift(lo -> hi)).
  Int22 side(int a, int b, int k) const {
    if (a < b) return kIdentity;
    return kTurns[(6 - turn_[k] + 3) % 6];  // -R^-t = R^(3 - t)
  }
  Int2 stored(int k) const { return {shift_[k][0], shift_[k][1]}; }
  Int2 shift(int a, int b, int k) const { return times(side(a, b, k), stored(k)); }
  void change(int k, const Int2& d) {
    shift_[k] = {static_cast<std::int16_t>(shift_[k][0] + d[0]), static_cast<std::int16_t>(shift_[k][1] + d[1])};
  }

  // Triangle f regular: every edge a turn, the turns composing to none around it.
  bool regular(int f) const {
    const int a = m_.F(f, 0), b = m_.F(f, 1), c = m_.F(f, 2);
    const std::array<int, 3>& k = edges_[f];
    if (turn_[k[0]] < 0 || turn_[k[1]] < 0 || turn_[k[2]] < 0) return false;
    return times(times(into(a, b, k[0]), into(b, c, k[1])), into(c, a, k[2])) == kIdentity;
  }
  // Its Burgers vector in its first corner's coordinates: shift(a -> b) + (a <- b) (shift(b -> c) + (b <- c)
  // shift(c -> a)).
  Int2 burgers(int f) const {
    const int a = m_.F(f, 0), b = m_.F(f, 1), c = m_.F(f, 2);
    const std::array<int, 3>& k = edges_[f];
    return plus(shift(a, b, k[0]), times(into(a, b, k[0]), plus(shift(b, c, k[1]), times(into(b, c, k[1]), shift(c, a, k[2])))));
  }
  // How f's Burgers vector changes when the stored shift of its edge e (0: a-b, 1: b-c, 2: c-a) changes by d: by
  // effect(f, e) d (the vector is linear in the shifts).
  Int22 effect(int f, int e) const {
    const int a = m_.F(f, 0), b = m_.F(f, 1), c = m_.F(f, 2);
    const std::array<int, 3>& k = edges_[f];
    if (e == 0) return side(a, b, k[0]);
    const Int22 ab = into(a, b, k[0]);
    if (e == 1) return times(ab, side(b, c, k[1]));
    return times(times(ab, into(b, c, k[1])), side(c, a, k[2]));
  }
  int edgeOf(int f, int k) const { return edges_[f][0] == k ? 0 : edges_[f][1] == k ? 1 : 2; }
  int across(int f, int k) const { return across_[k][0] == f ? across_[k][1] : across_[k][0]; }
  // The change of entry k's shift that takes vector `b` off triangle f (effect d = -b), and what it brings to g
  // across k.
  Int2 takeOff(int f, int k, const Int2& b) const { return times(inverse(effect(f, edgeOf(f, k))), negated(b)); }

  // The changes along `path` (triangle left, entry crossed), from the core on: each takes the core's vector off the
  // triangle it leaves. Marks the changed edges' ends for the solve, with the rings around them solved again: about
  // the path's length in field-mesh edges (a dipole's strain reaches about as far as the two cores are apart),
  // kNearestRings at least, kResolveRings at most.
  void apply(const std::vector<std::pair<int, int>>& path) {
    if (path.empty()) return;
    const int rings = std::clamp(static_cast<int>(path.size()) / 2 + 2, kNearestRings, kResolveRings);
    // The core's move as a displacement of the lattice: -b times the winding about the segment from where it was
    // to where it went (seeded below, before the solve).
    Move move;
    const int f0 = path.front().first;
    move.from = centroid(f0);
    move.burgers = basis(m_.F(f0, 0)).vector(burgers(f0));
    move.rings = rings;
    for (const auto& [f, k] : path) {
      change(k, takeOff(f, k, burgers(f)));
      const int hi = m_.adjacent[k];
      const int lo = static_cast<int>(std::upper_bound(m_.start.begin(), m_.start.end(), k) - m_.start.begin()) - 1;
      radius_[lo] = std::max(radius_[lo], rings), radius_[hi] = std::max(radius_[hi], rings);
      move.start.push_back(lo), move.start.push_back(hi);
      move.edges.push_back(k), move.edges.push_back(entryIn(hi, lo));
    }
    move.to = centroid(across(path.back().first, path.back().second));
    moves_.push_back(std::move(move));
  }
  Vec3 centroid(int f) const { return (m_.point(m_.F(f, 0)) + m_.point(m_.F(f, 1)) + m_.point(m_.F(f, 2))) / 3; }

  // The displacement each move asks of the lattice points around its path: -b w(x), w the winding about the
  // segment from its old place A to its new one B (the signed angle from B - x to A - x over a turn, in x's tangent
  // plane): w turns by one about A and back about B, as the Burgers vectors ask (the translations around A now
  // add up to b less), and its jump across the segment is a whole lattice vector, which each point's settling on
  // its own lattice takes up. Tapered to none over the outer half of the move's rings.
  void seedMoves(std::vector<Vec3>& displacement) {
    std::vector<int> ring(nv_, -1), touched;
    std::vector<double> winding(nv_, 0.0);
    std::vector<char> cut(m_.adjacent.size(), 0), done(nv_, 0);
    for (const Move& mv : moves_) {
      for (int k : mv.edges) cut[k] = 1;  // both ways: the entry of each edge in either end's row
      std::vector<int> front;
      for (int v : mv.start)
        if (ring[v] < 0) ring[v] = 0, front.push_back(v), touched.push_back(v);
      for (int r = 0; r < mv.rings && !front.empty(); ++r) {
        std::vector<int> next;
        for (int v : front)
          for (int k = m_.start[v]; k < m_.start[v + 1]; ++k) {
            const int u = m_.adjacent[k];
            if (ring[u] < 0) ring[u] = r + 1, next.push_back(u), touched.push_back(u);
          }
        front.swap(next);
      }
      // The winding in turns, its whole part chosen from vertex to vertex across the edges the move did not change
      // (the band less the cut is simply connected): it jumps by one across the changed edges alone.
      for (int v : touched) {
        const Vec3 x = m_.point(v), n = L_.frame[v].n;
        const Vec3 a = mv.from - x, b = mv.to - x;
        const Vec3 at = a - dot(a, n) * n, bt = b - dot(b, n) * n;
        winding[v] = turns(dot(cross(bt, at), n), dot(bt, at));
      }
      std::vector<int> order{touched.front()};
      done[touched.front()] = 1;
      for (std::size_t head = 0; head < order.size(); ++head) {
        const int v = order[head];
        for (int k = m_.start[v]; k < m_.start[v + 1]; ++k) {
          const int u = m_.adjacent[k];
          if (ring[u] < 0 || done[u] || cut[k]) continue;
          winding[u] += std::round(winding[v] - winding[u]);
          done[u] = 1;
          order.push_back(u);
        }
      }
      // None far out: the whole turns shifted so that the outermost ring's mean winding is nearest zero.
      double outer = 0;
      int outerCount = 0;
      for (int v : touched)
        if (ring[v] == mv.rings) outer += winding[v], ++outerCount;
      const double offset = outerCount > 0 ? std::round(outer / outerCount) : 0.0;
      for (int v : touched) {
        const double t = std::clamp(2.0 * (1.0 - double(ring[v]) / (mv.rings + 1)), 0.0, 1.0);
        if (done[v]) displacement[v] += (t * (winding[v] - offset)) * mv.burgers;
        ring[v] = -1, done[v] = 0;
      }
      touched.clear();
      for (int k : mv.edges) cut[k] = 0;
    }
  }


  // Breadth first from core f0, carrying the vector the path would bring to each triangle, to the nearest core the
  // vector cancels (or makes one of two) or, where `sinks`, singular point. Applies the path found; returns 1, else 0.
  int searchFrom(int f0, int reach, bool sinks, long long* budget) {
    const Int2 b0 = burgers(f0);
    ++stamp_;
    queue_.clear();
    queue_.push_back(f0);
    seen_[f0] = stamp_, from_[f0] = -1, via_[f0] = -1, depth_[f0] = 0, carried_[f0] = b0;
    int end = -1;
    for (std::size_t head = 0; head < queue_.size() && end < 0; ++head) {
      const int f = queue_[head];
      if (budget && --*budget < 0) return 0;
      if (depth_[f] >= reach) continue;
      for (int c = 0; c < 3 && end < 0; ++c) {
        const int k = edges_[f][c];
        const int g = across(f, k);
        if (g < 0 || seen_[g] == stamp_) continue;
        if (singular_[g]) {
          if (sinks) seen_[g] = stamp_, from_[g] = f, via_[g] = k, end = g;
          continue;
        }
        const Int2 arrives = times(effect(g, edgeOf(g, k)), takeOff(f, k, carried_[f]));
        if (core_[g]) {
          // Cancelled, or two cores made one (three dislocations whose vectors add up to none meet in pairs).
          const Int2 sum = plus(burgers(g), arrives);
          if (isZero(sum) || isUnit(sum)) seen_[g] = stamp_, from_[g] = f, via_[g] = k, end = g;
          continue;
        }
        seen_[g] = stamp_, from_[g] = f, via_[g] = k, depth_[g] = depth_[f] + 1, carried_[g] = arrives;
        queue_.push_back(g);
      }
    }
    if (end < 0) return 0;
    std::vector<std::pair<int, int>> path;
    for (int g = end; from_[g] >= 0; g = from_[g]) path.push_back({from_[g], via_[g]});
    std::reverse(path.begin(), path.end());
    apply(path);
    core_[f0] = 0;
    if (end != f0 && !singular_[end]) core_[end] = !isZero(burgers(end));
    return 1;
  }

  // The cores left, each down the distance to the nearest singular point (breadth first from all of them at
  // once), around other cores.
  void descendToSinks(int& cancelled, const CancelFlag* cancel) {
    constexpr int kFar = std::numeric_limits<int>::max();
    std::vector<int> distance(nf_, kFar);
    queue_.clear();
    for (int f = 0; f < nf_; ++f)
      if (singular_[f]) distance[f] = 0, queue_.push_back(f);
    for (std::size_t head = 0; head < queue_.size(); ++head) {
      const int f = queue_[head];
      for (int c = 0; c < 3; ++c) {
        const int g = across(f, edges_[f][c]);
        if (g >= 0 && distance[g] == kFar) distance[g] = distance[f] + 1, queue_.push_back(g);
      }
    }
    for (int f0 = 0; f0 < nf_; ++f0) {
      if ((f0 & 0xffff) == 0) checkCancel(cancel);
      if (!core_[f0] || distance[f0] == kFar) continue;
      std::vector<std::pair<int, int>> path;
      int f = f0;
      bool reached = true;
      while (distance[f] > 0) {
        int next = -1, via = -1;
        for (int c = 0; c < 3; ++c) {
          const int k = edges_[f][c], g = across(f, k);
          if (g >= 0 && distance[g] < distance[f] && !core_[g] && (next < 0 || distance[g] < distance[next])) next = g, via = k;
        }
        if (next < 0) {
          reached = false;
          break;
        }
        path.push_back({f, via});
        f = next;
      }
      if (!reached) continue;
      apply(path);
      core_[f0] = 0;
      ++cancelled;
    }
  }

  // The lattice points within the marked rings of the changed edges (the boundary's held) solved again: min over
  // the edges of |O_u - O_v - S_vu|^2, S_vu the translation v -> u in space (the mean of both ends' readings), the
  // points outside held; a graph Laplacian, the same for x, y, z, by conjugate gradients from the moves'
  // displacements (seedMoves), which leave the error smooth: kResolveIterations of them. Then each point settled
  // on its own lattice's point nearest its vertex.
  void resolve(const CancelFlag* cancel) {
    for (int r = kResolveRings; r > 1; --r)
      for (int v = 0; v < nv_; ++v)
        if (radius_[v] == r)
          for (int k = m_.start[v]; k < m_.start[v + 1]; ++k) {
            int& u = radius_[m_.adjacent[k]];
            u = std::max(u, r - 1);
          }
    std::vector<int> unknowns, index(nv_, -1);
    for (int v = 0; v < nv_; ++v)
      if (radius_[v] > 0 && !m_.boundary[v]) index[v] = static_cast<int>(unknowns.size()), unknowns.push_back(v);
    const int n = static_cast<int>(unknowns.size());
    if (n == 0) return;
    std::vector<Vec3> displacement(nv_, Vec3::Zero());
    seedMoves(displacement);
    checkCancel(cancel);
    // The rows: the diagonal, the unknown neighbours (per compressed-row entry, -1 where none), the right-hand side.
    constexpr double kAnchor = 1e-4;
    std::vector<Vec3> rhs(n), x(n);
    std::vector<double> diagonal(n);
    std::vector<int> column(m_.adjacent.size(), -1);
    parallelRanges(n, kSweepGrain, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        const int v = unknowns[i];
        const Basis bv = basis(v);
        x[i] = O_[v] + displacement[v];
        Vec3 b = kAnchor * O_[v];
        double d = kAnchor;
        for (int k = m_.start[v]; k < m_.start[v + 1]; ++k) {
          const int u = m_.adjacent[k], e = v < u ? k : entry(v, u);
          if (turn_[e] < 0) continue;
          const Vec3 S = 0.5 * (bv.vector(shift(v, u, e)) - basis(u).vector(shift(u, v, e)));
          d += 1;
          b -= S;
          if (index[u] < 0) b += O_[u];
          else column[k] = index[u];
        }
        rhs[i] = b, diagonal[i] = d;
      }
    });
    auto multiply = [&](const std::vector<Vec3>& p, std::vector<Vec3>& out) {
      parallelRanges(n, kSweepGrain, [&](int begin, int end) {
        for (int i = begin; i < end; ++i) {
          const int v = unknowns[i];
          Vec3 sum = diagonal[i] * p[i];
          for (int k = m_.start[v]; k < m_.start[v + 1]; ++k)
            if (column[k] >= 0) sum -= p[column[k]];
          out[i] = sum;
        }
      });
    };
    // Per coordinate, sums of products: over blocks of kDotBlock rows on threads, the blocks' sums added in order (the
    // same on every platform and thread count).
    constexpr int kDotBlock = 4096;
    const int blocks = (n + kDotBlock - 1) / kDotBlock;
    std::vector<Vec3> partial(blocks);
    auto dots = [&](const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
      parallelTasks(blocks, [&](int k) {
        Vec3 sum = Vec3::Zero();
        for (int i = k * kDotBlock, end = std::min(n, (k + 1) * kDotBlock); i < end; ++i) sum += a[i].cwiseProduct(b[i]);
        partial[k] = sum;
      });
      Vec3 sum = Vec3::Zero();
      for (const Vec3& s : partial) sum += s;
      return sum;
    };
    // Conjugate gradients, preconditioned by the diagonal, the three coordinates side by side.
    std::vector<Vec3> r(n), z(n), p(n), q(n);
    multiply(x, q);
    for (int i = 0; i < n; ++i) r[i] = rhs[i] - q[i], z[i] = r[i] / diagonal[i], p[i] = z[i];
    Vec3 rz = dots(r, z);
    const Vec3 goal = kResolveResidual * kResolveResidual * dots(rhs, rhs);
    for (int it = 0; it < kResolveIterations; ++it) {
      const Vec3 rr = dots(r, r);
      if (rr.x() <= goal.x() && rr.y() <= goal.y() && rr.z() <= goal.z()) break;
      multiply(p, q);
      const Vec3 pq = dots(p, q);
      Vec3 alpha;
      for (int c = 0; c < 3; ++c) alpha[c] = pq[c] > 0 ? rz[c] / pq[c] : 0.0;
      parallelRanges(n, kSweepGrain, [&](int begin, int end) {
        for (int i = begin; i < end; ++i) {
          x[i] += alpha.cwiseProduct(p[i]);
          r[i] -= alpha.cwiseProduct(q[i]);
          z[i] = r[i] / diagonal[i];
        }
      });
      const Vec3 next = dots(r, z);
      Vec3 beta;
      for (int c = 0; c < 3; ++c) beta[c] = rz[c] > 0 ? next[c] / rz[c] : 0.0;
      parallelRanges(n, kSweepGrain, [&](int begin, int end) {
        for (int i = begin; i < end; ++i) p[i] = z[i] + beta.cwiseProduct(p[i]);
      });
      rz = next;
    }
    for (const Vec3& at : x)
      if (!at.allFinite()) return;
    parallelRanges(n, kSweepGrain, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        const int v = unknowns[i];
        const Basis bv = basis(v);
        const Vec3 onto = x[i] - dot(x[i] - L_.x[v], L_.frame[v].n) * L_.frame[v].n;
        const Vec3 settled = onto + bv.vector(roundLattice(bv.coords(L_.x[v] - onto)));
        O_[v] = settled - dot(settled - L_.x[v], L_.frame[v].n) * L_.frame[v].n;
      }
    });
  }

  const FieldMesh& m_;
  const Level& L_;
  const std::vector<Vec3>& Q_;
  std::vector<Vec3>& O_;
  double cell_;
  int nv_, nf_;
  std::vector<signed char> turn_;                   // per entry lo -> hi: the turn (hi <- lo) as a power of R; -1: none
  std::vector<std::array<std::int16_t, 2>> shift_;  // per entry lo -> hi: shift(lo -> hi) in lo's coordinates
  std::vector<std::array<int, 3>> edges_;
  std::vector<std::array<int, 2>> across_;
  std::vector<char> singular_, core_;
  std::vector<int> seen_, from_, via_, depth_, queue_, radius_;
  std::vector<Int2> carried_;
  int stamp_ = 0;
  struct Move {
    Vec3 from, to, burgers;
    int rings = 0;
    std::vector<int> start;  // the ends of the edges it changed
    std::vector<int> edges;  // their entries, each both ways
  };
  std::vector<Move> moves_;
};

}  // namespace

int cancelDislocations(const FieldMesh& mesh, const Level& level, const std::vector<Vec3>& q, std::vector<Vec3>& o,
                       double cell, int* left, const CancelFlag* cancel) {
  Dislocations d(mesh, level, q, o, cell);
  return d.run(left, cancel);
}

}  // namespace phex::global
