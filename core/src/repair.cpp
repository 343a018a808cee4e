// phex — local repair of invalid triangle stars (§4.2, Propositions 4 and 5).
//
// A laid triangulation can miss validity at a few stars: where a flow line bends sharply, near umbilics,
// where rows are resampled or fronts zipped, or where the discretization of an uploaded mesh disturbs the
// conjugate directions. Each such vertex is moved a little within the surface, to the position that makes
// its own star and its neighbours' stars valid, judged exactly as checkTriangulation judges them.
#include <algorithm>
#include <cmath>
#include <limits>

#include "phex/duality.hpp"
#include "phex/dupin.hpp"
#include "phex/ideal_triangle.hpp"
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

class Repair {
 public:
  Repair(Triangulation& t, const Surface& surface)
      : t_(t), T_(t.mesh), surface_(surface), rings_(vertexRings(t.mesh)), geo_(vertexGeometry(t, surface)) {
    parametric_ = dynamic_cast<const ParametricSurface*>(&surface);
    if (!parametric_ || static_cast<int>(t.uv.size()) != T_.V.rows()) parametric_ = nullptr;
    const int nv = static_cast<int>(T_.V.rows());
    checkable_ = judgedStars(T_, rings_, geo_, T_.meanEdgeLength());  // the stars checkTriangulation judges
    neighbours_.resize(nv);
    for (int v = 0; v < nv; ++v) {
      for (int f : rings_.triangles[v])
        for (int k = 0; k < 3; ++k)
          if (T_.F(f, k) != v) neighbours_[v].push_back(T_.F(f, k));
      std::sort(neighbours_[v].begin(), neighbours_[v].end());
      neighbours_[v].erase(std::unique(neighbours_[v].begin(), neighbours_[v].end()), neighbours_[v].end());
    }
    original_ = T_.V;
    laidShortest_.resize(nv);
    for (int v = 0; v < nv; ++v) laidShortest_[v] = shortestEdge(v);
  }

  bool invalid(int v) const { return checkable_[v] && starState(v).first > 0; }

