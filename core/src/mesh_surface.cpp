#include "phex/mesh_surface.hpp"

#include <algorithm>
#include <optional>
#include <array>
#include <cmath>
#include <initializer_list>
#include <cstdio>
#include <limits>
#include <numeric>

#include "phex/dupin.hpp"
#include "phex/error.hpp"
#include "phex/mesh_io.hpp"
#include "phex/parallel.hpp"

namespace phex {
namespace {

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw Error(ErrorCode::InvalidInput, "mesh '" + name + "': " + what);
}

// Sums in a fixed order. Eigen's reductions (dot, norm, products) add in an order that depends on its SIMD
// path: with SSE2 (native) a 3-vector's dot product can come out as (x + y) + z, without SIMD (WebAssembly)
// as x + (y + z). Written out, every platform rounds alike.
inline double dot(const Vec3& a, const Vec3& b) { return a.x() * b.x() + a.y() * b.y() + a.z() * b.z(); }
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
// A vector whose squared length underflows (a triangle of 1e-88 in a mesh spanning 29: its cross product's
// squares are under 1e-308) is scaled by its largest component first, or its "unit" vector comes out 5 % short.
inline Vec3 normalized(const Vec3& a) {
  const double n = norm(a);
  if (n > 1e-140) return Vec3(a / n);
  const double largest = std::max({std::abs(a.x()), std::abs(a.y()), std::abs(a.z())});
  if (!(largest > 0)) return a;
  const Vec3 s = a / largest;
  return Vec3(s / norm(s));
}
inline Vec3 times(const Eigen::Matrix3d& M, const Vec3& v) {
  return Vec3(M(0, 0) * v.x() + M(0, 1) * v.y() + M(0, 2) * v.z(), M(1, 0) * v.x() + M(1, 1) * v.y() + M(1, 2) * v.z(),
              M(2, 0) * v.x() + M(2, 1) * v.y() + M(2, 2) * v.z());
}
// Eigen's unitOrthogonal() for 3-vectors, with the norms summed in a fixed order.
inline Vec3 unitOrthogonal(const Vec3& n) {
  if (!(std::abs(n.x()) <= std::abs(n.z()) * 1e-12) || !(std::abs(n.y()) <= std::abs(n.z()) * 1e-12)) {
    const double inverse = 1 / std::sqrt(n.x() * n.x() + n.y() * n.y());
    return Vec3(-n.y() * inverse, n.x() * inverse, 0);
  }
  const double inverse = 1 / std::sqrt(n.y() * n.y() + n.z() * n.z());
  return Vec3(0, -n.z() * inverse, n.y() * inverse);
}

// Principal curvatures and directions of the shape tensor T restricted to the tangent plane of `normal`.
// The 2x2 symmetric eigenproblem is solved in closed form with +, -, *, / and sqrt alone (correctly rounded
// everywhere, unlike libm's hypot, atan2, cos and sin), so the result is the same on every platform.
LocalGeometry principalFrame(const Vec3& point, const Vec3& normal, const Eigen::Matrix3d& T) {
  LocalGeometry g;
  g.point = point;
  g.normal = normal;
  const Vec3 u = unitOrthogonal(normal), v = normal.cross(u);
  const Vec3 Tu = times(T, u), Tv = times(T, v);
  const double a = dot(u, Tu), c = dot(v, Tv), b = 0.5 * (dot(u, Tv) + dot(v, Tu));
  const double half = 0.5 * (a - c);
  const double mean = 0.5 * (a + c), radius = std::sqrt(half * half + b * b);
  g.k1 = mean + radius;
  g.k2 = mean - radius;
  // The direction of the larger eigenvalue, at angle t = atan2(2 b, a - c) / 2 in (-pi/2, pi/2] from u.
  const Vec2 t = largerEigenDirection(a - c, 2 * b, 2 * radius);
  const double cosT = t.x(), sinT = t.y();
  g.d1 = cosT * u + sinT * v;
  g.d2 = normal.cross(g.d1);
  return g;
}

// The point of triangle abc nearest to p, as barycentric coordinates (Ericson, Real-Time Collision
// Detection, 5.1.5): the Voronoi regions of the vertices, then of the edges, then the face.
Vec3 closestBarycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return Vec3(1, 0, 0);
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return Vec3(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    return Vec3(1 - t, t, 0);
  }
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return Vec3(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    return Vec3(1 - t, 0, t);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return Vec3(0, 1 - t, t);
  }
  const double denom = 1 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return Vec3(1 - v - w, v, w);
}

// exp(-t) for t in [0, 1] from + and * alone, so that every platform rounds it alike (libm's exp differs
// between glibc and musl in the last bit): exp(-t / 8) by its Taylor polynomial to degree 10 (truncation
// below 3e-18 relative), squared three times. Within a few ulps of std::exp.
inline double expMinus(double t) {
  const double s = -0.125 * t;
  double e = 1.0 / 3628800;
  e = e * s + 1.0 / 362880;
  e = e * s + 1.0 / 40320;
  e = e * s + 1.0 / 5040;
  e = e * s + 1.0 / 720;
  e = e * s + 1.0 / 120;
  e = e * s + 1.0 / 24;
  e = e * s + 1.0 / 6;
  e = e * s + 0.5;
  e = e * s + 1;
  e = e * s + 1;
  e *= e;
  e *= e;
  return e * e;
}

// Eigen's LDLT (diagonal pivoting, the same zero-pivot rules) and its rcond estimate (Hager and Higham's
// 1-norm estimator, as Eigen::internal::rcond_invmatrix_L1_norm_estimate), written out for a fixed small
// size over plain arrays: Eigen 3.4 has no WebAssembly SIMD, and its reductions sum in a different order
// with SSE2 than without, so this scalar code is both faster in wasm and identical on every platform.
// Only the lower triangle a[i][j], i >= j, is read and written.
template <int m>
struct SmallLdlt {
  double a[m][m];  // L below the diagonal (unit diagonal implied), D on it
  int transposition[m];
  double l1Norm = 0;

  // Factors the symmetric matrix whose upper triangle is `upper` (upper[j][i], i >= j); false where Eigen
  // reports NumericalIssue.
  bool compute(const double (&upper)[m][m]) {
    for (int i = 0; i < m; ++i)
      for (int j = 0; j <= i; ++j) a[i][j] = upper[j][i];
    l1Norm = 0;
    for (int c = 0; c < m; ++c) {
      double sum = 0;
      for (int i = c; i < m; ++i) sum += std::abs(a[i][c]);
      for (int j = 0; j < c; ++j) sum += std::abs(a[c][j]);
      if (sum > l1Norm) l1Norm = sum;
    }
    bool foundZeroPivot = false, ok = true;
    double temp[m];
    for (int k = 0; k < m; ++k) {
      int p = k;  // the largest diagonal entry left (the first of equals)
      double biggest = std::abs(a[k][k]);
      for (int i = k + 1; i < m; ++i)
        if (std::abs(a[i][i]) > biggest) biggest = std::abs(a[i][i]), p = i;
      transposition[k] = p;
      if (p != k) {
        for (int j = 0; j < k; ++j) std::swap(a[k][j], a[p][j]);
        for (int i = p + 1; i < m; ++i) std::swap(a[i][k], a[i][p]);
        std::swap(a[k][k], a[p][p]);
        for (int i = k + 1; i < p; ++i) std::swap(a[i][k], a[p][i]);
      }
      if (k > 0) {
        for (int j = 0; j < k; ++j) temp[j] = a[j][j] * a[k][j];
        double dot = 0;
        for (int j = 0; j < k; ++j) dot += a[k][j] * temp[j];
        a[k][k] -= dot;
        for (int i = k + 1; i < m; ++i) {
          double s = 0;
          for (int j = 0; j < k; ++j) s += a[i][j] * temp[j];
          a[i][k] -= s;
        }
      }
      const double akk = a[k][k];
      const bool valid = std::abs(akk) > 0;
      if (k == 0 && !valid) {  // a zero diagonal: Eigen succeeds only for the zero matrix (rcond 0 then)
        for (int j = 0; j < m; ++j) transposition[j] = j;
        return false;
      }
      if (valid) {
        for (int i = k + 1; i < m; ++i) a[i][k] /= akk;
      } else {
        for (int i = k + 1; i < m; ++i) ok = ok && a[i][k] == 0;
      }
      if (foundZeroPivot && valid) ok = false;
      else if (!valid) foundZeroPivot = true;
    }
    return ok;
  }

