#include "phex/surface.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

namespace phex {

std::vector<LocalGeometry> ParametricSurface::samples(int count) const {
  const Domain d = domain();
  const int side = std::max(1, static_cast<int>(std::lround(std::sqrt(std::max(count, 1)))));
  std::vector<LocalGeometry> out;
  out.reserve(side * side);
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j)
      out.push_back(geometryAt(d.u0 + (d.u1 - d.u0) * (i + 0.5) / side, d.v0 + (d.v1 - d.v0) * (j + 0.5) / side));
  return out;
}

LocalGeometry ParametricSurface::geometryAt(double u, double v) const {
  const Jet j = jet(u, v);
  LocalGeometry g;
  g.point = j.P;
  Vec3 n = j.Pu.cross(j.Pv);
  const double nn = n.norm();
  if (!(nn > 0)) {
    // Degenerate parametrization (a pole): fall back to a neighbouring regular point for the frame.
    const Domain d = domain();
    const double eps = 1e-7 * std::max(d.u1 - d.u0, d.v1 - d.v0);
    const Jet k = jet(u, v + (v > 0.5 * (d.v0 + d.v1) ? -eps : eps));
    n = k.Pu.cross(k.Pv);
  }
  n.normalize();
  g.normal = n;
  // First and second fundamental forms; the shape operator's eigenpairs solve (-II) a = k I a,
  // the sign making k > 0 where the surface bends away from the normal.
  Eigen::Matrix2d I, II;
  I << j.Pu.dot(j.Pu), j.Pu.dot(j.Pv), j.Pu.dot(j.Pv), j.Pv.dot(j.Pv);
  II << -j.Puu.dot(n), -j.Puv.dot(n), -j.Puv.dot(n), -j.Pvv.dot(n);
  if (!(I.determinant() > 1e-300)) {
    g.d1 = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
    g.d2 = n.cross(g.d1);
    return g;
  }
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix2d> es(II, I);
  const Eigen::Vector2d k = es.eigenvalues();  // ascending
  const Eigen::Matrix2d a = es.eigenvectors();
  g.k1 = k(1);
  g.k2 = k(0);
  g.d1 = (a(0, 1) * j.Pu + a(1, 1) * j.Pv).normalized();
  // d2 from the frame so that (d1, d2, n) is right-handed and exactly orthonormal.
  g.d1 = (g.d1 - g.d1.dot(n) * n).normalized();
  g.d2 = n.cross(g.d1);
  return g;
}

Vec2 ParametricSurface::normalize(Vec2 uv) const {
  const Domain d = domain();
  auto wrap = [](double x, double a, double b) {
    const double p = b - a;
    x = std::fmod(x - a, p);
    if (x < 0) x += p;
    return a + x;
  };
  uv.x() = d.periodicU ? wrap(uv.x(), d.u0, d.u1) : std::clamp(uv.x(), d.u0, d.u1);
  uv.y() = d.periodicV ? wrap(uv.y(), d.v0, d.v1) : std::clamp(uv.y(), d.v0, d.v1);
  return uv;
}

Vec2 ParametricSurface::project(const Vec3& p, Vec2 uv) const {
  // Newton's method on f(u, v) = |P(u, v) - p|^2 / 2, with a gradient step when the Hessian is indefinite.
  uv = normalize(uv);
  for (int it = 0; it < 50; ++it) {
    const Jet j = jet(uv.x(), uv.y());
    const Vec3 r = j.P - p;
    const Eigen::Vector2d g(j.Pu.dot(r), j.Pv.dot(r));
    Eigen::Matrix2d H;
    H << j.Pu.dot(j.Pu) + j.Puu.dot(r), j.Pu.dot(j.Pv) + j.Puv.dot(r), j.Pu.dot(j.Pv) + j.Puv.dot(r),
        j.Pv.dot(j.Pv) + j.Pvv.dot(r);
    // The step -A^-1 g for a symmetric 2 x 2 A, in closed form.
    auto stepFor = [&g](const Eigen::Matrix2d& A) {
      const double det = A(0, 0) * A(1, 1) - A(0, 1) * A(0, 1);
      return Eigen::Vector2d(-(A(1, 1) * g.x() - A(0, 1) * g.y()) / det, -(A(0, 0) * g.y() - A(0, 1) * g.x()) / det);
    };
    Eigen::Vector2d step;
    if (H.determinant() > 0 && H(0, 0) > 0) {
      step = stepFor(H);
    } else {
      Eigen::Matrix2d I;
      I << j.Pu.dot(j.Pu), j.Pu.dot(j.Pv), j.Pu.dot(j.Pv), j.Pv.dot(j.Pv);
      step = stepFor(I);  // Gauss-Newton step
    }
    if (!step.allFinite()) break;
    const Vec2 next = normalize(uv + step);
    const double moved = (next - uv).norm();
    uv = next;
    if (moved < 1e-15 * (1.0 + uv.norm())) break;
  }
  return uv;
}

