// phex — the global method's 6-fold direction field in the Dupin metric, smoothed on a multiresolution hierarchy.
#include <algorithm>
#include <numeric>

#include "global.hpp"
#include "phex/parallel.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

namespace phex::global {
namespace {

// The hierarchy stops where a level has this many vertices or fewer, or barely shrinks.
constexpr int kCoarsest = 64;
// Gauss-Seidel sweeps per level: more on the coarse levels (cheap, and where the field's layout settles), fewer on
// the fine ones, which start from their parent's field.
// (Measured on the shared models at 10k faces: 10 and 8 sweeps gave the same triangulations within a tenth of a
// point of valence 6, at twice the time.)
int sweepsAt(int level) { return level == 0 ? 4 : 6; }
// The weight of the alignment per vertex (times the option and the vertex's anisotropy weight and degree).
// Stronger alignment pulls the field off its smoothest layout, and the lattice along it gains dislocations: on the
// shared models at 3000 faces 0.1 and 1 cost 5-30 points of valence 6 against 0.02.
constexpr double kAlign = 0.02;

// Unit eigenvector of the smaller eigenvalue of the symmetric form [[a, b], [b, c]] in the basis (u, w), and the
// two eigenvalues, with +, -, *, / and sqrt alone (see principalFrame in mesh_surface.cpp).
Vec3 smallerAxis(double a, double b, double c, const Vec3& u, const Vec3& w, double& lo, double& hi) {
  const double half = 0.5 * (a - c), mean = 0.5 * (a + c), radius = std::sqrt(half * half + b * b);
  lo = mean - radius, hi = mean + radius;
  // The larger eigenvalue's direction turned by 90 degrees.
  const Vec2 t = largerEigenDirection(a - c, 2 * b, 2 * radius);
  return -t.y() * u + t.x() * w;
}

Vec3 anyTangent(const Vec3& n) { return normalized(tangential(std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY(), n)); }

// The frame of a cluster of vertices: the normal and the metric G = D^T D averaged by area, the metric restricted
// to the cluster's tangent plane and factored again into an axis and a scale (determinant 1).
Frame averageFrame(const std::vector<const Frame*>& frames, const std::vector<double>& weights) {
  Vec3 n = Vec3::Zero();
  for (std::size_t i = 0; i < frames.size(); ++i) n += weights[i] * frames[i]->n;
  Frame out;
  out.n = norm(n) > 1e-12 ? normalized(n) : frames.front()->n;
  const Vec3 u = anyTangent(out.n), w = cross(out.n, u);
  double a = 0, b = 0, c = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Frame& f = *frames[i];
    const Vec3 du = f.toDupin(tangential(u, f.n)), dw = f.toDupin(tangential(w, f.n));
    a += weights[i] * dot(du, du), b += weights[i] * dot(du, dw), c += weights[i] * dot(dw, dw);
  }
  double lo = 1, hi = 1;
  out.t = smallerAxis(a, b, c, u, w, lo, hi);
  out.sigma = lo > 0 && hi > 0 ? std::sqrt(std::sqrt(lo / hi)) : 1.0;
  return out;
}

void colour(Level& L) {
  const int n = L.size();
  std::vector<int> colourOf(n, -1);
  int colours = 0;
  std::vector<char> used;
  for (int v = 0; v < n; ++v) {
    used.assign(colours + 1, 0);
    for (int i = L.start[v]; i < L.start[v + 1]; ++i)
      if (colourOf[L.adjacent[i]] >= 0) used[colourOf[L.adjacent[i]]] = 1;
    int c = 0;
    while (used[c]) ++c;
    colourOf[v] = c;
    colours = std::max(colours, c + 1);
  }
  L.colorStart.assign(colours + 1, 0);
  for (int v = 0; v < n; ++v) ++L.colorStart[colourOf[v] + 1];
  for (int c = 0; c < colours; ++c) L.colorStart[c + 1] += L.colorStart[c];
  std::vector<int> fill(L.colorStart.begin(), L.colorStart.end() - 1);
  L.colorOrder.assign(n, 0);
  for (int v = 0; v < n; ++v) L.colorOrder[fill[colourOf[v]]++] = v;
}

// The next coarser level: vertices matched in pairs along edges (similar normals, small areas first).
Level coarsen(const Level& fine) {
  const int n = fine.size();
  struct Edge {
    double score;
    int i, j;
  };
  std::vector<Edge> edges;
  for (int i = 0; i < n; ++i)
    for (int k = fine.start[i]; k < fine.start[i + 1]; ++k) {
      const int j = fine.adjacent[k];
      if (j <= i) continue;
      const double score = dot(fine.frame[i].n, fine.frame[j].n) / (fine.area[i] + fine.area[j]);
      edges.push_back({score, i, j});
    }
  parallelSort(edges.begin(), edges.end(), [](const Edge& a, const Edge& b) {  // no ties: (i, j) is unique
    return a.score != b.score ? a.score > b.score : a.i != b.i ? a.i < b.i : a.j < b.j;
  });
  std::vector<int> mate(n, -1);
  for (const Edge& e : edges)
    if (mate[e.i] < 0 && mate[e.j] < 0 && dot(fine.frame[e.i].n, fine.frame[e.j].n) > -0.5) mate[e.i] = e.j, mate[e.j] = e.i;
  Level coarse;
  std::vector<int> parent(n, -1);
  int m = 0;
  for (int i = 0; i < n; ++i)
    if (parent[i] < 0) {
      parent[i] = m;
      if (mate[i] >= 0) parent[mate[i]] = m;
      ++m;
    }
  coarse.x.resize(m);
  coarse.frame.resize(m);
  coarse.area.assign(m, 0.0);
  coarse.alignWeight.assign(m, 0.0);
  coarse.scale.assign(m, 0.0);
  coarse.target.assign(m, Vec3::Zero());
  coarse.fixed.assign(m, 0);
  // Each coarse vertex's children (one or two), in order, as compressed rows.
  std::vector<int> childStart(m + 1, 0), childList(n);
  for (int i = 0; i < n; ++i) ++childStart[parent[i] + 1];
  for (int c = 0; c < m; ++c) childStart[c + 1] += childStart[c];
  {
    std::vector<int> fill(childStart.begin(), childStart.end() - 1);
    for (int i = 0; i < n; ++i) childList[fill[parent[i]]++] = i;
  }
  auto children = [&](int c) {
    struct Range {
      const int *b, *e;
      const int* begin() const { return b; }
      const int* end() const { return e; }
    };
    return Range{childList.data() + childStart[c], childList.data() + childStart[c + 1]};
  };
  parallelRanges(m, kSweepGrain, [&](int begin, int end) {  // each coarse vertex on its own
    std::vector<const Frame*> frames;
    std::vector<double> weights;
    for (int c = begin; c < end; ++c) {
      frames.clear(), weights.clear();
      double area = 0;
      Vec3 x = Vec3::Zero();
      for (int i : children(c)) {
        frames.push_back(&fine.frame[i]);
        weights.push_back(fine.area[i]);
        area += fine.area[i];
        x += fine.area[i] * fine.x[i];
      }
      coarse.area[c] = area;
      coarse.x[c] = area > 0 ? Vec3(x / area) : fine.x[*children(c).begin()];
      coarse.frame[c] = averageFrame(frames, weights);
      for (int i : children(c)) {
        coarse.alignWeight[c] += fine.area[i] * fine.alignWeight[i] / std::max(area, 1e-300);
        coarse.scale[c] += fine.area[i] * fine.scale[i] / std::max(area, 1e-300);
        if (fine.fixed[i] && !coarse.fixed[c]) coarse.fixed[c] = 1, coarse.target[c] = fine.target[i];
      }
      if (!coarse.fixed[c]) coarse.target[c] = coarse.frame[c].t;
      coarse.target[c] = normalized(tangential(coarse.target[c], coarse.frame[c].n));
      if (!(norm(coarse.target[c]) > 0.5)) coarse.target[c] = coarse.frame[c].t, coarse.fixed[c] = 0;
    }
  });
  // Adjacency: the children's, mapped (each coarse vertex's row gathered from its children's, sorted, unique).
  coarse.start.assign(m + 1, 0);
  std::vector<int> row;
  for (int c = 0; c < m; ++c) {
    row.clear();
    for (int i : children(c))
      for (int k = fine.start[i]; k < fine.start[i + 1]; ++k)
        if (const int b = parent[fine.adjacent[k]]; b != c) row.push_back(b);
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    coarse.adjacent.insert(coarse.adjacent.end(), row.begin(), row.end());
    coarse.start[c + 1] = static_cast<int>(coarse.adjacent.size());
  }
  colour(coarse);
  // `parent` belongs to the fine level; the caller stores it there.
  coarse.parent = std::move(parent);
  return coarse;
}

// The candidate of the six lattice directions of w (a unit vector of the frame with normal n) nearest `reference`,
// and how many sixths of a turn from w it is.
Vec3 nearestOfSix(const Vec3& reference, const Vec3& w, const Vec3& n, int* turns = nullptr) {
  const Vec3 c[3] = {w, rotate60(w, n), rotate60(rotate60(w, n), n)};
  int best = 0;
  double bestDot = dot(reference, c[0]);
  for (int k = 1; k < 3; ++k) {
    const double d = dot(reference, c[k]);
    if (std::abs(d) > std::abs(bestDot)) best = k, bestDot = d;
  }
  if (turns) *turns = bestDot < 0 ? best + 3 : best;
  return bestDot < 0 ? Vec3(-c[best]) : c[best];
}

}  // namespace

