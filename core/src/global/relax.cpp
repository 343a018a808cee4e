// phex — the global method's vertices fitted to the field: the lattice's points come from rounding a position field,
// which leaves them some hundredths of a cell off the lattice (jitter); near a parabolic curve, where Props. 4 and
// 5 tolerate less and less misalignment, that is enough to fold panels. Fitted in least squares to the lattice
// vectors the edges stand for, the rows follow the field's lines again.
#include <algorithm>
#include <array>
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
  const int ne = static_cast<int>(edges.size());
  std::vector<Vec3> vectors(ne);
  for (int round = 0; round < rounds; ++round) {
    checkCancel(cancel);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
    for (int v = 0; v < nv; ++v)
      if (unknown[v] >= 0) rhs.row(unknown[v]) = kAnchor * T.V.row(v);
    // Each edge's lattice vector over threads, summed in order below.
    parallelRanges(ne, kPointsPerThread, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        const auto [a, b] = edges[i];
        const Vec3 e = T.V.row(b).transpose() - T.V.row(a).transpose();
        vectors[i] = 0.5 * (latticeVector(a, e) + latticeVector(b, e));
      }
    });
    for (int i = 0; i < ne; ++i) {
      const auto [a, b] = edges[i];
      const Vec3& L = vectors[i];
      const int ia = unknown[a], ib = unknown[b];
      // d/dx_b: (x_b - x_a - L); d/dx_a: -(x_b - x_a - L).
      if (ib >= 0) rhs.row(ib) += L.transpose();
      if (ia >= 0) rhs.row(ia) -= L.transpose();
      if (ia < 0 && ib >= 0) rhs.row(ib) += T.V.row(a);
      if (ib < 0 && ia >= 0) rhs.row(ia) += T.V.row(b);
    }
    // The three coordinates' solves at once (each column's is the same whether solved alone or with the others).
    Eigen::MatrixXd x(n, 3);
    parallelTasks(3, [&](int c) { x.col(c) = solver.solve(rhs.col(c)); });
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

namespace {

// The triangulation's edge flips, kept undoable: each vertex's triangles (a hash map of every half-edge took a quarter
// of the greedy pass's time at 100k faces), valences, and which vertices are on the boundary. The triangulation is a
// manifold here (the extraction made it one): a half-edge a -> b is in one triangle at most, found among a's.
class Flips {
 public:
  struct Flip {
    int f = -1, g = -1, a = -1, b = -1, p = -1, q = -1;
    std::array<int, 3> rowF{}, rowG{};  // the two triangles' corners as they were, for undo
  };

  explicit Flips(TriMesh& T) : T_(T), around_(T.V.rows()), valence_(T.V.rows(), 0), boundary_(T.V.rows(), 0) {
    const int nf = static_cast<int>(T.F.rows());
    for (int f = 0; f < nf; ++f)
      for (int c = 0; c < 3; ++c) around_[T.F(f, c)].push_back(f);
    for (int f = 0; f < nf; ++f)
      for (int c = 0; c < 3; ++c) {
        const int a = T.F(f, c), b = T.F(f, (c + 1) % 3);
        if (halfEdge(b, a) < 0) boundary_[a] = boundary_[b] = 1, ++valence_[a], ++valence_[b];
        else if (a < b) ++valence_[a], ++valence_[b];
      }
  }

  // The half-edge a -> b as 3 f + c (corner c: F(f, c) = a, F(f, c + 1) = b), or -1.
  int halfEdge(int a, int b) const {
    for (int f : around_[a])
      for (int c = 0; c < 3; ++c)
        if (T_.F(f, c) == a && T_.F(f, (c + 1) % 3) == b) return 3 * f + c;
    return -1;
  }

  // A boundary vertex's ideal valence is 4 (half a hexagon's star), an interior one's 6: the squared miss.
  int excess(int v, int change = 0) const {
    const int d = valence_[v] + change - (boundary_[v] ? 4 : 6);
    return d * d;
  }
  bool irregular(int v) const { return excess(v) > 0; }
  int corner(int f, int c) const { return T_.F(f, c); }
  bool onBoundary(int v) const { return boundary_[v]; }
  const std::vector<int>& around(int v) const { return around_[v]; }

