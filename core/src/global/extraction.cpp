// phex — the global method's triangle mesh: the lattice's points as vertices, connected as the dual of their
// Voronoi regions on the field mesh, with vertices along the boundary curves.
#include <algorithm>
#include <array>
#include <limits>
#include <cstdint>
#include <map>
#include <numeric>
#include <queue>
#include <sstream>

#include "global.hpp"
#include "phex/error.hpp"
#include "phex/parallel.hpp"

namespace phex::global {
namespace {

// Lattice points of two neighbouring vertices closer than this (in cells, Dupin metric) are one point.
constexpr double kSamePoint = 0.4;
// Two sites closer than this (in cells) are merged.
constexpr double kMergeSites = 0.5;
// Boundary sites: no two closer than kBoundaryMin cells along the boundary; a gap over kBoundaryGap cells gets
// sites in between.
constexpr double kBoundaryMin = 0.5, kBoundaryGap = 1.4;
// A boundary turning by more than this (degrees) over about a third of a cell (kCornerReach) on either side, and over
// a cell (kCornerSpan), is a corner: a site.
constexpr double kCornerTurn = 1 - 0.76604444311897801;  // 1 - cos 40 degrees
constexpr double kCornerReach = 0.33, kCornerSpan = 1.0;
// A region reaching farther than this from its site (cells) has a lattice point missing: a site is added there.
constexpr double kFarInRegion = 1.0;
// An interior site whose region touches the boundary is dropped when nearer to it than this (cells).
constexpr double kNearBoundary = 0.6;
// An interior site nearer to a boundary edge of the triangulation than this share of the edge is dropped.
constexpr double kNearBoundaryEdge = 0.35;
constexpr int kMaxRounds = 12;

struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  }
  void unite(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

struct Site {
  Vec3 p;         // position (on the surface, or on a boundary loop)
  int seed = -1;  // a fine vertex next to it, where its region starts
  int loop = -1;  // its boundary loop, or -1 for an interior site
};

class Extractor {
 public:
  Extractor(const Surface& surface, const FieldMesh& m, const std::vector<Vec3>& o, const std::vector<double>& scale,
            double cell)
      : surface_(surface), m_(m), o_(o), scale_(scale), cell_(cell) {}

  Extraction run(const CancelFlag* cancel) {
    clusterSites();
    boundarySites();
    // For label(), which grows the regions once per round: cells(d, v) as the length of (a . d, b . d), the Dupin
    // frame's axes scaled by sigma and 1 / sigma over the cell there (they are tangent: d's normal part drops out).
    axes_.resize(m_.vertexCount());
    for (int v = 0; v < m_.vertexCount(); ++v) {
      const Frame& f = m_.frame[v];
      axes_[v] = {f.sigma / h(v) * f.t, f.b() / (f.sigma * h(v))};
    }
    Extraction out;
    int repairs = 0;
    for (int round = 0;; ++round) {
      checkCancel(cancel);
      if (round == 0) label();
      else relabel();
      if (round >= kMaxRounds) break;
      const int changes = repair(round);
      if (changes == 0) break;
      repairs += changes;
    }
    out.repairs = repairs;
    std::vector<int> bad;
    std::vector<int> siteOf;
    out.mesh = dual(bad, &out.seeds, &siteOf);
    const int notches = closeNotches(out.mesh, siteOf);
    if (!bad.empty()) {
      std::ostringstream s;
      s.precision(4);
      const Vec3 at = sites_[bad.front()].p;
      s << "the lattice's Voronoi regions leave " << bad.size() << " vertices of the triangulation non-manifold, the first near ("
        << at.x() << ", " << at.y() << ", " << at.z() << "): a smaller cell resolves the surface there";
      throw Error(ErrorCode::CannotTile, s.str());
    }
    // Components of the surface no triangle stands on (smaller than a cell, or too thin for the lattice): named.
    std::vector<char> laid(m_.components, 0);
    for (int f = 0; f < out.mesh.F.rows(); ++f) laid[m_.component[out.seeds[out.mesh.F(f, 0)]]] = 1;
    std::vector<double> area(m_.components, 0.0);
    std::vector<Vec3> centre(m_.components, Vec3::Zero());
    for (int v = 0; v < m_.vertexCount(); ++v) area[m_.component[v]] += m_.area[v], centre[m_.component[v]] += m_.area[v] * m_.point(v);
    for (int c = 0; c < m_.components; ++c) {
      if (laid[c]) continue;
      std::ostringstream n;
      n.precision(4);
      const Vec3 at = area[c] > 0 ? Vec3(centre[c] / area[c]) : Vec3::Zero();
      n << "a part of the surface (area " << area[c] << ") near (" << at.x() << ", " << at.y() << ", " << at.z()
        << ") is too small for the cell " << cell_ << " and was left without panels: a smaller cell tiles it";
      notes_.push_back(n.str());
    }
    notes_.insert(notes_.begin(), "global triangulation: " + std::to_string(out.mesh.V.rows()) + " vertices (" +
                                      std::to_string(boundarySiteCount()) + " on the boundary), " +
                                      std::to_string(repairs) + (repairs == 1 ? " lattice point" : " lattice points") +
                                      " added or removed to connect the regions" +
                                      (notches > 0 ? ", " + std::to_string(notches) + " notches in the boundary closed" : ""));
    out.notes = notes_;
    return out;
  }

 private:
  double h(int v) const { return cell_ * scale_[v]; }
  // The length of d in cells, in the Dupin frame of fine vertex v.
  double cells(const Vec3& d, int v) const { return norm(m_.frame[v].toDupin(tangential(d, m_.frame[v].n))) / h(v); }
  double edgeCells(int a, int b) const {
    const Vec3 d = m_.point(b) - m_.point(a);
    return 0.5 * (cells(d, a) + cells(d, b));
  }

  // The position field's points, one per cluster of neighbouring fine vertices that round to the same point.
  void clusterSites() {
    const int nv = m_.vertexCount();
    DisjointSets sets(nv);
    for (int v = 0; v < nv; ++v)
      for (int i = m_.start[v]; i < m_.start[v + 1]; ++i) {
        const int u = m_.adjacent[i];
        if (u < v) continue;
        const Vec3 d = o_[u] - o_[v];
        if (cells(d, v) < kSamePoint && std::abs(dot(d, m_.frame[v].n)) < kSamePoint * h(v)) sets.unite(u, v);
      }
    // Clusters whose points lie closer than kMergeSites and touch are one.
    std::vector<int> root(nv);
    for (int v = 0; v < nv; ++v) root[v] = sets.find(v);
    std::vector<Vec3> sum(nv, Vec3::Zero());
    std::vector<int> members(nv, 0);
    for (int v = 0; v < nv; ++v) sum[root[v]] += o_[v], ++members[root[v]];
    for (int v = 0; v < nv; ++v)
      for (int i = m_.start[v]; i < m_.start[v + 1]; ++i) {
        const int u = m_.adjacent[i];
        const int a = root[v], b = root[u];
        if (a == b) continue;
        if (cells(sum[a] / members[a] - sum[b] / members[b], v) < kMergeSites) sets.unite(a, b);
      }
    std::vector<int> index(nv, -1);
    std::vector<int> rootOf(nv);
    for (int v = 0; v < nv; ++v) rootOf[v] = sets.find(v);
    std::fill(sum.begin(), sum.end(), Vec3::Zero());
    std::fill(members.begin(), members.end(), 0);
    clusterHasBoundary_.assign(nv, 0);
    for (int v = 0; v < nv; ++v) {
      sum[rootOf[v]] += o_[v], ++members[rootOf[v]];
      if (m_.boundary[v]) clusterHasBoundary_[rootOf[v]] = 1;
    }
    clusterOf_ = rootOf;
    for (int v = 0; v < nv; ++v) {
      const int r = rootOf[v];
      if (index[r] < 0 && !clusterHasBoundary_[r]) {
        index[r] = static_cast<int>(sites_.size());
        Site s;
        s.p = sum[r] / members[r];
        sites_.push_back(s);
      }
    }
    // Seeds: the member nearest the point; the point itself projected onto the surface.
    std::vector<double> best(sites_.size(), std::numeric_limits<double>::infinity());
    for (int v = 0; v < nv; ++v) {
      const int s = index[rootOf[v]];
      if (s < 0) continue;
      const double d = (m_.point(v) - sites_[s].p).squaredNorm();
      if (d < best[s]) best[s] = d, sites_[s].seed = v;
    }
    parallelRanges(static_cast<int>(sites_.size()), kPointsPerThread, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) sites_[i].p = surface_.closestPoint(sites_[i].p).point;
    });
  }

