// phex — the one interface every algorithm asks about the shape being tiled (§3).
#pragma once
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "phex/geometry.hpp"

namespace phex {

class Surface {
 public:
  virtual ~Surface() = default;

  // Short identifier, e.g. "torus".
  virtual std::string name() const = 0;
  // The point of the surface nearest to p, with its local geometry.
  virtual LocalGeometry closestPoint(const Vec3& p) const = 0;
  // Axis-aligned bounds of the (trimmed) surface.
  virtual Box3 bounds() const = 0;
  // True when the surface has no boundary (sphere, torus, ...).
  virtual bool isClosed() const = 0;
  // About `count` points spread over the surface, with their local geometry (for choices made from an
  // overview of the shape: where to start laying, which family runs along the parabolic curves).
  virtual std::vector<LocalGeometry> samples(int count) const = 0;
  // The boundary as closed polylines (a loop's first point is not repeated at its end), fine enough to stand for
  // the curve at any panel size; none on a closed surface. Boundary nodes of the P-Hex mesh are put on it.
  virtual std::vector<std::vector<Vec3>> boundaryCurves() const = 0;
};

// A surface given by P(u, v) on [u0, u1] x [v0, v1] with exact first and second derivatives.
// A periodic direction wraps around (u1 is the same curve as u0).
class ParametricSurface : public Surface {
 public:
  struct Domain {
    double u0 = 0, u1 = 1, v0 = 0, v1 = 1;
    bool periodicU = false, periodicV = false;
  };
  // Position and its derivatives up to second order at (u, v).
  struct Jet {
    Vec3 P, Pu, Pv, Puu, Puv, Pvv;
  };

  virtual Jet jet(double u, double v) const = 0;
  virtual Domain domain() const = 0;

  Vec3 position(double u, double v) const { return jet(u, v).P; }
  // Normal, principal curvatures and directions at (u, v), from the two fundamental forms.
  LocalGeometry geometryAt(double u, double v) const;
  // A grid over the parameter domain, cell midpoints.
  std::vector<LocalGeometry> samples(int count) const override;
  // Projects p onto the surface by Newton's method on (u, v), starting from `uv`; returns the
  // parameters of the foot point (clamped to the domain, wrapped in periodic directions).
  Vec2 project(const Vec3& p, Vec2 uv) const;

  LocalGeometry closestPoint(const Vec3& p) const override;
  Box3 bounds() const override;
  bool isClosed() const override;
  // The domain's edges in directions that do not wrap, each sampled at kBoundarySamples points.
  std::vector<std::vector<Vec3>> boundaryCurves() const override;
  static constexpr int kBoundarySamples = 2048;

  // Wraps periodic coordinates into the domain and clamps the others.
  Vec2 normalize(Vec2 uv) const;

 private:
  // Samples of the domain that start closestPoint's Newton iteration, bucketed in a uniform grid.
  struct SeedGrid {
    Vec3 origin = Vec3::Zero();
    double cell = 1;
    Eigen::Vector3i dims = Eigen::Vector3i::Ones();
    std::vector<int> start, ids;  // seeds of cell c: ids[start[c] .. start[c+1])
    Eigen::Vector3i cellOf(const Vec3& p) const;
    int index(const Eigen::Vector3i& c) const;
  };
  // Built on first use, once, whichever thread asks first (phex/parallel.hpp: trial lays query one surface
  // at once); copies take the flag with the seeds.
  void ensureSeeds() const;
  std::size_t nearestSeed(const Vec3& p) const;
  struct ReadyFlag {
    std::atomic<bool> value{false};
    ReadyFlag() = default;
    ReadyFlag(const ReadyFlag& o) : value(o.value.load()) {}
    ReadyFlag& operator=(const ReadyFlag& o) {
      value.store(o.value.load());
      return *this;
    }
  };
  mutable ReadyFlag seedsReady_;
  mutable std::vector<Vec3> seedPoints_;
  mutable std::vector<Vec2> seedParams_;
  mutable SeedGrid grid_;
};

using SurfacePtr = std::shared_ptr<const Surface>;
using ParametricSurfacePtr = std::shared_ptr<const ParametricSurface>;

}  // namespace phex