void ParametricSurface::ensureSeeds() const {
  if (seedsReady_.value.load(std::memory_order_acquire)) return;
  static std::mutex building;
  const std::lock_guard<std::mutex> lock(building);
  if (seedsReady_.value.load(std::memory_order_relaxed)) return;
  seedPoints_.clear();
  seedParams_.clear();
  const Domain d = domain();
  constexpr int n = 64;
  for (int i = 0; i <= n; ++i)
    for (int k = 0; k <= n; ++k) {
      const Vec2 uv(d.u0 + (d.u1 - d.u0) * i / n, d.v0 + (d.v1 - d.v0) * k / n);
      seedParams_.push_back(uv);
      seedPoints_.push_back(position(uv.x(), uv.y()));
    }
  // A uniform grid over the seeds (counting sort by cell) so a query looks at nearby cells only.
  Box3 box;
  for (const Vec3& q : seedPoints_) box.extend(q);
  const Vec3 size = box.sizes().cwiseMax(1e-12 * (1.0 + box.sizes().maxCoeff()));
  grid_.cell = size.maxCoeff() / 24.0;
  grid_.origin = box.min();
  for (int a = 0; a < 3; ++a) grid_.dims[a] = std::max(1, static_cast<int>(std::ceil(size[a] / grid_.cell)) + 1);
  std::vector<int> cellOf(seedPoints_.size());
  grid_.start.assign(static_cast<std::size_t>(grid_.dims[0]) * grid_.dims[1] * grid_.dims[2] + 1, 0);
  for (std::size_t i = 0; i < seedPoints_.size(); ++i) {
    cellOf[i] = grid_.index(grid_.cellOf(seedPoints_[i]));
    ++grid_.start[cellOf[i] + 1];
  }
  for (std::size_t c = 1; c < grid_.start.size(); ++c) grid_.start[c] += grid_.start[c - 1];
  grid_.ids.resize(seedPoints_.size());
  std::vector<int> fill(grid_.start.begin(), grid_.start.end() - 1);
  for (std::size_t i = 0; i < seedPoints_.size(); ++i) grid_.ids[fill[cellOf[i]]++] = static_cast<int>(i);
  seedsReady_.value.store(true, std::memory_order_release);
}

Eigen::Vector3i ParametricSurface::SeedGrid::cellOf(const Vec3& p) const {
  Eigen::Vector3i c;
  for (int a = 0; a < 3; ++a) c[a] = gridCell((p[a] - origin[a]) / cell, dims[a]);
  return c;
}

int ParametricSurface::SeedGrid::index(const Eigen::Vector3i& c) const { return (c.z() * dims[1] + c.y()) * dims[0] + c.x(); }

