// phex — the cell's scale along the 6-fold field that makes its lattice integrable: where the field turns (on
// curved surfaces it must), a lattice of one size cannot follow it without dislocations (pentagon-heptagon pairs,
// a row more on one side than on the other); one whose size varies as e^phi with grad phi = -J omega can, omega
// being the field's rotation against the metric's parallel transport.
#include <algorithm>
#include <cmath>

#include <Eigen/Sparse>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>

#include "global.hpp"
#include "phex/parallel.hpp"

namespace phex::global {
namespace {

// e^x with +, -, *, / alone (libm's exp may differ between platforms in the last bit): the Taylor series of
// e^(x / 2^16), squared 16 times.
double exponential(double x) {
  const double y = x / 65536.0;
  double term = 1, sum = 1;
  for (int k = 1; k <= 7; ++k) term *= y / k, sum += term;
  for (int k = 0; k < 16; ++k) sum *= sum;
  return sum;
}


// Conjugate gradients on the fine equations, preconditioned by a two-grid cycle, until the residual is this
// much of the right-hand side's (or kScaleIterations).
constexpr double kScaleResidual = 1e-8;
constexpr int kScaleIterations = 200;

// Each vertex's aggregate: greedily, in vertex order, a vertex whose ring is all free takes its two-ring's free
// vertices; those left join the aggregate of a neighbour (the first in their ring), or are one of their own.
// Returns the aggregates' count.
int aggregates2Ring(const std::vector<std::vector<int>>& adjacent, std::vector<int>& of) {
  const int nv = static_cast<int>(adjacent.size());
  of.assign(nv, -1);
  int count = 0;
  for (int v = 0; v < nv; ++v) {
    if (of[v] >= 0) continue;
    bool free = true;
    for (int u : adjacent[v]) free = free && of[u] < 0;
    if (!free) continue;
    of[v] = count;
    for (int u : adjacent[v]) of[u] = count;
    for (int u : adjacent[v])
      for (int w : adjacent[u])
        if (of[w] < 0) of[w] = count;
    ++count;
  }
  for (int v = 0; v < nv; ++v)
    if (of[v] < 0) {
      for (int u : adjacent[v])
        if (of[u] >= 0) {
          of[v] = of[u];
          break;
        }
      if (of[v] < 0) of[v] = count++;
    }
  return count;
}

// The preconditioner of conjugate gradients on K x = rhs (K symmetric positive definite, stored whole) on a large
// mesh: a symmetric two-grid cycle, a Gauss-Seidel sweep forwards, the correction solved on the aggregates (their
// rows and columns summed: the Galerkin product for a piecewise-constant prolongation), a sweep backwards. In
// Eigen's preconditioner interface (set up before the solver's compute, which leaves it as it is).
class TwoGrid {
 public:
  template <typename Matrix>
  TwoGrid& analyzePattern(const Matrix&) { return *this; }
  template <typename Matrix>
  TwoGrid& factorize(const Matrix&) { return *this; }
  template <typename Matrix>
  TwoGrid& compute(const Matrix&) { return *this; }
  Eigen::ComputationInfo info() { return coarse_.info(); }

  // K's aggregates `of` (count of them) and its entries; false where their system cannot be factorized.
  bool setUp(const std::vector<Eigen::Triplet<double>>& entries, const Eigen::SparseMatrix<double>& K,
             const std::vector<int>& of, int count) {
    K_ = &K, of_ = &of, count_ = count;
    std::vector<Eigen::Triplet<double>> summed;
    summed.reserve(entries.size());
    for (const Eigen::Triplet<double>& e : entries) summed.emplace_back(of[e.row()], of[e.col()], e.value());
    Eigen::SparseMatrix<double> Kc(count, count);
    Kc.setFromTriplets(summed.begin(), summed.end());
    coarse_.compute(Kc);
    return coarse_.info() == Eigen::Success;
  }

  Eigen::VectorXd solve(const Eigen::VectorXd& r) const {
    const Eigen::SparseMatrix<double>& K = *K_;
    const std::vector<int>& of = *of_;
    const int n = static_cast<int>(r.size());
    // One Gauss-Seidel step on row v of K z = r (column v holds row v, K being symmetric).
    auto relax = [&](Eigen::VectorXd& z, int v) {
      double diagonal = 0, sum = r(v);
      for (Eigen::SparseMatrix<double>::InnerIterator it(K, v); it; ++it)
        if (it.row() == v) diagonal += it.value();
        else sum -= it.value() * z(it.row());
      if (diagonal > 0) z(v) = sum / diagonal;
    };
    Eigen::VectorXd z = Eigen::VectorXd::Zero(n);
    for (int v = 0; v < n; ++v) relax(z, v);
    const Eigen::VectorXd residual = r - K * z;
    Eigen::VectorXd rc = Eigen::VectorXd::Zero(count_);
    for (int v = 0; v < n; ++v) rc(of[v]) += residual(v);
    const Eigen::VectorXd y = coarse_.solve(rc);
    for (int v = 0; v < n; ++v) z(v) += y(of[v]);
    for (int v = n - 1; v >= 0; --v) relax(z, v);
    return z;
  }