  // x = A^-1 x in place (A symmetric: also A^-T).
  void solveInPlace(double (&x)[m]) const {
    for (int k = 0; k < m; ++k) std::swap(x[k], x[transposition[k]]);
    for (int i = 1; i < m; ++i) {
      double s = 0;
      for (int j = 0; j < i; ++j) s += a[i][j] * x[j];
      x[i] -= s;
    }
    for (int i = 0; i < m; ++i) x[i] = std::abs(a[i][i]) > std::numeric_limits<double>::min() ? x[i] / a[i][i] : 0.0;
    for (int i = m - 2; i >= 0; --i) {
      double s = 0;
      for (int j = i + 1; j < m; ++j) s += a[j][i] * x[j];
      x[i] -= s;
    }
    for (int k = m - 1; k >= 0; --k) std::swap(x[k], x[transposition[k]]);
  }

  static double norm1(const double (&x)[m]) {
    double s = 0;
    for (int i = 0; i < m; ++i) s += std::abs(x[i]);
    return s;
  }

  // An upper bound on ||A^-1||_1 = ||P^T L^-T D^-1 L^-1 P||_1 <= ||L^-1||_inf max|1 / d_i| ||L^-1||_1, from
  // L^-1 (cheaper than the estimator's solves). Every estimate of rcond() is at least 1 / (||A||_1 times it).
  double inverseNormBound() const {
    double x[m][m];  // L^-1, unit lower triangular
    for (int j = 0; j < m; ++j) {
      for (int i = j + 1; i < m; ++i) {
        double s = a[i][j];
        for (int k = j + 1; k < i; ++k) s += a[i][k] * x[k][j];
        x[i][j] = -s;
      }
    }
    double rowMax = 1, columnMax = 1, dMin = std::numeric_limits<double>::infinity();
    for (int i = 0; i < m; ++i) {
      double row = 1, column = 1;
      for (int j = 0; j < i; ++j) row += std::abs(x[i][j]);
      for (int k = i + 1; k < m; ++k) column += std::abs(x[k][i]);
      rowMax = std::max(rowMax, row), columnMax = std::max(columnMax, column);
      dMin = std::min(dMin, std::abs(a[i][i]));
    }
    return rowMax * columnMax / dMin;
  }

  // rcond() > threshold, deciding from the bound above where it suffices (a margin of 2 covers the
  // estimator's own round-off), else from the estimate.
  bool rcondAbove(double threshold) const {
    if (l1Norm > 0 && 1 / (l1Norm * inverseNormBound()) > 2 * threshold) return true;
    return rcond() > threshold;
  }

  // Eigen's LDLT::rcond(): 1 / (||A||_1 * an estimate of ||A^-1||_1 from below).
  double rcond() const {
    if (l1Norm == 0) return 0;
    double v[m], sign[m], oldSign[m] = {};
    for (int i = 0; i < m; ++i) v[i] = 1.0 / m;
    solveInPlace(v);
    double lower = norm1(v), oldLower = lower;
    int oldIndex = -1;
    for (int k = 0; k < 4; ++k) {
      bool same = k > 0;
      for (int i = 0; i < m; ++i) {
        sign[i] = v[i] < 0 ? -1.0 : 1.0;
        same = same && sign[i] == oldSign[i];
      }
      if (same) break;
      for (int i = 0; i < m; ++i) v[i] = sign[i];
      solveInPlace(v);
      int index = 0;
      for (int i = 1; i < m; ++i)
        if (std::abs(v[i]) > std::abs(v[index])) index = i;
      if (index == oldIndex) break;
      for (int i = 0; i < m; ++i) v[i] = i == index ? 1.0 : 0.0;
      solveInPlace(v);
      lower = norm1(v);
      if (lower <= oldLower) break;
      for (int i = 0; i < m; ++i) oldSign[i] = sign[i];
      oldIndex = index;
      oldLower = lower;
    }
    double alternating = 1;
    for (int i = 0; i < m; ++i) {
      v[i] = alternating * (1 + static_cast<double>(i) / (m - 1));
      alternating = -alternating;
    }
    solveInPlace(v);
    const double inverseNorm = std::max(lower, (2 * norm1(v)) / (3.0 * m));
    return inverseNorm == 0 ? 0 : (1 / inverseNorm) / l1Norm;
  }
};

// A jet z(x, y) fitted around a vertex: the normal and the 3D shape tensor it gives at the vertex.
struct JetFit {
  bool ok = false;
  Vec3 normal;
  Eigen::Matrix3d tensor;
  double residual = 0;  // root mean square of the points' heights off the fitted jet
  // The jet itself: z = sum coefficient[i] * monomial_i(x * scale, y * scale) / scale over `terms` monomials.
  double coefficient[10] = {0};
  double scale = 0;
  int terms = 0;
};

// Fits z = sum c_ij x^i y^j (i + j <= 3, or 2) to `local` (x, y, z in the frame whose third axis is the
// trial normal), weighted by a Gaussian of the distance. The fitted surface is a graph (x, y, f(x, y)):
// with J = [X_x X_y], metric G = J^T J and second fundamental form B = -Hess f / sqrt(1 + |grad f|^2)
// (sign: k > 0 bending away from the normal), the shape tensor on 3D tangent vectors is
// J G^-1 B G^-1 J^T. Plain loops over fixed-size arrays (the normal equations' lower triangle only).
// The monomials of a cubic jet at (x, y), in the order of its coefficients (the first 6: the quadratic's).
inline void jetMonomials(double x, double y, double row[10]) {
  row[0] = 1, row[1] = x, row[2] = y, row[3] = x * x, row[4] = x * y, row[5] = y * y;
  row[6] = x * x * x, row[7] = x * x * y, row[8] = x * y * y, row[9] = y * y * y;
}

template <int m>  // 10 coefficients: cubic; 6: quadratic (fixed sizes: no allocation per vertex)
JetFit fitJet(const std::vector<Vec3>& local) {
  JetFit fit;
  const int n = static_cast<int>(local.size());
  if (n < m + 2) return fit;
  double radius2 = 0;
  for (const Vec3& q : local) radius2 = std::max(radius2, q.x() * q.x() + q.y() * q.y());
  if (!(radius2 > 0)) return fit;
  const double scale = 1 / std::sqrt(radius2);  // monomials of x / h keep the normal equations well conditioned
  double A[m][m], rhs[m];  // the normal equations, upper triangle A[j][i], i >= j (rows contiguous)
  for (int i = 0; i < m; ++i) {
    rhs[i] = 0;
    for (int j = i; j < m; ++j) A[i][j] = 0;
  }
  constexpr int kBlock = 32;  // the weights of a block first: independent, they pipeline
  double weight[kBlock];
  for (int begin = 0; begin < n; begin += kBlock) {
    const int end = std::min(n, begin + kBlock);
    for (int k = begin; k < end; ++k) {
      const double x = local[k].x() * scale, y = local[k].y() * scale;
      weight[k - begin] = expMinus(x * x + y * y);  // nearer points count more: the jet is a local model
    }
    for (int k = begin; k < end; ++k) {
      const double x = local[k].x() * scale, y = local[k].y() * scale, w = weight[k - begin];
      double row[10];
      jetMonomials(x, y, row);
      const double wz = w * local[k].z() * scale;
      for (int j = 0; j < m; ++j) {
        const double wj = w * row[j];
        for (int i = j; i < m; ++i) A[j][i] += wj * row[i];
        rhs[j] += wz * row[j];
      }
    }
  }
  SmallLdlt<m> ldlt;
  if (!ldlt.compute(A) || !ldlt.rcondAbove(1e-10)) return fit;
  double* c = rhs;
  ldlt.solveInPlace(rhs);
  double squares = 0;
  for (int k = 0; k < n; ++k) {
    const double x = local[k].x() * scale, y = local[k].y() * scale;
    double row[10];
    jetMonomials(x, y, row);
    double z = 0;
    for (int i = 0; i < m; ++i) z += c[i] * row[i];
    const double r = local[k].z() - z / scale;
    squares += r * r;
  }
  fit.residual = std::sqrt(squares / n);
  for (int i = 0; i < m; ++i) fit.coefficient[i] = c[i];
  fit.scale = scale;
  fit.terms = m;
  // Back to unscaled derivatives at the origin: f_x = c1, f_xx = 2 c3 s, ... (z was scaled too).
  const double fx = c[1], fy = c[2], fxx = 2 * c[3] * scale, fxy = c[4] * scale, fyy = 2 * c[5] * scale;
  // G = J^T J = I + g g^T with g = (fx, fy), det G = 1 + |g|^2; M = G^-1 B G^-1; tensor = J M J^T.
  const double det = 1 + fx * fx + fy * fy, root = std::sqrt(det);
  const double b00 = -fxx / root, b01 = -fxy / root, b11 = -fyy / root;
  const double g00 = (1 + fy * fy) / det, g01 = -(fx * fy) / det, g11 = (1 + fx * fx) / det;
  const double h00 = g00 * b00 + g01 * b01, h01 = g00 * b01 + g01 * b11;  // H = G^-1 B
  const double h10 = g01 * b00 + g11 * b01, h11 = g01 * b01 + g11 * b11;
  const double m00 = h00 * g00 + h01 * g01, m01 = h00 * g01 + h01 * g11;  // M = H G^-1 (symmetric)
  const double m11 = h10 * g01 + h11 * g11;
  const double j0[2] = {m00 * fx + m01 * fy, m01 * fx + m11 * fy};  // M g
  fit.tensor << m00, m01, j0[0], m01, m11, j0[1], j0[0], j0[1], fx * j0[0] + fy * j0[1];
  fit.normal = Vec3(-fx, -fy, 1) / root;
  fit.ok = fit.tensor.allFinite() && fit.normal.allFinite();
  return fit;
}

}  // namespace