Vec3 matchDirection(const Vec3& reference, const Frame& b, const Vec3& q, const Frame& a, const Vec3& e, int* turns) {
  return nearestOfSix(reference, normalized(transport(q, a, b, e)), b.n, turns);
}

constexpr double kAlignedSurface = 0.5, kAlignedBoundary = 0.5;

std::vector<Level> hierarchy(const FieldMesh& mesh, const std::vector<double>& scale, bool freeAlignedBoundary,
                             const std::vector<double>* holdTo) {
  std::vector<Level> levels(1);
  Level& L = levels[0];
  const int n = mesh.vertexCount();
  L.x.resize(n);
  for (int v = 0; v < n; ++v) L.x[v] = mesh.point(v);
  L.frame = mesh.frame;
  L.area = mesh.area;
  L.alignWeight = holdTo ? *holdTo : mesh.alignWeight;
  L.scale = scale;
  L.fixed = mesh.boundary;
  // On a surface whose field is held to the flatter principal direction over most of it (a near-developable: the
  // mean alignment weight over kAlignedSurface), the boundary is not fixed where that hold is strong
  // (kAlignedBoundary): rows along a boundary that runs across the flatter direction end every other one at
  // a vertex of 5 or 7 faces next to it, while rows along the flatter direction end at the boundary cleanly, their
  // panels clipped to it. (Not where the caller says the curvature is noise: GlobalOptions::freeAlignedBoundary.)
  double held = 0;
  for (int v = 0; v < n; ++v) held += mesh.alignWeight[v];
  if (freeAlignedBoundary && n > 0 && held > kAlignedSurface * n)
    for (int v = 0; v < n; ++v)
      if (mesh.alignWeight[v] > kAlignedBoundary) L.fixed[v] = 0;
  L.target.resize(n);
  for (int v = 0; v < n; ++v) {
    L.target[v] = L.fixed[v] ? mesh.boundaryTangent[v] : mesh.frame[v].t;
    if (!(norm(L.target[v]) > 0.5)) L.target[v] = mesh.frame[v].t, L.fixed[v] = 0;
  }
  L.start = mesh.start;
  L.adjacent = mesh.adjacent;
  colour(L);
  while (levels.back().size() > kCoarsest) {
    Level next = coarsen(levels.back());
    if (next.size() > 0.9 * levels.back().size()) break;
    levels.back().parent = std::move(next.parent);
    next.parent.clear();
    levels.push_back(std::move(next));
  }
  return levels;
}

