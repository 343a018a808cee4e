// phex — the global method's triangular lattice along the 6-fold field: a position field (6-PoSy), smoothed on the
// same hierarchy as the directions.
#include <algorithm>
#include <cmath>

#include "global.hpp"
#include "phex/parallel.hpp"

namespace phex::global {
namespace {

constexpr double kFlatHinge = 0.999;
// Sweeps per level: many on the coarsest (cheap, where the lattice's layout settles), few on the middle ones, more on
// the finest, whose points are extracted (16 there and 12 between cost twice the time for 0.2 points of valence 6).
int sweepsAt(int level, int levels) { return level + 1 == levels ? 30 : level == 0 ? 10 : 5; }


// (The three helpers below are inlined by force: called for every neighbour in every sweep, the calls cost more
// than their arithmetic; the position field's finest level 281 -> 242 ms at 10k faces on one thread.)

// The point of the lattice through o nearest to p (p's tangential part, in the lattice's Dupin metric: the lattice
// is equilateral there). Coordinates (a, b) of p - o in the basis (U, V), then the best of the four corners around
// them by a^2 + ab + b^2, the squared length of a U + b V in units of the edge.
[[gnu::always_inline]] inline Vec3 nearestPoint(const Lattice& lat, const Vec3& o, const Vec3& p) {
  const Vec3 d = p - o;
  const double du = dot(lat.U, d), dv = dot(lat.V, d);
  double ba, bb;
  nearestCorner(lat.i00 * du + lat.i01 * dv, lat.i01 * du + lat.i11 * dv, ba, bb);
  return o + ba * lat.U + bb * lat.V;
}

// The rotation taking unit normal a to unit normal b by the shortest way (about a x b), applied to v.
Vec3 rotateInto(const Vec3& v, const Vec3& axis, double c) {
  return v * c + cross(axis, v) + axis * (dot(axis, v) / (1 + c));
}

// The point nearest to both tangent planes' points p0, p1 (least squares to p0 and p1 on both planes): where the
// two planes are hinged when compared.
Vec3 middlePoint(const Vec3& p0, const Vec3& n0, const Vec3& p1, const Vec3& n1) {
  const double n0p0 = dot(n0, p0), n0p1 = dot(n0, p1), n1p0 = dot(n1, p0), n1p1 = dot(n1, p1), n0n1 = dot(n0, n1);
  const double denominator = 1 / (1 - n0n1 * n0n1 + 1e-4);
  const double l0 = 2 * (n0p1 - n0p0 - n0n1 * (n1p0 - n1p1)) * denominator;
  const double l1 = 2 * (n1p0 - n1p1 - n0n1 * (n0p1 - n0p0)) * denominator;
  return 0.5 * (p0 + p1) - 0.25 * (n0 * l0 + n1 * l1);
}

// `p` moved into the tangent plane at x with normal n.
[[gnu::always_inline]] inline Vec3 intoPlane(const Vec3& p, const Vec3& x, const Vec3& n) { return p - dot(p - x, n) * n; }

// Whether tangent planes whose normals' dot product is c compare as they are: planes within 2.5 degrees compare well
// enough so (most neighbours on the fine levels).
inline bool flatHinge(double c) { return c > kFlatHinge || c < -0.5; }

// The point of vertex u's lattice (through o) nearest to p, moved into v's tangent plane (at xv, normal nv): as the
// two planes compare where flat (flatHinge).
[[gnu::always_inline]] inline Vec3 nearestFlat(const Lattice& lat, const Vec3& o, const Vec3& p, const Vec3& xv, const Vec3& nv) {
  return intoPlane(nearestPoint(lat, o, p), xv, nv);
}

#if defined(__SSE2__) && defined(__GNUC__)
// Two vertices' steps of the running mean side by side in the two lanes of SSE2 registers (GCC's vector types): the
// same operations in the same order on each lane as nearestFlat and the mean's step (IEEE arithmetic lane by lane,
// no contraction), so the same bits, with half the instructions; the processor's window then holds both chains of
// dependent arithmetic, where two chains of scalar code filled it before the second had gone far.
using Lanes = double __attribute__((vector_size(16)));
using Mask = long long __attribute__((vector_size(16)));
struct Vec3Lanes {
  Lanes x, y, z;
};
inline Vec3Lanes lanes(const Vec3& a, const Vec3& b) { return {Lanes{a.x(), b.x()}, Lanes{a.y(), b.y()}, Lanes{a.z(), b.z()}}; }
inline Vec3Lanes operator-(const Vec3Lanes& a, const Vec3Lanes& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Lanes dotLanes(const Vec3Lanes& a, const Vec3Lanes& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// nearestFlat on both lanes, then each lane's mean moved to it: sum = (sum * weight + p) / (weight + 1).
[[gnu::always_inline]] inline void nearestFlatPairStep(const Lattice& la, const Lattice& lb, const Vec3& oa, const Vec3& ob, Vec3& suma,
                                                       Vec3& sumb, const Vec3& xa, const Vec3& xb, const Vec3& na, const Vec3& nb,
                                                       double wa, double wb) {
  const Vec3Lanes U = lanes(la.U, lb.U), V = lanes(la.V, lb.V), o = lanes(oa, ob), p = lanes(suma, sumb);
  const Lanes i00{la.i00, lb.i00}, i01{la.i01, lb.i01}, i11{la.i11, lb.i11};
  const Vec3Lanes d = p - o;
  const Lanes du = dotLanes(U, d), dv = dotLanes(V, d);
  const Lanes a = i00 * du + i01 * dv, b = i01 * du + i11 * dv;
  const Lanes a0{std::floor(a[0]), std::floor(a[1])}, b0{std::floor(b[0]), std::floor(b[1])};
  const Lanes one{1.0, 1.0};
  const Lanes a1 = a0 + one, b1 = b0 + one;
  auto cost = [&](const Lanes& ca, const Lanes& cb) {
    const Lanes ea = a - ca, eb = b - cb;
    return ea * ea + ea * eb + eb * eb;
  };
  const Lanes c0 = cost(a0, b0), c1 = cost(a1, b0), c2 = cost(a0, b1), c3 = cost(a1, b1);
  const Mask first = ~(c1 < c0), third = ~(c3 < c2);
  const Lanes m01 = first ? c0 : c1, m23 = third ? c2 : c3;
  const Mask low = ~(m23 < m01);
  const Lanes ba = low ? (first ? a0 : a1) : (third ? a0 : a1), bb = low ? b0 : b1;
  const Vec3Lanes q{o.x + ba * U.x + bb * V.x, o.y + ba * U.y + bb * V.y, o.z + ba * U.z + bb * V.z};
  // Into the tangent planes: q - ((q - x) . n) n.
  const Vec3Lanes x = lanes(xa, xb), n = lanes(na, nb);
  const Lanes s = dotLanes(q - x, n);
  const Vec3Lanes in{q.x - s * n.x, q.y - s * n.y, q.z - s * n.z};
  const Lanes w{wa, wb}, w1 = w + one;
  const Vec3Lanes next{(p.x * w + in.x) / w1, (p.y * w + in.y) / w1, (p.z * w + in.z) / w1};
  suma = Vec3(next.x[0], next.y[0], next.z[0]);
  sumb = Vec3(next.x[1], next.y[1], next.z[1]);
}
#endif

// The point of vertex u's lattice nearest to p (a point of vertex v's tangent plane), the two planes hinged on their
// line of intersection (the surface between them unbent), so that lattice points compare as on the surface and not
// across its bend; the result is in v's plane.
[[gnu::always_inline]] inline Vec3 nearestHinged(const Lattice& lat, const Vec3& o, const Vec3& xu, const Vec3& nu, const Vec3& p, const Vec3& xv,
                   const Vec3& nv) {
  const double c = dot(nu, nv);
  if (flatHinge(c)) return nearestFlat(lat, o, p, xv, nv);
  const Vec3 hinge = middlePoint(xv, nv, xu, nu);
  const Vec3 axis = cross(nv, nu);  // v's plane onto u's, and back about -axis
  const Vec3 inU = hinge + rotateInto(p - hinge, axis, c);
  const Vec3 found = nearestPoint(lat, o, inU);
  return intoPlane(hinge + rotateInto(found - hinge, Vec3(-axis), c), xv, nv);
}

// A boundary vertex's lattice point lies on the boundary's tangent line (a row of the lattice runs along the
// boundary: its direction is fixed there), at the lattice step nearest the vertex.
Vec3 ontoBoundary(const Vec3& o, const Vec3& x, const Vec3& tangent, const Vec3& U) {
  Vec3 p = x + dot(o - x, tangent) * tangent;
  const double step = norm(U);
  if (step > 0) p += std::round(dot(x - p, tangent) / step) * step * tangent;
  return p;
}

}  // namespace

std::vector<Vec3> positionField(std::vector<Level>& levels, std::vector<std::vector<Vec3>>& fields, double cell,
                                const ProgressFn& progress, const CancelFlag* cancel) {
  const int count = static_cast<int>(levels.size());
  std::vector<Vec3> O, parentO;
  for (int l = count - 1; l >= 0; --l) {
    checkCancel(cancel);
    const Level& L = levels[l];
    const std::vector<Vec3>& Q = fields[l];
    std::vector<Lattice> lattice(L.size());
    parallelRanges(L.size(), kSweepGrain, [&](int begin, int end) {
      for (int v = begin; v < end; ++v) lattice[v] = latticeAt(L, Q, v, cell);
    });
    // Vertex v's own lattice point nearest to it, its lattice laid through `origin` (on the boundary line where the
    // direction is fixed): where it starts, and where each sweep leaves it.
    auto settle = [&](int v, const Vec3& origin) {
      const Vec3 o = intoPlane(nearestPoint(lattice[v], origin, L.x[v]), L.x[v], L.frame[v].n);
      return L.fixed[v] ? ontoBoundary(o, L.x[v], L.target[v], lattice[v].U) : o;
    };
    O.assign(L.size(), Vec3::Zero());
    for (int v = 0; v < L.size(); ++v)
      O[v] = settle(v, l == count - 1 ? L.x[v] : intoPlane(parentO[L.parent[v]], L.x[v], L.frame[v].n));
    // Per neighbour entry, whether the two tangent planes compare as they are (nearestHinged's flat case; all of
    // them on the finest level of the bench's upload): fixed while the positions are smoothed, and the neighbour's
    // normal is not read again in every sweep.
    std::vector<char> flat(L.adjacent.size());
    parallelRanges(L.size(), kSweepGrain, [&](int begin, int end) {
      for (int v = begin; v < end; ++v)
        for (int i = L.start[v]; i < L.start[v + 1]; ++i) flat[i] = flatHinge(dot(L.frame[L.adjacent[i]].n, L.frame[v].n));
    });
    // A vertex's update: the running mean over its neighbours of their lattice points nearest to the mean so far,
    // then its own lattice point nearest to it. Each neighbour's step waits on the one before.
    struct Mean {
      int v, i, end;
      Vec3 x, n, sum;
      double weight;
    };
    auto first = [&](int v) { return Mean{v, L.start[v], L.start[v + 1], L.x[v], L.frame[v].n, O[v], 0.0}; };
    auto step = [&](Mean& m) {
      const int i = m.i++, u = L.adjacent[i];
      const Vec3 p = flat[i] ? nearestFlat(lattice[u], O[u], m.sum, m.x, m.n)
                             : nearestHinged(lattice[u], O[u], L.x[u], L.frame[u].n, m.sum, m.x, m.n);
      m.sum = (m.sum * m.weight + p) / (m.weight + 1);
      m.weight += 1;
    };
    auto last = [&](const Mean& m) { O[m.v] = settle(m.v, m.sum); };
    // Both vertices' next steps; natively in SSE2 lanes where both neighbours' planes compare flat.
    auto stepBoth = [&](Mean& ma, Mean& mb) {
#if defined(__SSE2__) && defined(__GNUC__)
      if (flat[ma.i] && flat[mb.i]) {
        const int ua = L.adjacent[ma.i++], ub = L.adjacent[mb.i++];
        nearestFlatPairStep(lattice[ua], lattice[ub], O[ua], O[ub], ma.sum, mb.sum, ma.x, mb.x, ma.n, mb.n, ma.weight, mb.weight);
        ma.weight += 1, mb.weight += 1;
        return;
      }
#endif
      step(ma), step(mb);
    };
    // Two vertices' steps interleaved (sweepLevelInPairs), and the flat hinges known beforehand: the position
    // field's finest level at 10k faces (the bench's upload) 285-343 -> 237-254 ms on one thread, 151-163 -> 124-138
    // ms on two, the same field bit for bit (four vertices interleaved: no faster than two).
    sweepLevelInPairs(
        L, sweepsAt(l, count),
        [&](int a, int b) {
          Mean ma = first(a), mb = first(b);
          while (ma.i < ma.end && mb.i < mb.end) stepBoth(ma, mb);
          while (ma.i < ma.end) step(ma);
          while (mb.i < mb.end) step(mb);
          last(ma);
          last(mb);
        },
        [&](int v) {
          Mean m = first(v);
          while (m.i < m.end) step(m);
          last(m);
        });
    parentO.swap(O);
    if (progress) progress({"triangulate", 0.3 + 0.2 * double(count - l) / count, "lattice, level " + std::to_string(l)});
  }
  return parentO;
}

}  // namespace phex::global