MeshSurface::MeshSurface(TriMesh mesh, std::string name) : mesh_(std::move(mesh)), name_(std::move(name)) {
  const int nv = vertexCount(), nf = static_cast<int>(mesh_.F.rows());
  if (nf == 0) fail(name_, "has no triangles");
  if (!mesh_.V.allFinite()) fail(name_, "has a coordinate that is not finite");
  if (nv > 0 && !(mesh_.V.cwiseAbs().maxCoeff() <= kMaxMeshCoordinate))
    fail(name_, "has a coordinate beyond ±1e50 (the extent of the mesh and the products of its lengths must stay finite)");
  if (mesh_.F.minCoeff() < 0 || mesh_.F.maxCoeff() >= nv)
    fail(name_, "a triangle refers to a vertex out of range (" + std::to_string(nv) + " vertices)");
  for (int v = 0; v < nv; ++v) bounds_.extend(Vec3(mesh_.V.row(v).transpose()));
  if (const double extent = bounds_.diagonal().norm(); !(extent >= kMinMeshExtent)) {
    char value[64];
    std::snprintf(value, sizeof value, "%.3g", extent);
    fail(name_, std::string("spans only ") + value +
                    " (its box's diagonal), under 1e-50: the products of lengths that small underflow; scale the mesh up");
  }
  buildTopology();
  const double edge = mesh_.meanEdgeLength();
  noise_ = edge > 0 ? estimateCurvature(2) / edge : 0.0;
  if (noise_ > kNoisyMesh) {
    // The curvature noise goes as residual / radius^2 / sqrt(points), about 1 / rings^3: rings to bring it
    // down to what 2 rings give at kNoisyMesh.
    curvatureRings_ = static_cast<int>(std::clamp(std::ceil(2 * std::cbrt(noise_ / kNoisyMesh)), 3.0, 8.0));
    estimateCurvature(curvatureRings_);
  }
  // A developable (an uploaded barrel vault, cone, ...): the curvature that vanishes comes out of the fits as
  // a trace (1e-5 to 1e-3 of the other on a sampled cylinder and cone), enough to make every point elliptic
  // or hyperbolic with a Dupin conic stretched along the ruling: ideal steps of a few hundredths of a cell,
  // stars judged by Props 4/5 where they cannot be, tangent planes that differ along a ruling. Where nearly
  // every curved vertex has one principal curvature under kDevelopableRatio of the other, that one is taken
  // as 0 there (vertices and points within triangles alike), as on the analytic developables (§5.3).
  const double curved = kCurvedScale / bounds_.diagonal().norm();
  planar_ = std::all_of(vertexGeometry_.begin(), vertexGeometry_.end(),
                        [&](const LocalGeometry& g) { return !(g.largestCurvature() >= curved); });
  if (planar_) {
    // The fits' round-off (1e-14 on a sloping plane) has directions of its own, and ideal triangles
    // (§5.1) from it are anything but equilateral (Method 1: 91 % hexagons there, 100 % on a level one).
    for (LocalGeometry& g : vertexGeometry_) g.k1 = g.k2 = 0;
    for (Eigen::Matrix3d& tensor : shapeTensor_) tensor.setZero();
  }
  developable_ = samplesDevelopable(vertexGeometry_, curved);
  if (developable_) {
    // Points within triangles about an inflection ruling interpolate tensors of opposite signs, whose
    // directions differ by a trace: a saddle with kmin = kmax and the ruling as an asymptotic direction (L0
    // on a corrugated field failed there, at 500 and 800 faces). Where both curvatures are that small the
    // point is taken as parabolic too.
    planarBelow_ = planarBelow(vertexGeometry_);
    for (LocalGeometry& g : vertexGeometry_) snapDevelopable(g);
    findRulings();
    for (int v = 0; v < nv; ++v) alongRuling(vertexGeometry_[v], rulings_[v]);
  }
  // The tree and the grid are built from the triangles alone, each into its own members: side by side (the bench's
  // upload refined for 100k faces, 979k triangles: 155 and 79 ms one after the other).
  parallelTasks(2, [&](int which) { which == 0 ? buildTree() : buildGrid(); });
}

// An interior edge a-b between triangles f and g whose planes turn by more than kCreaseDegrees. Slivers (their
// height under a tenth of their longest edge) do not count, their planes are anyone's; nor do triangles folded
// back over each other (turning by more than kFoldDegrees), the mark of a broken parametrization rather than a
// ridge: a jittered, graded grid of a smooth wave had 127 such edges, and laid as well as an even one.
void MeshSurface::noteCrease(int f, int g, int a, int b, std::vector<double>& turns) {
  auto normal = [&](int t) -> std::optional<Vec3> {
    const Vec3 p = mesh_.V.row(mesh_.F(t, 0)), q = mesh_.V.row(mesh_.F(t, 1)), r = mesh_.V.row(mesh_.F(t, 2));
    const Vec3 n = (q - p).cross(r - p);
    const double longest = std::max({dot(q - p, q - p), dot(r - q, r - q), dot(p - r, p - r)});
    if (!(norm(n) >= 0.1 * longest)) return std::nullopt;
    return n;
  };
  const std::optional<Vec3> nf = normal(f), ng = normal(g);
  if (!nf || !ng) return;
  const double lengths = norm(*nf) * norm(*ng);
  if (!(lengths > 0)) return;
  const double cosine = dot(*nf, *ng) / lengths;
  turns.push_back(cosine);
  if (!(cosine < std::cos(kCreaseDegrees * M_PI / 180)) || cosine < std::cos(kFoldDegrees * M_PI / 180)) return;
  ++creases_.edges;
  const double degrees = std::acos(std::max(-1.0, cosine)) * 180 / M_PI;
  if (degrees > creases_.degrees) {
    creases_.degrees = degrees;
    creases_.at = 0.5 * (mesh_.V.row(a) + mesh_.V.row(b)).transpose();
  }
}