void setScale(std::vector<Level>& levels, const std::vector<double>& scale) {
  levels[0].scale = scale;
  for (std::size_t l = 1; l < levels.size(); ++l) {
    const Level& fine = levels[l - 1];
    Level& coarse = levels[l];
    coarse.scale.assign(coarse.size(), 0.0);
    for (int i = 0; i < fine.size(); ++i)
      coarse.scale[fine.parent[i]] += fine.area[i] * fine.scale[i] / std::max(coarse.area[fine.parent[i]], 1e-300);
  }
}

namespace {

// 2D vectors as complex numbers: directions in a frame's (t, b) coordinates.
inline Vec2 mul(const Vec2& a, const Vec2& b) { return Vec2(a.x() * b.x() - a.y() * b.y(), a.x() * b.y() + a.y() * b.x()); }
inline Vec2 conj(const Vec2& a) { return Vec2(a.x(), -a.y()); }
inline Vec2 unit(const Vec2& a) {
  const double n = std::sqrt(a.x() * a.x() + a.y() * a.y());
  return n > 0 ? Vec2(a / n) : a;
}
inline Vec2 turn60(const Vec2& a) {
  static const double s = 0.5 * std::sqrt(3.0);
  return Vec2(0.5 * a.x() - s * a.y(), s * a.x() + 0.5 * a.y());
}
// Of w's six lattice directions, the one nearest r.
inline Vec2 nearestOfSix2(const Vec2& r, const Vec2& w) {
  const Vec2 c1 = turn60(w), c2 = turn60(c1);
  const double d0 = r.dot(w), d1 = r.dot(c1), d2 = r.dot(c2);
  const double a0 = std::abs(d0), a1 = std::abs(d1), a2 = std::abs(d2);
  if (a0 >= a1 && a0 >= a2) return d0 < 0 ? Vec2(-w) : w;
  if (a1 >= a2) return d1 < 0 ? Vec2(-c1) : c1;
  return d2 < 0 ? Vec2(-c2) : c2;
}
inline Vec2 power6(const Vec2& z) {
  const Vec2 z3 = mul(mul(z, z), z);
  return mul(z3, z3);
}
// A unit u with u^6 = w (w unit): the nearest of u0 in {1, e^15i, e^30i, e^45i}, whose sixth powers are 1, i, -1, -i,
// then Newton's steps on u^6 - w (no libm: the same bits on every platform).
Vec2 root6(const Vec2& w) {
  static const double c15 = (std::sqrt(6.0) + std::sqrt(2.0)) / 4, s15 = (std::sqrt(6.0) - std::sqrt(2.0)) / 4;
  static const double h = std::sqrt(0.5);
  const Vec2 start[4] = {Vec2(1, 0), Vec2(c15, s15), Vec2(0.5 * std::sqrt(3.0), 0.5), Vec2(h, h)};
  const Vec2 sixth[4] = {Vec2(1, 0), Vec2(0, 1), Vec2(-1, 0), Vec2(0, -1)};
  int best = 0;
  for (int k = 1; k < 4; ++k)
    if (w.dot(sixth[k]) > w.dot(sixth[best])) best = k;
  Vec2 u = start[best];
  for (int step = 0; step < 6; ++step) {
    const Vec2 u2 = mul(u, u), u5 = mul(mul(u2, u2), u);
    const Vec2 f = mul(u5, u) - w, d = 6.0 * u5;  // u <- u - f / d
    const double dd = d.squaredNorm();
    if (!(dd > 0)) break;
    u = unit(u - mul(f, conj(d)) / dd);
  }
  return u;
}

// Per half-edge (row v, neighbour u = adjacent[i]) the transport from u's Dupin frame to v's (see transport()).
std::vector<Vec2> transports(const Level& L) {
  std::vector<Vec2> R(L.adjacent.size());
  parallelRanges(L.size(), kSweepGrain, [&](int begin, int end) {
    for (int v = begin; v < end; ++v)
      for (int i = L.start[v]; i < L.start[v + 1]; ++i) {
        const int u = L.adjacent[i];
        const Vec3 e = L.x[v] - L.x[u];
        const Vec2 ea = unit(L.frame[u].coords(e, true)), eb = unit(L.frame[v].coords(e, true));
        R[i] = ea.squaredNorm() > 0 && eb.squaredNorm() > 0 ? mul(eb, conj(ea)) : Vec2(1, 0);
      }
  });
  return R;
}

// The levels' coarsest that the linear solve below takes: the finest with at most this many vertices.
constexpr int kDirectSolve = 6000;

// The smoothest 6-fold field on level L, as one linear solve (globally optimal direction fields): z = q^6 per
// vertex, min sum over edges |z_v - R^6 z_u|^2 + sum a_v |z_v - g_v|^2 with g the alignment target's sixth power,
// a its weight (boundary vertices: a large one), and where nothing aligns the field, a few inverse iterations
// towards unit length. Its singular points are where z passes through 0, as few as the surface needs.
std::vector<Vec2> smoothestField(const Level& L, const std::vector<Vec2>& R, const std::vector<Vec2>& target,
                                 const std::vector<double>& align) {
  const int n = L.size();
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * n);
  double degrees = 0;
  for (int v = 0; v < n; ++v) {
    const int degree = L.start[v + 1] - L.start[v];
    degrees += degree;
    double diagonal = degree;
    for (int i = L.start[v]; i < L.start[v + 1]; ++i) {
      const int u = L.adjacent[i];
      const Vec2 A = power6(R[i]);  // z_u seen at v
      // -A at (v, u): [[a, -b], [b, a]]
      entries.emplace_back(2 * v, 2 * u, -A.x()), entries.emplace_back(2 * v, 2 * u + 1, A.y());
      entries.emplace_back(2 * v + 1, 2 * u, -A.y()), entries.emplace_back(2 * v + 1, 2 * u + 1, -A.x());
    }
    const double a = L.fixed[v] ? 1e3 * std::max(degree, 1) : align[v];
    if (a > 0) {
      const Vec2 g = power6(target[v]);
      diagonal += a;
      rhs(2 * v) += a * g.x(), rhs(2 * v + 1) += a * g.y();
    }
    entries.emplace_back(2 * v, 2 * v, diagonal), entries.emplace_back(2 * v + 1, 2 * v + 1, diagonal);
  }
  const double mu = 1e-2 * degrees / std::max(n, 1);
  for (int k = 0; k < 2 * n; ++k) entries.emplace_back(k, k, mu);
  Eigen::SparseMatrix<double> H(2 * n, 2 * n);
  H.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(H);
  std::vector<Vec2> z(n);
  for (int v = 0; v < n; ++v) z[v] = power6(target[v]);
  if (solver.info() != Eigen::Success) return z;
  Eigen::VectorXd b(2 * n);
  for (int iteration = 0; iteration < 4; ++iteration) {
    for (int v = 0; v < n; ++v) {
      const Vec2 u = unit(z[v]);
      b(2 * v) = rhs(2 * v) + mu * u.x(), b(2 * v + 1) = rhs(2 * v + 1) + mu * u.y();
    }
    const Eigen::VectorXd x = solver.solve(b);
    for (int v = 0; v < n; ++v) z[v] = Vec2(x(2 * v), x(2 * v + 1));
  }
  return z;
}

}  // namespace