  // The flip of the edge of triangle f at corner c, if the topology allows it: an interior edge whose ends keep
  // three edges at least and whose opposite corners are not joined yet.
  bool flippable(int f, int c, Flip& out) const {
    const int a = T_.F(f, c), b = T_.F(f, (c + 1) % 3), p = T_.F(f, (c + 2) % 3);
    const int twin = halfEdge(b, a);
    if (twin < 0) return false;
    const int g = twin / 3, q = T_.F(g, (twin % 3 + 2) % 3);
    if (p == q || valence_[a] <= 3 || valence_[b] <= 3 || halfEdge(p, q) >= 0 || halfEdge(q, p) >= 0) return false;
    out = {f, g, a, b, p, q, {T_.F(f, 0), T_.F(f, 1), T_.F(f, 2)}, {T_.F(g, 0), T_.F(g, 1), T_.F(g, 2)}};
    return true;
  }
  // How the flip changes the sum of squared misses.
  int change(const Flip& x) const {
    return excess(x.a, -1) + excess(x.b, -1) + excess(x.p, 1) + excess(x.q, 1) - excess(x.a) - excess(x.b) -
           excess(x.p) - excess(x.q);
  }
  // The geometry: the new triangles (p, a, q) and (q, b, p) keep the side of `n` (the quad a q b p is convex seen
  // along it) and are no slivers.
  bool keepsShape(const Flip& x, const Vec3& n) const {
    const Vec3 A = T_.V.row(x.a).transpose(), B = T_.V.row(x.b).transpose(), P = T_.V.row(x.p).transpose(),
               Q = T_.V.row(x.q).transpose();
    const double t1 = dot(cross(A - P, Q - P), n), t2 = dot(cross(Q - P, B - P), n);
    const double scale = dot(Q - P, Q - P) + dot(A - B, A - B);
    return t1 > 0.05 * scale && t2 > 0.05 * scale;
  }
  Vec3 centre(const Flip& x) const {
    return 0.25 * (T_.V.row(x.a) + T_.V.row(x.b) + T_.V.row(x.p) + T_.V.row(x.q)).transpose();
  }
  // The normal of the two triangles the flip replaces (their area-weighted sum).
  Vec3 quadNormal(const Flip& x) const {
    const Vec3 A = T_.V.row(x.a).transpose(), B = T_.V.row(x.b).transpose(), P = T_.V.row(x.p).transpose(),
               Q = T_.V.row(x.q).transpose();
    return normalized(cross(B - A, P - A) + cross(A - B, Q - B));
  }

  // Triangle f becomes (p, a, q), triangle g becomes (q, b, p); a leaves g, b leaves f, p joins g, q f.
  void apply(const Flip& x) {
    T_.F.row(x.f) << x.p, x.a, x.q;
    T_.F.row(x.g) << x.q, x.b, x.p;
    leave(x.a, x.g), leave(x.b, x.f), around_[x.p].push_back(x.g), around_[x.q].push_back(x.f);
    --valence_[x.a], --valence_[x.b], ++valence_[x.p], ++valence_[x.q];
    touch(x);
  }
  // The flip taken back, the triangles' corners in their order as they were (the searches hold triangles and
  // corners from before it).
  void undo(const Flip& x) {
    T_.F.row(x.f) << x.rowF[0], x.rowF[1], x.rowF[2];
    T_.F.row(x.g) << x.rowG[0], x.rowG[1], x.rowG[2];
    leave(x.p, x.g), leave(x.q, x.f), around_[x.a].push_back(x.g), around_[x.b].push_back(x.f);
    ++valence_[x.a], ++valence_[x.b], --valence_[x.p], --valence_[x.q];
    touch(x);
  }

  // A clock that each flip (or undo) advances, and per vertex the time of the last one that changed its triangles
  // or valence or a neighbour's: whether a flip of an edge is possible and pays depends on its triangles' corners
  // and the vertex across (a neighbour of them) alone, so an edge judged since no vertex of one of its triangles
  // was stamped is judged the same again.
  long long clock() const { return clock_; }
  long long stamp(int v) const { return stamp_[v]; }