void MeshSurface::buildTopology() {
  const int nv = vertexCount(), nf = static_cast<int>(mesh_.F.rows());
  // Triangles around each vertex, in compressed rows.
  std::vector<int> start(nv + 1, 0), around(3 * static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++start[mesh_.F(f, k) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) around[fill[mesh_.F(f, k)]++] = f;
  }
  std::vector<double> turns;  // the cosine of every interior edge's turn (noteCrease)
  // Neighbouring vertices; each edge a->b must appear once, and b->a at most once (else non-manifold).
  neighbourStart_.assign(nv + 1, 0);
  neighbours_.clear();
  neighbours_.reserve(6 * static_cast<std::size_t>(nv) + 6);
  std::vector<int> boundaryNext(nv, -1);
  onBoundary_.assign(nv, 0);
  std::vector<int> ring;
  // The edges out of and into a vertex by their other end (with their triangle), counted by binary search: a
  // vertex in many triangles (a fan's hub) costs d log d, not d^2.
  std::vector<std::pair<int, int>> out, in;
  auto count = [](const std::vector<std::pair<int, int>>& edges, int b) {
    return std::equal_range(edges.begin(), edges.end(), std::pair(b, 0),
                            [](const std::pair<int, int>& x, const std::pair<int, int>& y) { return x.first < y.first; });
  };
  for (int a = 0; a < nv; ++a) {
    ring.clear();
    out.clear();
    in.clear();
    for (int i = start[a]; i < start[a + 1]; ++i) {
      const int f = around[i];
      int k = 0;
      while (mesh_.F(f, k) != a) ++k;
      out.emplace_back(mesh_.F(f, (k + 1) % 3), f);
      in.emplace_back(mesh_.F(f, (k + 2) % 3), f);
    }
    std::sort(out.begin(), out.end());
    std::sort(in.begin(), in.end());
    for (int i = start[a]; i < start[a + 1]; ++i) {
      const int f = around[i];
      int k = 0;
      while (mesh_.F(f, k) != a) ++k;
      const int b = mesh_.F(f, (k + 1) % 3);
      ring.push_back(b);
      ring.push_back(mesh_.F(f, (k + 2) % 3));
      const auto forwards = count(out, b), backwards = count(in, b);
      const long forward = forwards.second - forwards.first, backward = backwards.second - backwards.first;
      const int twin = backward > 0 ? (backwards.second - 1)->second : -1;
      if (backward == 1 && forward == 1 && a < b) noteCrease(f, twin, a, b, turns);
      if (forward > 1 || backward > 1)
        fail(name_, "the edge from vertex " + std::to_string(a) + " to " + std::to_string(b) +
                        " is non-manifold or inconsistently oriented (clean the mesh with cleanTriMesh first)");
      if (backward == 0) {
        if (boundaryNext[a] >= 0)
          fail(name_, "vertex " + std::to_string(a) + " is where two boundaries meet (a non-manifold vertex)");
        boundaryNext[a] = b;
        onBoundary_[a] = onBoundary_[b] = 1;
      }
    }
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    neighbours_.insert(neighbours_.end(), ring.begin(), ring.end());
    neighbourStart_[a + 1] = static_cast<int>(neighbours_.size());
  }
  if (!turns.empty()) {
    std::nth_element(turns.begin(), turns.begin() + turns.size() / 2, turns.end());
    creases_.medianDegrees = std::acos(std::clamp(turns[turns.size() / 2], -1.0, 1.0)) * 180 / M_PI;
  }
  // Boundary loops follow the boundary edges in the triangles' direction.
  boundaryLoops_.clear();
  std::vector<char> visited(nv, 0);
  for (int v = 0; v < nv; ++v) {
    if (boundaryNext[v] < 0 || visited[v]) continue;
    std::vector<int> loop;
    for (int a = v; !visited[a]; a = boundaryNext[a]) {
      visited[a] = 1;
      loop.push_back(a);
      if (boundaryNext[a] < 0) fail(name_, "the boundary through vertex " + std::to_string(a) + " does not close");
    }
    boundaryLoops_.push_back(std::move(loop));
  }
}

std::vector<Vec3> MeshSurface::trialNormals() const {
  const int nv = vertexCount(), nf = static_cast<int>(mesh_.F.rows());
  // Area-weighted normals: the trial frame of each fit, oriented like the triangles.
  std::vector<Vec3> trialNormal(nv, Vec3::Zero());
  for (int f = 0; f < nf; ++f) {
    const Vec3 a = mesh_.V.row(mesh_.F(f, 0)), b = mesh_.V.row(mesh_.F(f, 1)), c = mesh_.V.row(mesh_.F(f, 2));
    const Vec3 n = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) trialNormal[mesh_.F(f, k)] += n;
  }
  return trialNormal;
}

MeshSurface::VertexFit MeshSurface::fitVertex(int v, int minRings, const std::vector<Vec3>& trial, FitScratch& scratch) const {
  const Vec3& trialNormal = trial[v];
  // The smallest k-ring, k >= 2, with enough points for a cubic jet (capped for safety).
  scratch.patch.assign(1, v);
  scratch.stamp[v] = v;
  std::size_t ringBegin = 0;
  static const double turnCosine = std::cos(kPatchTurnDegrees * M_PI / 180);
  const double trialLength = norm(trialNormal);
  for (int rings = 1; rings <= 8; ++rings) {
    const std::size_t ringEnd = scratch.patch.size();
    // A noisy mesh's wider rings (past the second) stop before a fold (kPatchTurnDegrees): the intersection
    // shell and the genus-3 mesh of the shared models, coarse and sharply bent, counted as noisy, and fits over
    // 5 and 6 rings turned their normals up to 130 degrees from their triangles'.
    const bool guarded = minRings > 2 && rings > 2;
    bool turns = false;  // (guarded) the ring reaches a vertex whose normal turns too far from v's
    for (std::size_t i = ringBegin; i < ringEnd; ++i) {
      const int u = scratch.patch[i];
      // Not on through a hub (a fan's centre): its neighbours would be every neighbour's ring, all of the mesh.
      if (u != v && neighbourStart_[u + 1] - neighbourStart_[u] > kCrowdedVertex) continue;
      for (int j = neighbourStart_[u]; j < neighbourStart_[u + 1]; ++j) {
        const int w = neighbours_[j];
        if (scratch.stamp[w] == v) continue;
        scratch.stamp[w] = v, scratch.patch.push_back(w);
        if (guarded && !turns) turns = !(dot(trial[w], trialNormal) >= turnCosine * norm(trial[w]) * trialLength);
      }
    }
    if (turns) {
      scratch.patch.resize(ringEnd);
      break;
    }
    ringBegin = ringEnd;
    if (scratch.patch.size() == ringEnd || (rings >= minRings && static_cast<int>(scratch.patch.size()) >= kMinJetPoints)) break;
  }
  const Vec3 p = mesh_.V.row(v);
  Vec3 normal = norm(trialNormal) > 0 ? normalized(trialNormal) : Vec3::UnitZ();
  VertexFit out;
  Eigen::Matrix3d& tensor = out.tensor;
  tensor.setZero();
  // Two passes at most: a fit whose normal is far from the trial normal is refitted in its own frame.
  for (int pass = 0; pass < 2; ++pass) {
    const Vec3 t1 = unitOrthogonal(normal), t2 = normal.cross(t1);
    scratch.local.clear();
    for (int w : scratch.patch) {
      const Vec3 d = Vec3(mesh_.V.row(w)) - p;
      scratch.local.emplace_back(dot(d, t1), dot(d, t2), dot(d, normal));
    }
    JetFit fit = fitJet<10>(scratch.local);
    if (!fit.ok) fit = fitJet<6>(scratch.local);
    if (!fit.ok) break;  // too few points (a tiny mesh): keep the trial normal, zero curvature
    out.residual = fit.residual;
    std::copy(fit.coefficient, fit.coefficient + 10, out.coefficient);
    out.scale = fit.scale;
    out.terms = fit.terms;
    out.frame << t1, t2, normal;
    Eigen::Matrix3d R;
    R << t1, t2, normal;
    // tensor = R fit.tensor R^T, fitted = R fit.normal, summed in a fixed order.
    Eigen::Matrix3d RT;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) RT(i, j) = R(i, 0) * fit.tensor(0, j) + R(i, 1) * fit.tensor(1, j) + R(i, 2) * fit.tensor(2, j);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) tensor(i, j) = RT(i, 0) * R(j, 0) + RT(i, 1) * R(j, 1) + RT(i, 2) * R(j, 2);
    const Vec3 fitted = times(R, fit.normal);
    // A jet whose normal turns from the triangles' by more than kJetTurnDegrees has not fitted the surface
    // (a boundary vertex's one-sided patch over a fold: the intersection shell's feet turned by 66-138
    // degrees): the trial normal stands, and the tensor is taken in its tangent plane (principalFrame).
    static const double jetCosine = std::cos(kJetTurnDegrees * M_PI / 180);
    if (pass == 0 && !(dot(fitted, normal) >= jetCosine)) break;
    const bool refit = dot(fitted, normal) < 0.995;  // about 6 degrees
    normal = fitted;
    if (!refit) break;
  }
  out.normal = normal;
  return out;
}