std::vector<std::vector<Vec3>> orientationField(std::vector<Level>& levels, double alignment, const ProgressFn& progress,
                                                const CancelFlag* cancel) {
  const int count = static_cast<int>(levels.size());
  int direct = count - 1;
  while (direct > 0 && levels[direct - 1].size() <= kDirectSolve) --direct;
  std::vector<std::vector<Vec2>> q(count);
  std::vector<std::vector<Vec3>> out(count);
  for (int l = direct; l >= 0; --l) {
    checkCancel(cancel);
    const Level& L = levels[l];
    const std::vector<Vec2> R = transports(L);
    std::vector<Vec2> target(L.size());
    std::vector<double> align(L.size());
    for (int v = 0; v < L.size(); ++v) {
      target[v] = unit(L.frame[v].coords(L.target[v], true));
      align[v] = kAlign * alignment * L.alignWeight[v] * (L.start[v + 1] - L.start[v]);
    }
    std::vector<Vec2>& Q = q[l];
    if (l == direct) {
      const std::vector<Vec2> z = smoothestField(L, R, target, align);
      Q.resize(L.size());
      for (int v = 0; v < L.size(); ++v) Q[v] = z[v].squaredNorm() > 1e-30 ? root6(unit(z[v])) : target[v];
    } else {  // from the parent's field
      Q.resize(L.size());
      const Level& P = levels[l + 1];
      for (int v = 0; v < L.size(); ++v) {
        const int p = L.parent[v];
        const Vec3 w = P.frame[p].fromDupin(P.frame[p].vector(q[l + 1][p]));
        const Vec2 c = unit(L.frame[v].coords(tangential(w, L.frame[v].n), true));
        Q[v] = c.squaredNorm() > 0.25 ? c : target[v];
      }
    }
    sweepLevel(L, sweepsAt(l), [&](int v) {
      if (L.fixed[v]) {
        Q[v] = target[v];
        return;
      }
      Vec2 sum = Q[v];
      double weight = 0;
      for (int i = L.start[v]; i < L.start[v + 1]; ++i) {
        sum = unit(sum * weight + nearestOfSix2(sum, mul(R[i], Q[L.adjacent[i]])));
        weight += 1;
      }
      if (align[v] > 0) sum = unit(sum * weight + align[v] * nearestOfSix2(sum, target[v]));
      if (sum.squaredNorm() > 0.25) Q[v] = sum;
    });
    out[l].resize(L.size());
    for (int v = 0; v < L.size(); ++v) out[l][v] = L.frame[v].vector(Q[v]);
    if (progress) progress({"triangulate", 0.1 + 0.2 * double(direct + 1 - l) / (direct + 1), "direction field, level " + std::to_string(l)});
  }
  // Levels coarser than the solve's take its field (the position field starts on the coarsest).
  for (int l = direct + 1; l < count; ++l) {
    const Level& L = levels[l];
    const Level& F = levels[l - 1];
    out[l].assign(L.size(), Vec3::Zero());
    for (int v = 0; v < F.size(); ++v)
      if (out[l][F.parent[v]].squaredNorm() == 0) {
        const Vec3 w = F.frame[v].fromDupin(out[l - 1][v]);
        out[l][F.parent[v]] = normalized(L.frame[F.parent[v]].toDupin(tangential(w, L.frame[F.parent[v]].n)));
      }
    for (int v = 0; v < L.size(); ++v)
      if (!(norm(out[l][v]) > 0.5)) out[l][v] = normalized(L.frame[v].toDupin(L.target[v]));
  }
  return out;
}

