// phex — the global method's vertices fitted to the field: the lattice's points come from rounding a position field,
// which leaves them some hundredths of a cell off the lattice (jitter); near a parabolic curve, where Props. 4 and
// 5 tolerate less and less misalignment, that is enough to fold panels. Fitted in least squares to the lattice
// vectors the edges stand for, the rows follow the field's lines again.
#include <algorithm>
#include <cmath>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "global.hpp"
#include "phex/duality.hpp"
#include "phex/parallel.hpp"

namespace phex::global {

void fitToField(TriMesh& T, const std::vector<int>& seeds, const Surface& surface, const FieldMesh& mesh,
                const std::vector<Vec3>& q, const std::vector<double>& scale, double cell, int rounds,
                const CancelFlag* cancel) {
  const int nv = static_cast<int>(T.V.rows());
  if (nv == 0 || rounds <= 0) return;
  const VertexRings rings = vertexRings(T);
  // Interior vertices are the unknowns; boundary vertices stay on the boundary where they were put.
  std::vector<int> unknown(nv, -1);
  int n = 0;
  for (int v = 0; v < nv; ++v)
    if (rings.closed[v] && !rings.triangles[v].empty() && seeds[v] >= 0) unknown[v] = n++;
  if (n == 0) return;
  std::vector<std::pair<int, int>> edges;
  for (int f = 0; f < T.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = T.F(f, k), b = T.F(f, (k + 1) % 3);
      if (a < b || !rings.closed[a] || !rings.closed[b]) edges.push_back({std::min(a, b), std::max(a, b)});
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  // The lattice's six edge vectors at vertex v (three, and their negatives), in space.
  auto latticeVector = [&](int v, const Vec3& e) {
    const int s = seeds[v];
    const Frame& f = mesh.frame[s];
    Vec3 d = q[s], best = Vec3::Zero();
    double bestDot = -1;
    for (int k = 0; k < 3; ++k) {
      const Vec3 U = f.fromDupin(d);
      const double c = dot(U, e) / std::max(norm(U), 1e-300);
      if (std::abs(c) > bestDot) bestDot = std::abs(c), best = c < 0 ? Vec3(-U) : U;
      d = rotate60(d, f.n);
    }
    return Vec3(cell * scale[s] * best);
  };
  // min sum_edges |x_b - x_a - L_ab|^2 + kAnchor sum_v |x_v - x_v^0|^2: a graph Laplacian, the same for x, y, z.
  constexpr double kAnchor = 1e-2;
  std::vector<Eigen::Triplet<double>> entries;
  for (int v = 0; v < nv; ++v)
    if (unknown[v] >= 0) entries.emplace_back(unknown[v], unknown[v], kAnchor);
  for (const auto& [a, b] : edges) {
    const int ia = unknown[a], ib = unknown[b];
    if (ia >= 0) entries.emplace_back(ia, ia, 1.0);
    if (ib >= 0) entries.emplace_back(ib, ib, 1.0);
    if (ia >= 0 && ib >= 0) entries.emplace_back(ia, ib, -1.0), entries.emplace_back(ib, ia, -1.0);
  }
  Eigen::SparseMatrix<double> K(n, n);
  K.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(K);
  if (solver.info() != Eigen::Success) return;
  for (int round = 0; round < rounds; ++round) {
    checkCancel(cancel);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
    for (int v = 0; v < nv; ++v)
      if (unknown[v] >= 0) rhs.row(unknown[v]) = kAnchor * T.V.row(v);
    for (const auto& [a, b] : edges) {
      const Vec3 e = T.V.row(b).transpose() - T.V.row(a).transpose();
      const Vec3 L = 0.5 * (latticeVector(a, e) + latticeVector(b, e));
      const int ia = unknown[a], ib = unknown[b];
      // d/dx_b: (x_b - x_a - L); d/dx_a: -(x_b - x_a - L).
      if (ib >= 0) rhs.row(ib) += L.transpose();
      if (ia >= 0) rhs.row(ia) -= L.transpose();
      if (ia < 0 && ib >= 0) rhs.row(ib) += T.V.row(a);
      if (ib < 0 && ia >= 0) rhs.row(ia) += T.V.row(b);
    }
    const Eigen::MatrixXd x = solver.solve(rhs);
    Points next = T.V;
    parallelRanges(nv, kPointsPerThread, [&](int begin, int end) {
      for (int v = begin; v < end; ++v)
        if (unknown[v] >= 0) next.row(v) = surface.closestPoint(x.row(unknown[v]).transpose()).point.transpose();
    });
    T.V = next;
  }
}

}  // namespace phex::global

namespace phex::global {

int improveValences(TriMesh& T, const Surface& surface, const CancelFlag* cancel) {
  const int nv = static_cast<int>(T.V.rows()), nf = static_cast<int>(T.F.rows());
  if (nf == 0) return 0;
  // Each vertex's triangles, kept as the flips change them (a hash map of every half-edge took a quarter of this
  // at 100k faces). The triangulation is a manifold here (the extraction made it one): a half-edge a -> b is in
  // one triangle at most, found among a's.
  std::vector<std::vector<int>> around(nv);
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) around[T.F(f, c)].push_back(f);
  // The half-edge a -> b as 3 f + c (corner c: F(f, c) = a, F(f, c + 1) = b), or -1.
  auto halfEdge = [&](int a, int b) {
    for (int f : around[a])
      for (int c = 0; c < 3; ++c)
        if (T.F(f, c) == a && T.F(f, (c + 1) % 3) == b) return 3 * f + c;
    return -1;
  };
  std::vector<int> valence(nv, 0);
  std::vector<char> boundary(nv, 0);
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = T.F(f, c), b = T.F(f, (c + 1) % 3);
      if (halfEdge(b, a) < 0) boundary[a] = boundary[b] = 1, ++valence[a], ++valence[b];
      else if (a < b) ++valence[a], ++valence[b];
    }
  // A boundary vertex's ideal valence is 4 (half a hexagon's star), an interior one's 6.
  auto excess = [&](int v, int change) {
    const int d = valence[v] + change - (boundary[v] ? 4 : 6);
    return d * d;
  };
  auto leave = [&](int v, int f) { around[v].erase(std::find(around[v].begin(), around[v].end(), f)); };
  int flips = 0;
  for (int pass = 0; pass < 8; ++pass) {
    checkCancel(cancel);
    int flipped = 0;
    for (int f = 0; f < nf; ++f)
      for (int c = 0; c < 3; ++c) {
        const int a = T.F(f, c), b = T.F(f, (c + 1) % 3), p = T.F(f, (c + 2) % 3);
        if (a > b) continue;
        const int twin = halfEdge(b, a);
        if (twin < 0) continue;
        const int g = twin / 3, gc = twin % 3;
        const int q = T.F(g, (gc + 2) % 3);
        if (p == q || valence[a] <= 3 || valence[b] <= 3 || halfEdge(p, q) >= 0 || halfEdge(q, p) >= 0) continue;
        const int before = excess(a, 0) + excess(b, 0) + excess(p, 0) + excess(q, 0);
        const int after = excess(a, -1) + excess(b, -1) + excess(p, 1) + excess(q, 1);
        if (after >= before) continue;
        // Geometry: the new triangles (p, a, q) and (q, b, p) keep the surface's side (the quad a q b p is convex
        // seen along the normal) and are not slivers.
        const Vec3 A = T.V.row(a).transpose(), B = T.V.row(b).transpose(), P = T.V.row(p).transpose(),
                   Q = T.V.row(q).transpose();
        const Vec3 n = surface.closestPoint(0.25 * (A + B + P + Q)).normal;
        const double t1 = dot(cross(A - P, Q - P), n), t2 = dot(cross(Q - P, B - P), n);
        const double scale = (Q - P).squaredNorm() + (A - B).squaredNorm();
        if (!(t1 > 0.1 * scale * 0.5) || !(t2 > 0.1 * scale * 0.5)) continue;
        // Flip: triangle f becomes (p, a, q), triangle g becomes (q, b, p); a leaves g, b leaves f, p joins g, q f.
        T.F.row(f) << p, a, q;
        T.F.row(g) << q, b, p;
        leave(a, g), leave(b, f), around[p].push_back(g), around[q].push_back(f);
        --valence[a], --valence[b], ++valence[p], ++valence[q];
        ++flipped;
      }
    flips += flipped;
    if (flipped == 0) break;
  }
  return flips;
}

}  // namespace phex::global