TriMesh MeshSurface::refined(int k, Blend blending) const {
  const int nv = vertexCount(), nf = static_cast<int>(mesh_.F.rows());
  if (k < 1) throw Error(ErrorCode::InvalidParameter, "refinement level must be at least 1");
  if (double(nf) * k * k > double(kMaxRefinedTriangles))
    throw Error(ErrorCode::InvalidParameter, "refining " + std::to_string(nf) + " triangles " + std::to_string(k) + " x " +
                                                 std::to_string(k) + " would exceed " +
                                                 std::to_string(kMaxRefinedTriangles) + " triangles");
  const std::vector<Vec3> trial = trialNormals();
  std::vector<VertexFit> jets(nv);
  // Over two rings whatever noise() says: a coarse mesh's fits miss its vertices because the surface turns
  // much within two rings, not because they are scattered (a torus sampled 24 x 12 counted as noisy, and
  // its fits over 4 rings, spanning a third of its tube, blended into a surface far off it).
  parallelRanges(nv, kPointsPerThread, [&](int begin, int end) {
    FitScratch scratch(nv);
    for (int v = begin; v < end; ++v) jets[v] = fitVertex(v, 2, trial, scratch);
  });
  // x projected onto vertex v's jet (through the vertex: its constant term left out).
  auto onJet = [&](int v, const Vec3& x) -> Vec3 {
    const VertexFit& j = jets[v];
    if (j.terms == 0) return x;
    const Vec3 p = mesh_.V.row(v).transpose(), d = x - p;
    const Vec3 t1 = j.frame.col(0), t2 = j.frame.col(1), n = j.frame.col(2);
    const double u = dot(d, t1), w = dot(d, t2);
    double row[10];
    jetMonomials(u * j.scale, w * j.scale, row);
    double z = 0;
    for (int i = 1; i < j.terms; ++i) z += j.coefficient[i] * row[i];
    return p + u * t1 + w * t2 + (z / j.scale) * n;
  };
  const bool smooth = blending == Blend::Smooth;
  // Each vertex's jet reaches kBlendReach of its longest edge, its weight falling smoothly to 0 there (the smooth
  // blend alone: the barycentric one needs no reaches).
  std::vector<double> reach(smooth ? nv : 0, 0.0);
  for (int a = 0; a < static_cast<int>(reach.size()); ++a)
    for (int j = neighbourStart_[a]; j < neighbourStart_[a + 1]; ++j)
      reach[a] = std::max(reach[a], kBlendReach * (mesh_.V.row(a) - mesh_.V.row(neighbours_[j])).norm());
  // A few edges far longer than the rest (a needle among fair triangles) would send every walk below over most of
  // the mesh, for a time that grows as the square of its size: reaches are held to kBlendReachSpread times their
  // 99th percentile (on the shared models and the bench's upload none is past it). A 128 x 128 dome grid with one
  // corner pulled 30 units out, refined 2 x 2: 72 s before, 0.67 s held (the barycentric blend 0.08 s).
  double farthestReach = 0;
  if (!reach.empty()) {
    std::vector<double> sorted = reach;
    const auto at = sorted.begin() + static_cast<std::ptrdiff_t>(0.99 * double(nv - 1));
    std::nth_element(sorted.begin(), at, sorted.end());
    const double cap = kBlendReachSpread * *at;
    for (double& r : reach) r = std::min(r, cap);
    farthestReach = *std::max_element(reach.begin(), reach.end());
  }
  // The vertices whose jets may reach a point between `ids` (a triangle, an edge or a vertex, within `radius` of
  // `centre`): those within their reach of that ball, found through the vertices within the farthest reach of it
  // (so that neighbouring triangles find the same jets at their common points: a count of rings missed the long
  // edges' far-reaching jets of an uneven upload, and the refinement creased between triangles by 67 degrees).
  // Each range of points (parallelRanges) gathers into scratch of its own; every point is blended on its own, so
  // the refinement is the same whatever the thread count.
  struct Gathered {
    std::vector<int> stamp, near, seen;
    int round = 0;
  };
  auto gather = [&](Gathered& g, std::initializer_list<int> ids) {
    if (g.stamp.empty()) g.stamp.assign(nv, -1);
    ++g.round;
    g.near.clear();
    if (!smooth) return;
    g.seen.clear();
    Vec3 centre = Vec3::Zero();
    for (int c : ids) centre += mesh_.V.row(c).transpose() / double(ids.size());
    double radius = 0;
    for (int c : ids) radius = std::max(radius, (Vec3(mesh_.V.row(c).transpose()) - centre).norm());
    for (int c : ids)
      if (g.stamp[c] != g.round) g.stamp[c] = g.round, g.seen.push_back(c);
    for (std::size_t i = 0; i < g.seen.size(); ++i) {
      const int u = g.seen[i];
      const double d = (Vec3(mesh_.V.row(u).transpose()) - centre).norm();
      if (d < radius + reach[u]) g.near.push_back(u);
      if (!(d < radius + farthestReach)) continue;
      for (int j = neighbourStart_[u]; j < neighbourStart_[u + 1]; ++j)
        if (const int w = neighbours_[j]; g.stamp[w] != g.round) g.stamp[w] = g.round, g.seen.push_back(w);
    }
  };
  // The point at barycentric coordinates b of the triangle (or edge, or vertex) `ids`, whose jets' vertices are
  // gathered in `g`: its projections onto the jets that reach it, weighted by Wendland's C2 function of the distance
  // over the reach. The weights are smooth in space where barycentric ones kink at every edge.
  auto blend = [&](const Gathered& g, const int ids[3], const double b[3]) {
    Vec3 x = Vec3::Zero();
    for (int c = 0; c < 3; ++c) x += b[c] * mesh_.V.row(ids[c]).transpose();
    Vec3 q = Vec3::Zero();
    double total = 0;
    for (int v : g.near) {
      const double d = (x - Vec3(mesh_.V.row(v).transpose())).norm() / reach[v];
      if (!(d < 1)) continue;
      const double w = (1 - d) * (1 - d) * (1 - d) * (1 - d) * (4 * d + 1);
      q += w * onJet(v, x);
      total += w;
    }
    if (total > 0) return Vec3(q / total);
    // Barycentric (or reached by no jet: a degenerate triangle).
    q.setZero();
    for (int c = 0; c < 3; ++c)
      if (b[c] > 0) q += b[c] * onJet(ids[c], x);
    return q;
  };
  // Every edge's k - 1 inner points, from its lower vertex id to its higher, in the order of the adjacency
  // (each vertex's neighbours, sorted): the edge a-b (a < b) is neighbours_[j] = b of a's row, its points from
  // edgeFirst[j] on. Then each triangle's inner points, (k - 1)(k - 2) / 2 of them, in the order of the triangles.
  std::vector<int> edgeFirst(neighbours_.size(), -1);
  Eigen::Index next = nv;
  for (int a = 0; a < nv; ++a)
    for (int j = neighbourStart_[a]; j < neighbourStart_[a + 1]; ++j)
      if (neighbours_[j] > a) edgeFirst[j] = static_cast<int>(next), next += k - 1;
  const Eigen::Index facesFirst = next;
  const std::size_t inner = static_cast<std::size_t>(k - 1) * (k - 2) / 2;
  TriMesh out;
  out.V.resize(facesFirst + static_cast<Eigen::Index>(nf * inner), 3);
  // The blend's cost is in its walks and projections (a few microseconds a point): ranges of a few hundred.
  constexpr int kBlendGrain = 256;
  parallelRanges(nv, kBlendGrain, [&](int begin, int end) {
    Gathered g;
    for (int a = begin; a < end; ++a) {
      const int ids[3] = {a, a, a};
      const double b[3] = {1.0, 0.0, 0.0};
      gather(g, {a});
      out.V.row(a) = blend(g, ids, b).transpose();
      for (int j = neighbourStart_[a]; j < neighbourStart_[a + 1]; ++j) {
        if (neighbours_[j] < a) continue;
        const int edge[3] = {a, neighbours_[j], a};
        gather(g, {a, neighbours_[j]});
        for (int i = 1; i < k; ++i) {
          const double c[3] = {double(k - i) / k, double(i) / k, 0.0};
          out.V.row(edgeFirst[j] + i - 1) = blend(g, edge, c).transpose();
        }
      }
    }
  });
  auto edgePoint = [&](int a, int b, int i) {  // the point i / k of the way from a to b (0 < i < k)
    const int lo = std::min(a, b), hi = std::max(a, b);
    const int* row = neighbours_.data();
    const int j = static_cast<int>(std::lower_bound(row + neighbourStart_[lo], row + neighbourStart_[lo + 1], hi) - row);
    return edgeFirst[j] + (a < b ? i : k - i) - 1;
  };
  out.F.resize(static_cast<Eigen::Index>(nf) * k * k, 3);
  parallelRanges(nf, std::max(1, kBlendGrain / std::max<int>(1, static_cast<int>(inner))), [&](int begin, int end) {
    Gathered g;
    std::vector<int> lattice(static_cast<std::size_t>(k + 1) * (k + 1));
    for (int f = begin; f < end; ++f) {
      const int ids[3] = {mesh_.F(f, 0), mesh_.F(f, 1), mesh_.F(f, 2)};
      if (inner > 0) gather(g, {ids[0], ids[1], ids[2]});
      Eigen::Index point = facesFirst + static_cast<Eigen::Index>(f * inner), t = static_cast<Eigen::Index>(f) * k * k;
      // Point (i, j): a + i / k (b - a) + j / k (c - a).
      auto at = [&](int i, int j) -> int& { return lattice[static_cast<std::size_t>(j) * (k + 1) + i]; };
      for (int j = 0; j <= k; ++j)
        for (int i = 0; i + j <= k; ++i) {
          if (i == 0 && j == 0) at(i, j) = ids[0];
          else if (i == k) at(i, j) = ids[1];
          else if (j == k) at(i, j) = ids[2];
          else if (j == 0) at(i, j) = edgePoint(ids[0], ids[1], i);
          else if (i == 0) at(i, j) = edgePoint(ids[0], ids[2], j);
          else if (i + j == k) at(i, j) = edgePoint(ids[1], ids[2], j);
          else {
            const double b[3] = {double(k - i - j) / k, double(i) / k, double(j) / k};
            out.V.row(point) = blend(g, ids, b).transpose();
            at(i, j) = static_cast<int>(point++);
          }
        }
      for (int j = 0; j < k; ++j)
        for (int i = 0; i + j < k; ++i) {
          out.F.row(t++) << at(i, j), at(i + 1, j), at(i, j + 1);
          if (i + j + 1 < k) out.F.row(t++) << at(i + 1, j), at(i + 1, j + 1), at(i, j + 1);
        }
    }
  });
  return out;
}