std::size_t ParametricSurface::nearestSeed(const Vec3& p) const {
  // Rings of cells around p's (clamped) cell, until no unvisited cell can hold a nearer seed: every seed
  // outside the block of cells searched so far is at least as far from p as the nearest face of that
  // block that is not on the grid's border (no seed lies beyond the border).
  const Eigen::Vector3i c0 = grid_.cellOf(p);
  std::size_t best = 0;
  double bestD = std::numeric_limits<double>::infinity();
  const int maxRing = grid_.dims.maxCoeff();
  for (int r = 0; r <= maxRing; ++r) {
    const Eigen::Vector3i lo = c0 - Eigen::Vector3i::Constant(r), hi = c0 + Eigen::Vector3i::Constant(r);
    for (int z = std::max(lo.z(), 0); z <= std::min(hi.z(), grid_.dims[2] - 1); ++z)
      for (int y = std::max(lo.y(), 0); y <= std::min(hi.y(), grid_.dims[1] - 1); ++y) {
        const bool inner = z != lo.z() && z != hi.z() && y != lo.y() && y != hi.y();
        // Inside the ring's shell only the two cells at x = lo, hi; on its faces the whole row.
        const int step = inner ? std::max(1, 2 * r) : 1;
        for (int x = lo.x(); x <= hi.x(); x += step) {
          if (x < 0 || x >= grid_.dims[0]) continue;
          const int cell = (z * grid_.dims[1] + y) * grid_.dims[0] + x;
          for (int k = grid_.start[cell]; k < grid_.start[cell + 1]; ++k) {
            const double dd = (seedPoints_[grid_.ids[k]] - p).squaredNorm();
            if (dd < bestD) bestD = dd, best = static_cast<std::size_t>(grid_.ids[k]);
          }
        }
      }
    double reach = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (lo[a] > 0) reach = std::min(reach, p[a] - (grid_.origin[a] + lo[a] * grid_.cell));
      if (hi[a] < grid_.dims[a] - 1) reach = std::min(reach, grid_.origin[a] + (hi[a] + 1) * grid_.cell - p[a]);
    }
    if (reach == std::numeric_limits<double>::infinity() || (reach > 0 && bestD <= reach * reach)) break;
  }
  return best;
}

LocalGeometry ParametricSurface::closestPoint(const Vec3& p) const {
  ensureSeeds();
  const std::size_t seed = nearestSeed(p);
  Vec2 uv = project(p, seedParams_[seed]);
  // Newton may settle on a farther local minimum than its seed on strongly curved patches.
  if ((position(uv.x(), uv.y()) - p).squaredNorm() > (seedPoints_[seed] - p).squaredNorm()) uv = seedParams_[seed];
  return geometryAt(uv.x(), uv.y());
}

Box3 ParametricSurface::bounds() const {
  ensureSeeds();
  Box3 b;
  for (const Vec3& q : seedPoints_) b.extend(q);
  return b;
}

bool ParametricSurface::isClosed() const {
  const Domain d = domain();
  return d.periodicU && d.periodicV;
}

std::vector<std::vector<Vec3>> ParametricSurface::boundaryCurves() const {
  const Domain d = domain();
  const int n = kBoundarySamples;
  auto along = [&](bool alongU, double fixed, std::vector<Vec3>& out, bool reverse) {
    for (int i = 0; i < n; ++i) {
      const double t = double(reverse ? n - i : i) / n;
      out.push_back(alongU ? position(d.u0 + t * (d.u1 - d.u0), fixed) : position(fixed, d.v0 + t * (d.v1 - d.v0)));
    }
  };
  std::vector<std::vector<Vec3>> loops;
  if (d.periodicU && d.periodicV) return loops;
  if (d.periodicU || d.periodicV) {  // two rims, the edges at both ends of the direction that does not wrap
    for (const double end : {0.0, 1.0}) {
      std::vector<Vec3> loop;
      if (d.periodicU) along(true, d.v0 + end * (d.v1 - d.v0), loop, end > 0);
      else along(false, d.u0 + end * (d.u1 - d.u0), loop, end == 0);
      loops.push_back(std::move(loop));
    }
    return loops;
  }
  // One loop around the rectangle: v = v0, u = u1, v = v1 (backwards), u = u0 (backwards).
  std::vector<Vec3> loop;
  along(true, d.v0, loop, false);
  along(false, d.u1, loop, false);
  along(true, d.v1, loop, true);
  along(false, d.u0, loop, true);
  loops.push_back(std::move(loop));
  return loops;
}

}  // namespace phex