  // Sites along every boundary loop: at its corners, at the lattice's points on it, and in the gaps between.
  void boundarySites() {
    for (int l = 0; l < static_cast<int>(m_.loops.size()); ++l) {
      const std::vector<int>& loop = m_.loops[l];
      const int n = static_cast<int>(loop.size());
      if (n < 3) continue;
      std::vector<double> s(n + 1, 0.0);  // arc length in cells at each vertex, s[n] the loop's length
      for (int i = 0; i < n; ++i) s[i + 1] = s[i] + edgeCells(loop[i], loop[(i + 1) % n]);
      const double L = s[n];
      struct Candidate {
        double at;
        int priority;
      };
      std::vector<Candidate> candidates;
      // Corners: the direction over about a third of a cell on either side turns by more than kCornerDegrees, and
      // more than at the neighbours.
      // The turn over `reach` cells on either side of loop vertex i.
      auto turnAt = [&](int i, double reach) {
        int back = i, ahead = i;
        for (int k = 0; k < n / 2 && arcBetween(s, L, back, i) < reach; ++k) back = (back + n - 1) % n;
        for (int k = 0; k < n / 2 && arcBetween(s, L, i, ahead) < reach; ++k) ahead = (ahead + 1) % n;
        const Vec3& nn = m_.frame[loop[i]].n;
        const Vec3 a = normalized(tangential(m_.point(loop[i]) - m_.point(loop[back]), nn));
        const Vec3 b = normalized(tangential(m_.point(loop[ahead]) - m_.point(loop[i]), nn));
        return 1 - dot(a, b);  // grows with the angle (no libm: the same bits in every build)
      };
      std::vector<double> turn(n, 0.0);
      for (int i = 0; i < n; ++i) turn[i] = turnAt(i, kCornerReach);
      // A corner turns over a cell on either side too: a jagged boundary (an upload's rows ending in a zigzag, each
      // of its vertices turning 60 degrees) turns at every vertex over a third of a cell and not at all over a cell.
      for (int i = 0; i < n; ++i)
        if (turn[i] > kCornerTurn && turn[i] >= turn[(i + n - 1) % n] && turn[i] > turn[(i + 1) % n] &&
            turnAt(i, kCornerSpan) > kCornerTurn)
          candidates.push_back({s[i], 2});
      // The lattice's points on the boundary: per cluster with boundary vertices, its vertex nearest the point,
      // moved along the tangent to the point.
      std::map<int, std::pair<double, double>> byCluster;  // cluster -> (distance, arc)
      for (int i = 0; i < n; ++i) {
        const int v = loop[i];
        const Vec3 d = o_[v] - m_.point(v);
        const double dist = cells(d, v);
        const double along = dot(d, m_.boundaryTangent[v]) * norm(m_.frame[v].toDupin(m_.boundaryTangent[v])) / h(v);
        double at = s[i] + along;
        at -= L * std::floor(at / L);
        auto it = byCluster.find(clusterOf_[v]);
        if (it == byCluster.end() || dist < it->second.first) byCluster[clusterOf_[v]] = {dist, at};
      }
      for (const auto& [cluster, value] : byCluster)
        if (value.first < 0.5) candidates.push_back({value.second, 1});
      // Kept by priority, then along the loop, none within kBoundaryMin of one kept.
      std::stable_sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
        return a.priority != b.priority ? a.priority > b.priority : a.at < b.at;
      });
      std::vector<double> kept;
      for (const Candidate& c : candidates) {
        bool near = false;
        for (double k : kept) near = near || cyclicGap(k, c.at, L) < kBoundaryMin;
        if (!near) kept.push_back(c.at);
      }
      std::sort(kept.begin(), kept.end());
      std::vector<double> all;
      if (kept.empty()) {
        const int count = std::max(3, static_cast<int>(std::lround(L)));
        for (int i = 0; i < count; ++i) all.push_back(L * i / count);
      } else {
        for (std::size_t i = 0; i < kept.size(); ++i) {
          const double a = kept[i], b = i + 1 < kept.size() ? kept[i + 1] : kept[0] + L;
          all.push_back(a);
          const double gap = b - a;
          if (gap > kBoundaryGap) {
            const int parts = std::max(2, static_cast<int>(std::lround(gap)));
            for (int k = 1; k < parts; ++k) all.push_back(a + gap * k / parts);
          }
        }
        if (all.size() < 3) {  // a small hole: a triangle of sites around it
          const double a = all.front();
          all = {a, a + L / 3, a + 2 * L / 3};
        }
      }
      for (double at : all) {
        at -= L * std::floor(at / L);
        const int i = static_cast<int>(std::upper_bound(s.begin(), s.end(), at) - s.begin()) - 1;
        const int a = std::clamp(i, 0, n - 1), b = (a + 1) % n;
        const double len = s[a + 1] - s[a];
        const double w = len > 0 ? std::clamp((at - s[a]) / len, 0.0, 1.0) : 0.0;
        Site site;
        site.p = (1 - w) * m_.point(loop[a]) + w * m_.point(loop[b]);
        site.seed = w < 0.5 ? loop[a] : loop[b];
        site.loop = l;
        sites_.push_back(site);
      }
    }
  }
  static double cyclicGap(double a, double b, double L) {
    const double d = std::abs(a - b);
    return std::min(d, L - d);
  }
  static double arcBetween(const std::vector<double>& s, double L, int from, int to) {
    const double d = s[to] - s[from];
    return d >= 0 ? d : d + L;
  }
  int boundarySiteCount() const {
    int n = 0;
    for (const Site& s : sites_) n += s.loop >= 0;
    return n;
  }

  // Every fine vertex to its nearest site (in the Dupin metric, in cells), regions grown from the seeds outwards.
  void label() {
    const int nv = m_.vertexCount();
    label_.assign(nv, -1);
    dist_.assign(nv, std::numeric_limits<double>::infinity());
    Queue queue;
    for (int s = 0; s < static_cast<int>(sites_.size()); ++s) seed(s);
    for (int v = 0; v < nv; ++v)
      if (label_[v] >= 0) queue.push({dist_[v], v});
    grow(queue);
  }

  // label() after a round of mending (repair): the regions of the sites it removed emptied and grown over by their
  // neighbours, the sites it added grown from their seeds, the rest kept. The regions come out as label() grows
  // them afresh but where two reach a vertex in another order (the sweeps' runs the same bit for bit; the generated
  // genus 2 and 3, mending 20 and more points over several rounds, other lays as good); at 100k faces the second
  // label() of the bench's upload, for two sites changed, took 0.58 s.
  void relabel() {
    const int nv = m_.vertexCount();
    std::vector<char> emptied(nv, 0);
    for (int v = 0; v < nv; ++v) {
      if (label_[v] < 0) continue;
      label_[v] = renumbered_[label_[v]];
      if (label_[v] < 0) dist_[v] = std::numeric_limits<double>::infinity(), emptied[v] = 1;
    }
    Queue queue;
    for (int v = 0; v < nv; ++v) {
      if (label_[v] < 0) continue;
      for (int i = m_.start[v]; i < m_.start[v + 1]; ++i)
        if (emptied[m_.adjacent[i]]) {
          queue.push({dist_[v], v});
          break;
        }
    }
    for (int s = firstAdded_; s < static_cast<int>(sites_.size()); ++s)
      if (seed(s)) queue.push({dist_[sites_[s].seed], sites_[s].seed});
    grow(queue);
  }

  using Queue = std::priority_queue<std::pair<double, int>, std::vector<std::pair<double, int>>, std::greater<>>;
  // The length of d in cells at fine vertex v (the Dupin frame's axes over the cell: axes_).
  double cellsTo(const Vec3& d, int v) const {
    const double a = dot(axes_[v][0], d), b = dot(axes_[v][1], d);
    return std::sqrt(a * a + b * b);
  }
  // Site s's seed labelled s where it is nearer to s than to the site it has (of two at one seed, the first).
  bool seed(int s) {
    const int v = sites_[s].seed;
    const double d = cellsTo(m_.point(v) - sites_[s].p, v);
    if (!(d < dist_[v] || (d == dist_[v] && s < label_[v]))) return false;
    dist_[v] = d, label_[v] = s;
    return true;
  }
  // The regions grown from the vertices queued, each vertex to the nearest site whose region reaches it.
  void grow(Queue& queue) {
    while (!queue.empty()) {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > dist_[v]) continue;
      for (int i = m_.start[v]; i < m_.start[v + 1]; ++i) {
        const int u = m_.adjacent[i];
        // The distance to the site itself (not along the mesh): the regions' borders then lie where the sites'
        // own Voronoi regions' do, to within a fine edge, and each region stays connected (grown from its seed).
        const double du = cellsTo(m_.point(u) - sites_[label_[v]].p, u);
        if (du < dist_[u]) dist_[u] = du, label_[u] = label_[v], queue.push({du, u});
      }
    }
  }

  // The triangles where three regions meet; `bad` gets the sites whose star is not a manifold fan (or disk).
  // `siteOf` gets, per vertex of the result, its site.
  TriMesh dual(std::vector<int>& bad, std::vector<int>* seeds = nullptr, std::vector<int>* siteOf = nullptr) const {
    const int ns = static_cast<int>(sites_.size());
    std::vector<std::array<int, 3>> tris;
    for (int f = 0; f < m_.F.rows(); ++f) {
      const int a = label_[m_.F(f, 0)], b = label_[m_.F(f, 1)], c = label_[m_.F(f, 2)];
      if (a < 0 || b < 0 || c < 0 || a == b || b == c || a == c) continue;
      tris.push_back({a, b, c});
    }
    // Sites whose regions touch the boundary of the field mesh.
    std::vector<char> touches(ns, 0);
    for (int v = 0; v < m_.vertexCount(); ++v)
      if (m_.boundary[v] && label_[v] >= 0) touches[label_[v]] = 1;
    // The link of every site: the edges opposite it in its triangles, which must make one path (a region on the
    // boundary) or one cycle.
    std::vector<std::vector<std::pair<int, int>>> link(ns);
    for (const auto& t : tris)
      for (int k = 0; k < 3; ++k) link[t[k]].push_back({t[(k + 1) % 3], t[(k + 2) % 3]});
    std::vector<char> isBad(ns, 0);
    for (int s = 0; s < ns; ++s) {
      const auto& e = link[s];
      if (e.empty()) continue;  // a region with no triangle: dropped with the unused sites
      // The link's edges a -> b (a handful: searched in place rather than mapped).
      auto from = [&](int a) {  // the edge out of a, or null
        for (const auto& edge : e)
          if (edge.first == a) return &edge;
        return static_cast<const std::pair<int, int>*>(nullptr);
      };
      auto into = [&](int b) {
        for (const auto& edge : e)
          if (edge.second == b) return true;
        return false;
      };
      bool ok = true;
      for (std::size_t i = 0; i < e.size() && ok; ++i)  // no two edges out of one vertex, nor into one
        for (std::size_t j = 0; j < i && ok; ++j) ok = e[j].first != e[i].first && e[j].second != e[i].second;
      if (ok) {
        // One path (a region on the boundary) or one cycle through all the link's edges.
        int first = e.front().first, starts = 0;
        for (const auto& [a, b] : e)
          if (!into(a)) first = a, ++starts;
        int steps = 0, v = first;
        while (steps <= static_cast<int>(e.size()) && from(v)) {
          v = from(v)->second, ++steps;
          if (v == first) break;
        }
        ok = steps == static_cast<int>(e.size()) && (touches[s] ? starts == 1 : starts == 0 && v == first);
      }
      if (!ok) isBad[s] = 1;
    }
    for (int s = 0; s < ns; ++s)
      if (isBad[s]) bad.push_back(s);
    // The mesh of the used sites.
    std::vector<int> id(ns, -1);
    TriMesh out;
    int count = 0;
    for (const auto& t : tris)
      for (int k = 0; k < 3; ++k)
        if (id[t[k]] < 0) id[t[k]] = count++;
    out.V.resize(count, 3);
    if (seeds) seeds->assign(count, -1);
    if (siteOf) siteOf->assign(count, -1);
    for (int s = 0; s < ns; ++s)
      if (id[s] >= 0) {
        if (siteOf) (*siteOf)[id[s]] = s;
        out.V.row(id[s]) = sites_[s].p.transpose();
        if (seeds) (*seeds)[id[s]] = sites_[s].seed;
      }
    out.F.resize(static_cast<int>(tris.size()), 3);
    for (std::size_t f = 0; f < tris.size(); ++f)
      for (int k = 0; k < 3; ++k) out.F(static_cast<int>(f), k) = id[tris[f][k]];
    return out;
  }

  // An interior site the rounds of mending left on the triangulation's boundary (its region reaches the boundary
  // curve between two boundary sites that never became neighbours) makes a notch: two boundary edges dipping
  // inside, the surface between them bare (the Concerthall at 1000 faces: one, 0.7 of a cell deep). The triangle
  // of the site and those two boundary sites closes it, where they are not joined already. Returns how many.
  int closeNotches(TriMesh& T, const std::vector<int>& siteOf) const {
    const int nv = static_cast<int>(T.V.rows()), nf = static_cast<int>(T.F.rows());
    const HalfEdges halfEdges(T.F, nv);
    // Per vertex, its boundary half-edges in and out (-1: none; -2: more than one).
    std::vector<int> in(nv, -1), out(nv, -1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = T.F(f, k), b = T.F(f, (k + 1) % 3);
        if (halfEdges.has(b, a)) continue;
        out[a] = out[a] == -1 ? b : -2;
        in[b] = in[b] == -1 ? a : -2;
      }
    std::vector<Eigen::Vector3i> added;
    std::vector<char> used(nv, 0);
    for (int v = 0; v < nv; ++v) {
      const int a = in[v], b = out[v];
      if (a < 0 || b < 0 || a == b || sites_[siteOf[v]].loop >= 0) continue;
      if (sites_[siteOf[a]].loop < 0 || sites_[siteOf[b]].loop < 0 || used[a] || used[b] || used[v]) continue;
      if (halfEdges.has(a, b) || halfEdges.has(b, a)) continue;
      added.push_back(Eigen::Vector3i(v, a, b));  // half-edges v -> a and b -> v pair the boundary's a -> v, v -> b
      used[a] = used[b] = used[v] = 1;
    }
    if (added.empty()) return 0;
    T.F.conservativeResize(nf + static_cast<int>(added.size()), 3);
    for (std::size_t i = 0; i < added.size(); ++i) T.F.row(nf + static_cast<int>(i)) = added[i].transpose();
    return static_cast<int>(added.size());
  }

  // One round of mending: returns how many sites were added or removed.
  // One round of mending (the `round`-th): returns how many sites were added or removed.
  int repair(int round) {
    const int ns = static_cast<int>(sites_.size()), nv = m_.vertexCount();
    std::vector<int> farthest(ns, -1), size(ns, 0);
    for (int v = 0; v < nv; ++v) {
      const int s = label_[v];
      if (s < 0) continue;
      ++size[s];
      if (farthest[s] < 0 || dist_[v] > dist_[farthest[s]]) farthest[s] = v;
    }
    std::vector<char> remove(ns, 0);
    std::vector<Site> added;
    auto addAt = [&](int v) {
      Site s;
      s.p = m_.point(v);
      s.seed = v;
      added.push_back(s);
    };
    // Interior sites whose regions reach the boundary: dropped when near it, else a boundary site is added where
    // they reach it.
    std::vector<int> touchAt(ns, -1);
    for (int v = 0; v < nv; ++v)
      if (m_.boundary[v] && label_[v] >= 0 && sites_[label_[v]].loop < 0)
        if (touchAt[label_[v]] < 0 || dist_[v] < dist_[touchAt[label_[v]]]) touchAt[label_[v]] = v;
    for (int s = 0; s < ns; ++s) {
      if (touchAt[s] < 0) continue;
      if (dist_[touchAt[s]] < kNearBoundary) {
        remove[s] = 1;
      } else {
        Site b;
        b.p = m_.point(touchAt[s]);
        b.seed = touchAt[s];
        b.loop = loopOf(touchAt[s]);
        added.push_back(b);
      }
    }
    // Regions reaching far from their sites: a lattice point is missing there.
    for (int s = 0; s < ns; ++s)
      if (size[s] > 0 && !remove[s] && dist_[farthest[s]] > kFarInRegion) addAt(farthest[s]);
    // Sites whose stars are not manifold: their regions are split.
    std::vector<int> bad;
    std::vector<int> seeds;
    const TriMesh T = dual(bad, &seeds, &siteOf_);
    // Split first; where that has not mended them by half the rounds (a region folded over a crease, where the
    // field mesh's normals turn sharply), the site goes and its neighbours close over it.
    for (int s : bad)
      if (round >= kMaxRounds / 2) remove[s] = 1;
      else if (!remove[s] && dist_[farthest[s]] > 0.25) addAt(farthest[s]);
    // An interior site next to a boundary edge, nearer to it than kNearBoundaryEdge of its length: its triangle is a
    // sliver whose boundary panel no solve makes planar without folding (the rows there meet the boundary
    // slantwise). It goes; its neighbours close over the gap.
    for (int f = 0; f < T.F.rows(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = siteOf_[T.F(f, k)], b = siteOf_[T.F(f, (k + 1) % 3)], c = siteOf_[T.F(f, (k + 2) % 3)];
        if (sites_[a].loop < 0 || sites_[b].loop < 0 || sites_[c].loop >= 0 || remove[c]) continue;
        const Vec3 A = sites_[a].p, B = sites_[b].p, C = sites_[c].p;
        const double len = (B - A).norm();
        if (!(len > 0)) continue;
        const double s = std::clamp((C - A).dot(B - A) / (len * len), 0.0, 1.0);
        if ((A + s * (B - A) - C).norm() < kNearBoundaryEdge * len) remove[c] = 1;
      }
    int changes = static_cast<int>(added.size());
    std::vector<Site> kept;
    renumbered_.assign(ns, -1);
    for (int s = 0; s < ns; ++s) {
      if (remove[s] || size[s] == 0) {
        ++changes;
        continue;
      }
      renumbered_[s] = static_cast<int>(kept.size());
      kept.push_back(sites_[s]);
    }
    firstAdded_ = static_cast<int>(kept.size());
    // An added site near another added one is not added twice.
    for (const Site& a : added) {
      bool near = false;
      for (const Site& k : kept)
        if (k.seed == a.seed) near = true;
      if (!near) kept.push_back(a);
    }
    sites_ = std::move(kept);
    return changes;
  }
  int loopOf(int v) const {
    for (int l = 0; l < static_cast<int>(m_.loops.size()); ++l)
      for (int w : m_.loops[l])
        if (w == v) return l;
    return -1;
  }

  const Surface& surface_;
  const FieldMesh& m_;
  const std::vector<Vec3>& o_;
  const std::vector<double>& scale_;
  double cell_;
  std::vector<Site> sites_;
  std::vector<int> clusterOf_;
  std::vector<char> clusterHasBoundary_;
  std::vector<std::array<Vec3, 2>> axes_;  // per fine vertex, for label() (run sets them)
  std::vector<int> label_, siteOf_;
  std::vector<int> renumbered_;  // per site before the last round of mending, its index after (-1: removed)
  int firstAdded_ = 0;           // the sites that round added: from this index on
  std::vector<double> dist_;
  std::vector<std::string> notes_;
};

}  // namespace

Extraction extractTriangulation(const Surface& surface, const FieldMesh& mesh, const std::vector<Vec3>& o,
                                const std::vector<double>& scale, double cell, const CancelFlag* cancel) {
  return Extractor(surface, mesh, o, scale, cell).run(cancel);
}

}  // namespace phex::global