void MeshSurface::setRefinement(const TriMesh& coarse, int k) {
  if (k < 1 || double(coarse.F.rows()) * k * k != double(mesh_.F.rows()) || coarse.V.rows() > mesh_.V.rows())
    throw Error(ErrorCode::InvalidParameter, "the mesh is not this refinement of the coarse one");
  refinement_ = {coarse.F, static_cast<int>(coarse.V.rows()), k};
}

double MeshSurface::estimateCurvature(int minRings) {
  const int nv = vertexCount();
  const std::vector<Vec3> trialNormal = trialNormals();
  vertexGeometry_.resize(nv);
  shapeTensor_.resize(nv);
  std::vector<double> residual(nv, 0.0);
  parallelRanges(nv, kPointsPerThread, [&](int begin, int end) {
    FitScratch scratch(nv);
    for (int v = begin; v < end; ++v) {
      const VertexFit fit = fitVertex(v, minRings, trialNormal, scratch);
      residual[v] = fit.residual;
      shapeTensor_[v] = fit.tensor;
      vertexGeometry_[v] = principalFrame(mesh_.V.row(v).transpose(), fit.normal, fit.tensor);
    }
  });
  if (nv == 0) return 0;
  std::nth_element(residual.begin(), residual.begin() + nv / 2, residual.end());
  return residual[nv / 2];
}

std::vector<std::vector<Vec3>> MeshSurface::boundaryCurves() const {
  std::vector<std::vector<Vec3>> loops;
  for (const std::vector<int>& ids : boundaryLoops_) {
    std::vector<Vec3> loop;
    loop.reserve(ids.size());
    for (int v : ids) loop.push_back(mesh_.V.row(v).transpose());
    loops.push_back(std::move(loop));
  }
  return loops;
}

LocalGeometry MeshSurface::geometryInTriangle(int f, const Vec3& barycentric) const {
  Vec3 point = Vec3::Zero(), normal = Vec3::Zero();
  Eigen::Matrix3d tensor = Eigen::Matrix3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const int v = mesh_.F(f, k);
    point += barycentric(k) * mesh_.V.row(v).transpose();
    normal += barycentric(k) * vertexGeometry_[v].normal;
    tensor += barycentric(k) * shapeTensor_[v];
  }
  if (!(norm(normal) > 1e-12)) {  // opposite vertex normals (a fold): use the triangle's own normal
    const Vec3 a = mesh_.V.row(mesh_.F(f, 0)), b = mesh_.V.row(mesh_.F(f, 1)), c = mesh_.V.row(mesh_.F(f, 2));
    normal = (b - a).cross(c - a);
  }
  LocalGeometry g = principalFrame(point, normalized(normal), tensor);
  if (developable_) {
    snapDevelopable(g);
    if (g.largestCurvature() < planarBelow_) {
      const Vec3& first = rulings_[mesh_.F(f, 0)];
      Vec3 ruling = Vec3::Zero();
      for (int k = 0; k < 3; ++k) {
        const Vec3& r = rulings_[mesh_.F(f, k)];
        ruling += barycentric(k) * (r.dot(first) < 0 ? Vec3(-r) : r);
      }
      alongRuling(g, ruling);
    }
  }
  return g;
}

// A developable's ruling direction at each vertex: its zero-curvature direction where it is clearly curved.
// About an inflection of the profile (planar points) the fitted principal directions are arbitrary, and
// within triangles there the interpolated tensors of opposite signs turn them anywhere (a corrugated field's
// rows, laid across such a band, lost their apexes over half a row at 800 faces): there the vertices take
// the rulings of their curved neighbours, ring by ring.
void MeshSurface::findRulings() {
  const int nv = vertexCount();
  rulings_.assign(nv, Vec3::Zero());
  std::vector<char> known(nv, 0);
  for (int v = 0; v < nv; ++v) {
    const LocalGeometry& g = vertexGeometry_[v];
    // Boundary vertices' one-sided fits are the least sure of their directions (a corrugated field's last
    // column had its "ruling" along the boundary): they borrow too, as do the few whose fit was not parabolic.
    if (g.largestCurvature() < planarBelow_ || onBoundary_[v] || (g.k1 != 0 && g.k2 != 0))
      continue;
    rulings_[v] = g.k2 == 0 ? g.d2 : g.d1;
    known[v] = 1;
  }
  // Ring by ring from the known ones (a flat apron may be hundreds of rings wide): each ring's vertices take
  // the mean of their known neighbours' rulings, all from the rings before.
  std::vector<int> frontier, ring;
  for (int v = 0; v < nv; ++v)
    if (known[v]) frontier.push_back(v);
  std::vector<char> queued(nv, 0);
  std::vector<Vec3> found;
  while (!frontier.empty()) {
    ring.clear();
    for (int w : frontier)
      for (int j = neighbourStart_[w]; j < neighbourStart_[w + 1]; ++j) {
        const int v = neighbours_[j];
        if (!known[v] && !queued[v]) queued[v] = 1, ring.push_back(v);
      }
    std::sort(ring.begin(), ring.end());
    found.assign(ring.size(), Vec3::Zero());
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const int v = ring[i];
      Vec3 sum = Vec3::Zero();
      for (int j = neighbourStart_[v]; j < neighbourStart_[v + 1]; ++j) {
        const int w = neighbours_[j];
        if (known[w]) sum += sum.dot(rulings_[w]) < 0 ? Vec3(-rulings_[w]) : rulings_[w];
      }
      const Vec3& n = vertexGeometry_[v].normal;
      sum -= sum.dot(n) * n;
      if (norm(sum) > 0) found[i] = normalized(sum);
    }
    frontier.clear();
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const int v = ring[i];
      queued[v] = 0;  // one that found nothing is looked at again when a neighbour is found
      if (norm(found[i]) > 0) rulings_[v] = found[i], known[v] = 1, frontier.push_back(v);
    }
  }
}