 private:
  const Eigen::SparseMatrix<double>* K_ = nullptr;
  const std::vector<int>* of_ = nullptr;
  int count_ = 0;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> coarse_;
};

// K x = rhs on a large mesh by Eigen's conjugate gradients, preconditioned by TwoGrid. False where the aggregates'
// system cannot be factorized or the solution is not finite.
bool solveTwoGrid(const std::vector<Eigen::Triplet<double>>& entries, const Eigen::SparseMatrix<double>& K,
                  const Eigen::VectorXd& rhs, const std::vector<int>& of, int count, Eigen::VectorXd& x) {
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper, TwoGrid> cg;
  if (!cg.preconditioner().setUp(entries, K, of, count)) return false;
  cg.setTolerance(kScaleResidual);
  cg.setMaxIterations(kScaleIterations);
  cg.compute(K);
  x = cg.solve(rhs);
  return x.allFinite();
}

}  // namespace

// Above kDirectScale vertices the normal equations are not factorized as they are (a 20k-triangle upload refined
// for 100k faces: 490k vertices, three factorizations of 18 s each and most of the run's memory) but solved
// iteratively, a factorization of their sums over aggregates of vertices preconditioning (solveTwoGrid): 35-38
// iterations to 1e-8 there, 1.8 s a step.
std::vector<double> integrableScale(const FieldMesh& m, const std::vector<Vec3>& q, double strength, int directLimit) {
  std::vector<double> scale(m.vertexCount(), 1.0);
  if (strength == 0) return scale;
  // Solved on the coarse mesh the field mesh refines (phi is smooth), then interpolated.
  const Triangles& F = m.coarse.F.rows() > 0 ? m.coarse.F : m.F;
  const int nv = m.coarse.F.rows() > 0 ? static_cast<int>(m.coarse.V.rows()) : m.vertexCount();
  const int nf = static_cast<int>(F.rows());
  std::vector<std::vector<int>> adjacent(nv);
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) adjacent[F(f, c)].push_back(F(f, (c + 1) % 3)), adjacent[F(f, (c + 1) % 3)].push_back(F(f, c));
  for (std::vector<int>& row : adjacent) {
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
  }
  // Triangles at or next to a singular point carry its turn (+-60 degrees), which no smooth scale absorbs.
  std::vector<char> nearSingular(nv, 0);
  for (int f = 0; f < nf; ++f)
    if (singularityIndex(m, q, F(f, 0), F(f, 1), F(f, 2)) != 0)
      for (int c = 0; c < 3; ++c) nearSingular[F(f, c)] = 1;
  // Per triangle, the lattice coordinates' increments along its edges (the lattice of unit cell at each corner, its
  // directions matched to corner 0's): c_e = (alpha_a + alpha_b)(x_b - x_a) / 2 with alpha the coframe dual to the
  // corner's lattice vectors. Integrable: sum_e e^-phi_e c_e = 0 around every triangle (phi_e the mean of its ends).
  struct Tri {
    Vec2 c[3];  // edges 0->1, 1->2, 2->0
    bool use = false;
  };
  std::vector<Tri> tris(nf);
  parallelRanges(nf, 4096, [&](int begin, int end) {
    for (int f = begin; f < end; ++f) {
      const int c[3] = {F(f, 0), F(f, 1), F(f, 2)};
      Tri& t = tris[f];
      if (nearSingular[c[0]] || nearSingular[c[1]] || nearSingular[c[2]]) continue;
      Vec3 U[3], V[3];
      for (int k = 0; k < 3; ++k) {
        const Frame& fk = m.frame[c[k]];
        // Corner k's direction that, carried to corner 0, is nearest corner 0's.
        int turns = 0;
        if (k > 0) matchDirection(q[c[0]], m.frame[c[0]], q[c[k]], fk, m.point(c[0]) - m.point(c[k]), &turns);
        Vec3 own = q[c[k]];
        for (int r = 0; r < turns; ++r) own = rotate60(own, fk.n);
        U[k] = fk.fromDupin(own), V[k] = fk.fromDupin(rotate60(own, fk.n));
      }
      auto coords = [&](int k, const Vec3& e) {  // alpha_k(e): e in the basis U[k], V[k]
        const double uu = dot(U[k], U[k]), uv = dot(U[k], V[k]), vv = dot(V[k], V[k]);
        const double du = dot(U[k], e), dv = dot(V[k], e), det = uu * vv - uv * uv;
        return Vec2((vv * du - uv * dv) / det, (uu * dv - uv * du) / det);
      };
      for (int k = 0; k < 3; ++k) {
        const int a = k, b = (k + 1) % 3;
        const Vec3 e = m.point(c[b]) - m.point(c[a]);
        t.c[k] = 0.5 * (coords(a, e) + coords(b, e));
      }
      t.use = t.c[0].allFinite() && t.c[1].allFinite() && t.c[2].allFinite();
    }
  });
  // Gauss-Newton on phi: per triangle, sum_e w_e c_e (1 - (dphi_a + dphi_b) / 2) = 0 with w_e = e^-phi_e, plus a
  // light smoothness term (the graph Laplacian, weight kSmooth) that keeps phi defined where no triangle constrains it.
  double squares = 0;
  int used = 0;
  for (const Tri& t : tris)
    if (t.use) squares += t.c[0].squaredNorm() + t.c[1].squaredNorm() + t.c[2].squaredNorm(), used += 3;
  const double kSmooth = 1e-3 * (used > 0 ? squares / used : 1.0);
  std::vector<double> phi(nv, 0.0), weight(nv, 1.0);
  std::vector<int> aggregate;
  const int aggregates = nv > directLimit ? aggregates2Ring(adjacent, aggregate) : 0;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  for (int step = 0; step < 3; ++step) {
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(15 * static_cast<std::size_t>(nf) + nv);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nv);
    for (int f = 0; f < nf; ++f) {
      const Tri& t = tris[f];
      if (!t.use) continue;
      const int c[3] = {F(f, 0), F(f, 1), F(f, 2)};
      // Row r (x and y) of J dphi = curl: the coefficient of dphi at corner k.
      double J[2][3] = {{0, 0, 0}, {0, 0, 0}};
      Vec2 curl = Vec2::Zero();
      for (int k = 0; k < 3; ++k) {
        const int a = k, b = (k + 1) % 3;
        const double w = 1 / std::sqrt(weight[c[a]] * weight[c[b]]);  // e^-(phi_a + phi_b) / 2
        const Vec2 wc = w * t.c[k];
        curl += wc;
        for (int r = 0; r < 2; ++r) J[r][a] += 0.5 * wc(r), J[r][b] += 0.5 * wc(r);
      }
      // Less the triangle's mean: a uniform change of scale leaves a lattice as (non-)integrable as it is, and the
      // linear term alone would take shrinking everything for a cure.
      for (int r = 0; r < 2; ++r)
        for (int k = 0; k < 3; ++k) J[r][k] -= curl(r) / 3;
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) entries.emplace_back(c[a], c[b], J[0][a] * J[0][b] + J[1][a] * J[1][b]);
        rhs(c[a]) += J[0][a] * curl(0) + J[1][a] * curl(1);
      }
    }
    for (int v = 0; v < nv; ++v) {
      const int degree = static_cast<int>(adjacent[v].size());
      entries.emplace_back(v, v, kSmooth * (degree + 1e-3));
      for (int u : adjacent[v]) {
        entries.emplace_back(v, u, -kSmooth);
        rhs(v) -= kSmooth * (phi[v] - phi[u]);
      }
    }
    Eigen::SparseMatrix<double> K(nv, nv);
    K.setFromTriplets(entries.begin(), entries.end());
    Eigen::VectorXd delta;
    if (aggregates > 0) {
      if (!solveTwoGrid(entries, K, rhs, aggregate, aggregates, delta)) break;
    } else {
      // The steps' matrices share one pattern (the same triplets, other values): ordered once (the bench's upload
      // at 10k faces: three orderings took 9 of the 30 ms).
      if (step == 0) solver.analyzePattern(K);
      solver.factorize(K);
      if (solver.info() != Eigen::Success) break;
      delta = solver.solve(rhs);
    }
    // The constant is free (a uniform scale leaves the lattice as integrable): the mean step is taken out.
    delta.array() -= delta.mean();
    for (int v = 0; v < nv; ++v) {
      phi[v] = std::clamp(phi[v] + strength * delta(v), -0.6, 0.6);
      weight[v] = exponential(phi[v]);
    }
  }
  // On the field mesh (interpolated from the coarse one where it refines it), the mean cell area kept:
  // sum A e^(-2 phi) = sum A.
  double area = 0, weighted = 0;
  for (int v = 0; v < m.vertexCount(); ++v) {
    double p = v < nv ? phi[v] : 0.0;
    if (v >= nv) {
      const auto& [f, b] = m.where[v];
      for (int c = 0; c < 3; ++c) p += b(c) * phi[F(f, c)];
    }
    scale[v] = exponential(p);
    area += m.area[v], weighted += m.area[v] / (scale[v] * scale[v]);
  }
  const double k = weighted > 0 ? std::sqrt(weighted / area) : 1.0;
  for (double& x : scale) x *= k;
  return scale;
}

}  // namespace phex::global