  RepairResult run(int maxSweeps) {
    RepairResult r;
    const int nv = static_cast<int>(T_.V.rows());
    std::vector<int> bad;
    for (int v = 0; v < nv; ++v)
      if (invalid(v)) bad.push_back(v);
    r.invalidBefore = static_cast<int>(bad.size());
    std::vector<char> moved(nv, 0);
    for (int sweep = 0; sweep < maxSweeps && !bad.empty(); ++sweep) {
      ++r.sweeps;
      // The invalid stars' centres and their neighbours: moving any of them changes an invalid star.
      std::vector<int> work;
      for (int v : bad) {
        work.push_back(v);
        work.insert(work.end(), neighbours_[v].begin(), neighbours_[v].end());
      }
      std::sort(work.begin(), work.end());
      work.erase(std::unique(work.begin(), work.end()), work.end());
      bool progress = false;
      std::vector<int> changed;  // stars a move touched: the moved vertex's and its neighbours'
      for (int v : work)
        if (rings_.closed[v] && !rings_.triangles[v].empty() && improve(v)) {
          moved[v] = 1, progress = true;
          changed.push_back(v);
          changed.insert(changed.end(), neighbours_[v].begin(), neighbours_[v].end());
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
  // (invalid triangles, total violation) of u's star, with u's own geometry.
  std::pair<int, double> starState(int u) const {
    const LocalGeometry& g = geo_[u];
    int count = 0;
    double total = 0;
    for (int f : rings_.triangles[u]) {
      int k = 0;
      while (T_.F(f, k) != u) ++k;
      const Vec2 a = toTangentPlane(g, T_.V.row(T_.F(f, (k + 1) % 3)).transpose());
      const Vec2 b = toTangentPlane(g, T_.V.row(T_.F(f, (k + 2) % 3)).transpose());
      const TriangleState st = triangleState(g, a, b);
      count += !st.valid;
      total += st.violation;
    }
    return {count, total};
  }

  // The checkable stars that v's position affects: its own and its neighbours'.
  std::pair<int, double> localState(int v) const {
    int count = 0;
    double total = 0;
    auto add = [&](int u) {
      if (!checkable_[u]) return;
      const auto [c, s] = starState(u);
      count += c > 0;
      total += s;
    };
    add(v);
    for (int u : neighbours_[v]) add(u);
    return {count, total};
  }

  // The orientation of v's triangles seen along the surface normal at v: all must keep theirs.
  bool foldsOver(int v, const std::vector<int>& signs) const {
    const Vec3 n = geo_[v].normal;
    int i = 0;
    for (int f : rings_.triangles[v]) {
      const Vec3 a = T_.V.row(T_.F(f, 0)), b = T_.V.row(T_.F(f, 1)), c = T_.V.row(T_.F(f, 2));
      const double s = (b - a).cross(c - a).dot(n);
      if ((s > 0 ? 1 : -1) != signs[i++] || std::abs(s) < 1e-3 * minArea_[v]) return true;
    }
    return false;
  }

  double shortestEdge(int v) const {
    double shortest = std::numeric_limits<double>::infinity();
    for (int u : neighbours_[v]) shortest = std::min(shortest, (T_.V.row(u) - T_.V.row(v)).norm());
    return shortest;
  }

  bool improve(int v) {
    const Vec3 p0 = T_.V.row(v).transpose();
    const LocalGeometry g0 = geo_[v];
    const Vec2 uv0 = parametric_ ? t_.uv[v] : Vec2::Zero();
    std::pair<int, double> best = localState(v);
    if (best.first == 0 && best.second == 0) return false;
    // Orientation of the triangles now, and the ring's size.
    std::vector<int> signs;
    double ringEdge = 0, area = std::numeric_limits<double>::infinity();
    for (int f : rings_.triangles[v]) {
      const Vec3 a = T_.V.row(T_.F(f, 0)), b = T_.V.row(T_.F(f, 1)), c = T_.V.row(T_.F(f, 2));
      const double s = (b - a).cross(c - a).dot(g0.normal);
      signs.push_back(s > 0 ? 1 : -1);
      area = std::min(area, std::abs(s));
    }
    Vec3 centroid = Vec3::Zero();
    for (int u : neighbours_[v]) {
      centroid += T_.V.row(u).transpose();
      ringEdge += (T_.V.row(u).transpose() - p0).norm();
    }
    centroid /= static_cast<double>(neighbours_[v].size());
    ringEdge /= static_cast<double>(neighbours_[v].size());
    if (minArea_.size() != static_cast<std::size_t>(T_.V.rows())) minArea_.assign(T_.V.rows(), 0.0);
    minArea_[v] = area;
    const double cap = 0.4 * ringEdge;  // never further than this from where the laying put the vertex
    const double laidShortest = laidShortest_[v];  // nor shortening its edges much: no narrow layers made

    std::vector<Vec3> candidates;
    const Vec3 toCentroid = centroid - p0;
    for (double s : {1.0, 0.5, 0.25}) candidates.push_back(p0 + s * toCentroid);
    for (double step : {0.15, 0.05, 0.3})
      for (int i = 0; i < 8; ++i) {
        const double angle = i * 3.141592653589793 / 4;
        candidates.push_back(p0 + step * ringEdge * (std::cos(angle) * g0.d1 + std::sin(angle) * g0.d2));
      }

    Vec3 bestPoint = p0;
    LocalGeometry bestGeometry = g0;
    Vec2 bestUv = uv0;
    for (const Vec3& c : candidates) {
      if ((c - original_.row(v).transpose()).norm() > 1.5 * cap) continue;  // would land beyond the cap
      Vec2 uv = uv0;
      LocalGeometry g;
      if (parametric_) {
        uv = parametric_->project(c, uv0);
        g = parametric_->geometryAt(uv.x(), uv.y());
      } else {
        g = surface_.closestPoint(c);
      }
      if (!g.point.allFinite() || (g.point - original_.row(v).transpose()).norm() > cap) continue;
      T_.V.row(v) = g.point.transpose();
      geo_[v] = g;
      if (foldsOver(v, signs) || shortestEdge(v) < 0.75 * laidShortest) continue;
      const std::pair<int, double> s = localState(v);
      if (s.first < best.first || (s.first == best.first && s.second < best.second * (1 - 1e-9) - 1e-15)) {
        best = s;
        bestPoint = g.point;
        bestGeometry = g;
        bestUv = uv;
        if (s.first == 0 && s.second == 0) break;  // every star around is valid with its margins: done
      }
    }
    T_.V.row(v) = bestPoint.transpose();
    geo_[v] = bestGeometry;
    if (parametric_) t_.uv[v] = bestUv;
    return bestPoint != p0;
  }

  Triangulation& t_;
  TriMesh& T_;
  const Surface& surface_;
  const ParametricSurface* parametric_ = nullptr;
  VertexRings rings_;
  std::vector<LocalGeometry> geo_;
  std::vector<char> checkable_;
  std::vector<std::vector<int>> neighbours_;
  std::vector<double> minArea_;
  Points original_;
  std::vector<double> laidShortest_;  // each vertex's shortest edge as laid
};

}  // namespace

RepairResult repairStars(Triangulation& triangulation, const Surface& surface, int maxSweeps) {
  if (triangulation.mesh.F.rows() == 0 || maxSweeps <= 0) return {};
  Repair repair(triangulation, surface);
  const RepairResult r = repair.run(maxSweeps);
  if (r.invalidBefore > 0)
    triangulation.notes.push_back("repaired " + std::to_string(r.invalidBefore - r.invalidAfter) + " of " +
                                  std::to_string(r.invalidBefore) + " invalid stars by moving " +
                                  std::to_string(r.moved) + " vertices within the surface (" +
                                  std::to_string(r.sweeps) + " sweeps)");
  return r;
}

}  // namespace phex