 private:
  void touch(const Flip& x) {
    ++clock_;
    for (int v : {x.a, x.b, x.p, x.q})
      for (int f : around_[v])
        for (int c = 0; c < 3; ++c) stamp_[T_.F(f, c)] = clock_;
  }
  void leave(int v, int f) { around_[v].erase(std::find(around_[v].begin(), around_[v].end(), f)); }
  TriMesh& T_;
  std::vector<std::vector<int>> around_;
  std::vector<int> valence_;
  std::vector<char> boundary_;
  long long clock_ = 0;
  std::vector<long long> stamp_ = std::vector<long long>(T_.V.rows(), 0);
};

// Sequences of flips around an irregular vertex that leave the valences' sum of squared misses as it is (a dislocation,
// a 5 next to a 7, moving a row along its glide line) and end in one that lowers it (two dislocations of opposite
// sense meeting and cancelling, a dislocation joining a singular vertex): depth-first, `depth` flips at most, among
// the edges of the triangles around the irregular vertices the last flip left, none touching the boundary; at most
// `budget` flips tried in all. True when such a sequence was applied (it is in `done`).
bool glideFrom(Flips& flips, const std::vector<int>& seeds, int depth, const Flips::Flip* last, int& budget,
           std::vector<Flips::Flip>& done) {
  // The edges of the triangles around the seeds, each once: (smaller end, larger end, triangle, corner).
  std::vector<std::array<int, 4>> edges;
  for (int s : seeds)
    for (int f : flips.around(s))
      for (int c = 0; c < 3; ++c) {
        const int a = flips.corner(f, c), b = flips.corner(f, (c + 1) % 3);
        edges.push_back({std::min(a, b), std::max(a, b), f, c});
      }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end(),
                          [](const auto& l, const auto& r) { return l[0] == r[0] && l[1] == r[1]; }),
              edges.end());
  for (const auto& e : edges) {
    Flips::Flip x;
    if (budget <= 0) return false;
    if (!flips.flippable(e[2], e[3], x)) continue;
    // Inside only: a dislocation glided into the boundary strains the boundary panels' rows (the uploaded bumps at
    // 10k faces: a node 0.33 % of the diagonal off the surface, where inside only 0.02 %).
    if (flips.onBoundary(x.a) || flips.onBoundary(x.b) || flips.onBoundary(x.p) || flips.onBoundary(x.q)) continue;
    if (last && ((x.p == last->a && x.q == last->b) || (x.p == last->b && x.q == last->a))) continue;  // not back
    const int delta = flips.change(x);
    if (delta > 0 || (delta == 0 && depth <= 1)) continue;
    if (!flips.keepsShape(x, flips.quadNormal(x))) continue;
    --budget;
    flips.apply(x);
    done.push_back(x);
    if (delta < 0) return true;
    std::vector<int> next;
    for (int v : {x.a, x.b, x.p, x.q})
      if (flips.irregular(v)) next.push_back(v);
    if (!next.empty() && glideFrom(flips, next, depth - 1, &x, budget, done)) return true;
    done.pop_back();
    flips.undo(x);
  }
  return false;
}

}  // namespace

// Flips of a glide sequence at most, flips tried from one vertex at most (the sweeps' searches tried 160-580 at most,
// 11 on average), flips tried in all per vertex of the mesh, and rounds over the vertices.
constexpr int kGlideDepth = 8, kGlideBudget = 2048, kGlideShare = 16, kGlideRounds = 4;

int improveValences(TriMesh& T, const Surface& surface, bool glide, const CancelFlag* cancel) {
  const int nv = static_cast<int>(T.V.rows()), nf = static_cast<int>(T.F.rows());
  if (nf == 0) return 0;
  Flips flips(T);
  int count = 0;
  // When each edge (3 f + c) was last judged by the greedy passes, -1 before: judged again only where a flip since
  // stamped a corner of its triangle (the same flips as judging every edge in every pass; 114 -> 35 ms at 100k
  // faces, and the greedy pass after the glides judges only the edges around them).
  std::vector<long long> judged(3 * static_cast<std::size_t>(nf), -1);
  auto greedy = [&]() {
    for (int pass = 0; pass < 8; ++pass) {
      checkCancel(cancel);
      int flipped = 0;
      for (int f = 0; f < nf; ++f)
        for (int c = 0; c < 3; ++c) {
          Flips::Flip x;
          const int a = T.F(f, c), b = T.F(f, (c + 1) % 3), p = T.F(f, (c + 2) % 3);
          if (a > b) continue;
          long long& at = judged[3 * static_cast<std::size_t>(f) + c];
          if (at >= 0 && flips.stamp(a) <= at && flips.stamp(b) <= at && flips.stamp(p) <= at) continue;
          at = flips.clock();
          if (!flips.flippable(f, c, x) || flips.change(x) >= 0) continue;
          if (!flips.keepsShape(x, surface.closestPoint(flips.centre(x)).normal)) continue;
          flips.apply(x);
          ++flipped;
        }
      count += flipped;
      if (flipped == 0) break;
    }
  };
  greedy();
  // Then dislocations glided together (kGlideDepth flips at most from each irregular vertex), and the greedy
  // flips again where that left a lower sum within one flip.
  // All the searches together try at most kGlideShare flips per vertex of the mesh (on the sweeps about one in all).
  long long left = static_cast<long long>(kGlideShare) * nv;
  for (int round = 0; glide && round < kGlideRounds && left > 0; ++round) {
    int glided = 0;
    for (int v = 0; v < nv && left > 0; ++v) {
      if (v % 1024 == 0) checkCancel(cancel);
      if (!flips.irregular(v) || flips.onBoundary(v)) continue;
      std::vector<Flips::Flip> done;
      const int budget = static_cast<int>(std::min<long long>(kGlideBudget, left));
      int unused = budget;
      if (glideFrom(flips, {v}, kGlideDepth, nullptr, unused, done)) glided += static_cast<int>(done.size());
      left -= budget - unused;
    }
    count += glided;
    if (glided == 0) break;
  }
  if (glide) greedy();
  return count;
}

}  // namespace phex::global