// Principal directions along `ruling` (and across it) at a developable's planar point: the ruling takes the
// zero curvature.
void MeshSurface::alongRuling(LocalGeometry& g, const Vec3& ruling) const {
  if (!(g.largestCurvature() < planarBelow_)) return;
  Vec3 r = ruling - ruling.dot(g.normal) * g.normal;
  if (!(norm(r) > 1e-9)) return;
  r = normalized(r);
  if (g.k2 == 0) g.d1 = r.cross(g.normal), g.d2 = r;  // d2 = normal x d1 = r
  else g.d1 = r, g.d2 = g.normal.cross(r);
}

void MeshSurface::snapDevelopable(LocalGeometry& g) const {
  const double ratio = g.largestCurvature() < planarBelow_ ? 1.0 : kDevelopableRatio;
  if (std::abs(g.k2) <= ratio * std::abs(g.k1)) g.k2 = 0;
  else if (std::abs(g.k1) <= ratio * std::abs(g.k2)) g.k1 = 0;
}

void MeshSurface::buildTree() {
  const int nf = static_cast<int>(mesh_.F.rows());
  // The triangles' centroids with their ids, contiguous: the median splits partition this array in place.
  struct Item {
    double centre[3];
    int f;
  };
  std::vector<Item> items(nf);
  for (int f = 0; f < nf; ++f) {
    const Vec3 c = (mesh_.V.row(mesh_.F(f, 0)) + mesh_.V.row(mesh_.F(f, 1)) + mesh_.V.row(mesh_.F(f, 2))).transpose() / 3;
    items[f] = {{c.x(), c.y(), c.z()}, f};
  }
  nodes_.clear();
  nodes_.reserve(static_cast<std::size_t>(nf));
  nodes_.emplace_back();
  struct Task {
    int node, begin, end;
  };
  std::vector<Task> tasks{{0, 0, nf}};
  constexpr int kLeafSize = 4;
  while (!tasks.empty()) {
    const Task t = tasks.back();
    tasks.pop_back();
    if (t.end - t.begin <= kLeafSize) {
      nodes_[t.node].first = t.begin;
      nodes_[t.node].count = t.end - t.begin;
      continue;
    }
    // Median split along the longest side of the centroids' box: a balanced tree, depth log2(#F / 4).
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = hi[a] = items[t.begin].centre[a];
    for (int i = t.begin + 1; i < t.end; ++i)
      for (int a = 0; a < 3; ++a) {
        const double x = items[i].centre[a];
        lo[a] = x < lo[a] ? x : lo[a];
        hi[a] = x > hi[a] ? x : hi[a];
      }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    const int mid = (t.begin + t.end) / 2;
    std::nth_element(items.begin() + t.begin, items.begin() + mid, items.begin() + t.end,
                     [axis](const Item& a, const Item& b) { return a.centre[axis] < b.centre[axis]; });
    const int left = static_cast<int>(nodes_.size());
    nodes_[t.node].first = left;
    nodes_[t.node].count = 0;
    nodes_.emplace_back();
    nodes_.emplace_back();
    tasks.push_back({left, t.begin, mid});
    tasks.push_back({left + 1, mid, t.end});
  }
  triangleOrder_.resize(nf);
  for (int i = 0; i < nf; ++i) triangleOrder_[i] = items[i].f;
  // Boxes bottom-up (children come after their parent): each leaf's from its triangles' corners, each
  // inner node's the union of its children's — the same boxes as scanning every subtree's triangles.
  for (int n = static_cast<int>(nodes_.size()) - 1; n >= 0; --n) {
    Node& node = nodes_[n];
    if (node.count > 0) {
      node.box.setEmpty();
      for (int i = node.first; i < node.first + node.count; ++i)
        for (int k = 0; k < 3; ++k) node.box.extend(Vec3(mesh_.V.row(mesh_.F(triangleOrder_[i], k)).transpose()));
    } else {
      node.box = nodes_[node.first].box.merged(nodes_[node.first + 1].box);
    }
  }
}

double MeshSurface::triangleDistance(int f, const Vec3& p, Vec3& barycentric) const {
  const Vec3 a = mesh_.V.row(mesh_.F(f, 0)), b = mesh_.V.row(mesh_.F(f, 1)), c = mesh_.V.row(mesh_.F(f, 2));
  barycentric = closestBarycentric(p, a, b, c);
  const Vec3 d = barycentric(0) * a + barycentric(1) * b + barycentric(2) * c - p;
  return dot(d, d);
}

void MeshSurface::searchTree(const Vec3& p, double& best, int& triangle, Vec3& barycentric) const {
  int stack[128];  // the tree is balanced: depth <= 25 for kMaxMeshTriangles, two entries per level
  int top = 0;
  stack[top++] = 0;
  Vec3 bary;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (node.box.squaredExteriorDistance(p) > best) continue;
    if (node.count > 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const int f = triangleOrder_[i];
        const double d = triangleDistance(f, p, bary);
        // Ties (a point nearest to a shared edge or vertex) go to the lowest index, as in searchGrid, so that
        // the answer does not depend on the tree's shape (std::nth_element differs between C++ libraries).
        if (d < best || (d == best && f < triangle)) best = d, triangle = f, barycentric = bary;
      }
      continue;
    }
    // Nearer child on top, so it is searched first and prunes the other.
    const double dl = nodes_[node.first].box.squaredExteriorDistance(p);
    const double dr = nodes_[node.first + 1].box.squaredExteriorDistance(p);
    if (dl <= dr) {
      stack[top++] = node.first + 1;
      stack[top++] = node.first;
    } else {
      stack[top++] = node.first;
      stack[top++] = node.first + 1;
    }
  }
}