int singularityIndex(const FieldMesh& mesh, const std::vector<Vec3>& q, int i, int j, int k) {
  // Carry q_i around the triangle, matching it at each corner to the field there, and count the sixths of a turn
  // it comes back turned by against where it started.
  const int corners[4] = {i, j, k, i};
  Vec3 carried = q[i];
  for (int s = 0; s < 3; ++s) {
    const int a = corners[s], b = corners[s + 1];
    // The field at b, as the candidate nearest the carried direction: that is where the carried one now points.
    const Vec3 w = normalized(transport(carried, mesh.frame[a], mesh.frame[b], mesh.point(b) - mesh.point(a)));
    carried = nearestOfSix(w, q[b], mesh.frame[b].n);
  }
  // carried is one of q_i's six directions: which one.
  const Frame& f = mesh.frame[i];
  Vec3 c = q[i];
  int best = 0;
  double bestDot = dot(carried, c);
  for (int r = 1; r < 6; ++r) {
    c = rotate60(c, f.n);
    const double d = dot(carried, c);
    if (d > bestDot) best = r, bestDot = d;
  }
  return best <= 3 ? best : best - 6;  // -2 .. 3
}

bool principalTurns(const FieldMesh& mesh, int i, int j, int k) {
  // The principal directions (a cross: +-t and +-n x t) carried around the triangle as singularityIndex carries q;
  // the flatter one alone would jump by a quarter turn where |k1| = |k2| on a saddle.
  auto nearestOfFour = [&](const Vec3& w, int b) {
    const Vec3& t = mesh.frame[b].t;
    const Vec3 u = cross(mesh.frame[b].n, t);
    const double dt = dot(w, t), du = dot(w, u);
    return std::abs(dt) >= std::abs(du) ? Vec3(dt < 0 ? -t : t) : Vec3(du < 0 ? -u : u);
  };
  const int corners[4] = {i, j, k, i};
  Vec3 carried = mesh.frame[i].t;
  for (int s = 0; s < 3; ++s) {
    const int a = corners[s], b = corners[s + 1];
    carried = nearestOfFour(transport(carried, mesh.frame[a], mesh.frame[b], mesh.point(b) - mesh.point(a)), b);
  }
  return dot(carried, mesh.frame[i].t) < 0.5;
}

}  // namespace phex::global