void MeshSurface::buildGrid() {
  const int nf = static_cast<int>(mesh_.F.rows());
  const Vec3 size = bounds_.sizes();
  // Cells about two mean edges wide hold a handful of triangles each, and a point near the mesh is usually
  // settled by its own cell. Coarser where that would make too many cells or cell entries (long triangles).
  const double edge = mesh_.meanEdgeLength();
  double h = std::max(2 * edge, 1e-9 * std::max(size.maxCoeff(), 1e-300));
  if (!(h > 0) || !std::isfinite(h)) h = std::max(size.maxCoeff(), 1.0);
  const double maxCells = 4.0 * nf + 4096, maxEntries = 8.0 * nf + 4096;
  std::vector<std::array<int, 6>> range(nf);  // each triangle's cell box, inclusive
  // The cells of a triangle's box that its plane meets (the cells grown by a hair, for round-off).
  auto forCells = [&](int f, const std::array<int, 6>& r, auto&& fn) {
    const Vec3 a = mesh_.V.row(mesh_.F(f, 0)), b = mesh_.V.row(mesh_.F(f, 1)), c = mesh_.V.row(mesh_.F(f, 2));
    const Vec3 n = (b - a).cross(c - a);
    const double half = 0.5 * gridCell_ * (1 + 1e-6), reach = half * (std::abs(n.x()) + std::abs(n.y()) + std::abs(n.z()));
    const double offset = dot(n, a);
    const double slack = 1e-9 * norm(n) * (gridCell_ + a.cwiseAbs().maxCoeff() + bounds_.sizes().maxCoeff());
    const bool whole = r[0] == r[3] && r[1] == r[4] && r[2] == r[5];
    for (int k = r[2]; k <= r[5]; ++k)
      for (int j = r[1]; j <= r[4]; ++j)
        for (int i = r[0]; i <= r[3]; ++i) {
          if (!whole) {
            const Vec3 centre = gridOrigin_ + gridCell_ * Vec3(i + 0.5, j + 0.5, k + 0.5);
            if (std::abs(dot(n, centre) - offset) > reach + slack) continue;
          }
          fn(i + std::size_t(gridSize_[0]) * (j + std::size_t(gridSize_[1]) * k));
        }
  };
  // Ends: once h passes the mesh's size (finite: kMaxMeshCoordinate) there is one cell holding every triangle once.
  for (;; h *= 1.5) {
    double cells = 1, count[3];
    for (int a = 0; a < 3; ++a) cells *= count[a] = std::max(1.0, std::ceil(size(a) / h));
    if (!(cells <= maxCells)) continue;  // counted in floating point: cast once they fit an int
    for (int a = 0; a < 3; ++a) gridSize_[a] = static_cast<int>(count[a]);
    gridCell_ = h;
    gridInverseCell_ = 1 / h;
    gridOrigin_ = bounds_.min();
    double entries = 0;
    // A triangle goes into every cell its box meets, the box grown by a hair so that round-off in the cell of
    // a point on a cell face cannot lose it.
    const double grow = 1e-9 * h;
    for (int f = 0; f < nf && entries <= maxEntries; ++f) {
      Box3 box;
      for (int k = 0; k < 3; ++k) box.extend(Vec3(mesh_.V.row(mesh_.F(f, k)).transpose()));
      for (int a = 0; a < 3; ++a) {
        range[f][a] = gridCellOf(box.min()(a) - grow, a);
        range[f][a + 3] = gridCellOf(box.max()(a) + grow, a);
      }
      forCells(f, range[f], [&](std::size_t) { ++entries; });
    }
    if (entries <= maxEntries) break;
  }
  spheres_.resize(nf);
  for (int f = 0; f < nf; ++f) {
    const Vec3 a = mesh_.V.row(mesh_.F(f, 0)), b = mesh_.V.row(mesh_.F(f, 1)), c = mesh_.V.row(mesh_.F(f, 2));
    const Vec3 centre = (a + b + c) / 3;
    const Vec3 da = a - centre, db = b - centre, dc = c - centre;
    const double radius = std::sqrt(std::max({dot(da, da), dot(db, db), dot(dc, dc)}));
    spheres_[f] << centre, radius * (1 + 1e-12) + 1e-300;
  }
  const std::size_t cells = std::size_t(gridSize_[0]) * gridSize_[1] * gridSize_[2];
  cellStart_.assign(cells + 1, 0);
  for (int f = 0; f < nf; ++f) forCells(f, range[f], [&](std::size_t c) { ++cellStart_[c + 1]; });
  std::partial_sum(cellStart_.begin(), cellStart_.end(), cellStart_.begin());
  cellTriangles_.resize(cellStart_.back());
  std::vector<int> fill(cellStart_.begin(), cellStart_.end() - 1);
  for (int f = 0; f < nf; ++f) forCells(f, range[f], [&](std::size_t c) { cellTriangles_[fill[c]++] = f; });
}

int MeshSurface::gridCellOf(double x, int axis) const {
  return gridCell((x - gridOrigin_(axis)) * gridInverseCell_, gridSize_[axis]);
}

bool MeshSurface::searchGrid(const Vec3& p, double& best, int& triangle, Vec3& barycentric) const {
  int centre[3];
  for (int a = 0; a < 3; ++a) centre[a] = gridCellOf(p(a), a);
  auto cellId = [&](int i, int j, int k) { return i + std::size_t(gridSize_[0]) * (j + std::size_t(gridSize_[1]) * k); };
  double bestRoot = std::sqrt(best);
  Vec3 bary;
  auto test = [&](int f) {
    const Eigen::Vector4d& sphere = spheres_[f];
    const double reach = sphere(3) + bestRoot;
    const Vec3 toCentre = sphere.head<3>() - p;
    if (dot(toCentre, toCentre) > reach * reach) return;  // the triangle's ball is farther
    const double d = triangleDistance(f, p, bary);
    if (d < best || (d == best && f < triangle)) best = d, triangle = f, barycentric = bary, bestRoot = std::sqrt(d);
  };
  // The point's own cell, its triangle with the nearest centre first so that the balls reject most others.
  {
    const std::size_t c = cellId(centre[0], centre[1], centre[2]);
    const int begin = cellStart_[c], end = cellStart_[c + 1];
    if (begin == end) return false;  // an empty cell: far from the mesh, the tree
    // A cell crowded with small triangles (a mesh graded finely in one corner: cells are sized by the mean
    // edge) is searched faster by the tree, whose answer is the same.
    if (end - begin > kCrowdedCell) return false;
    int first = cellTriangles_[begin];
    double nearest = std::numeric_limits<double>::infinity();
    for (int e = begin; e < end; ++e) {
      const int f = cellTriangles_[e];
      const Vec3 dc = spheres_[f].head<3>() - p;
      const double d = dot(dc, dc);
      if (d < nearest) nearest = d, first = f;
    }
    test(first);
    for (int e = begin; e < end; ++e)
      if (cellTriangles_[e] != first) test(cellTriangles_[e]);
  }
  // Every triangle nearer than the best so far meets the ball of that radius about p, so its box meets one of
  // the cells the ball's box meets (the grid holds all triangles). Too many cells: the tree, from that bound.
  const double reach = bestRoot * (1 + 1e-9) + 1e-6 * gridCell_;
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = gridCellOf(p(a) - reach, a);
    hi[a] = gridCellOf(p(a) + reach, a);
    if (hi[a] - lo[a] > 4) return false;
  }
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i) {
        if (i == centre[0] && j == centre[1] && k == centre[2]) continue;
        const int idx[3] = {i, j, k};
        double d2 = 0;  // a cell farther than the best so far cannot hold a nearer triangle
        for (int a = 0; a < 3; ++a) {
          const double cellLo = gridOrigin_(a) + idx[a] * gridCell_, cellHi = cellLo + gridCell_;
          const double g = p(a) < cellLo ? cellLo - p(a) : p(a) > cellHi ? p(a) - cellHi : 0.0;
          d2 += g * g;
        }
        if (d2 > best * (1 + 1e-9)) continue;
        const std::size_t c = cellId(i, j, k);
        for (int e = cellStart_[c]; e < cellStart_[c + 1]; ++e) test(cellTriangles_[e]);
      }
  return true;
}

std::vector<LocalGeometry> MeshSurface::samples(int count) const {
  const Eigen::Index step = std::max<Eigen::Index>(1, mesh_.V.rows() / std::max(count, 1));
  std::vector<LocalGeometry> out;
  for (Eigen::Index v = 0; v < mesh_.V.rows(); v += step) out.push_back(closestPoint(mesh_.V.row(v).transpose()));
  return out;
}

LocalGeometry MeshSurface::closestPoint(const Vec3& p) const {
  double best = std::numeric_limits<double>::infinity();
  int triangle = 0;
  Vec3 barycentric(1, 0, 0);
  if (!searchGrid(p, best, triangle, barycentric)) searchTree(p, best, triangle, barycentric);
  return geometryInTriangle(triangle, barycentric);
}

std::string curvatureCsv(const std::vector<LocalGeometry>& rows) {
  std::string out = "x,y,z,k1,k2,d1x,d1y,d1z,d2x,d2y,d2z\n";
  char buf[512];
  for (const LocalGeometry& r : rows) {
    std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", r.point.x(),
                  r.point.y(), r.point.z(), r.k1, r.k2, r.d1.x(), r.d1.y(), r.d1.z(), r.d2.x(), r.d2.y(), r.d2.z());
    out += buf;
  }
  return out;
}

Vec3 closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 w = closestBarycentric(p, a, b, c);
  return w(0) * a + w(1) * b + w(2) * c;
}

bool noisyUpload(const Surface& surface) {
  const auto* upload = dynamic_cast<const MeshSurface*>(&surface);
  return upload && upload->noise() > MeshSurface::kNoisyMesh;
}

}  // namespace phex
