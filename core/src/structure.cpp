// phex — the structure on a P-Hex mesh: node axes, offsets at constant face distance, planar beams, solid model.
#include "phex/structure.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>

#include "phex/error.hpp"
#include "phex/mesh_io.hpp"
#include "phex/parallel.hpp"

namespace phex {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = 180.0 / kPi;
constexpr double kInf = std::numeric_limits<double>::infinity();
// A node of three faces is solved exactly (Cramer) unless its normals span almost no volume (|det| below this:
// the planes nearly parallel to one line, a developable's or a flat region's), where the least-squares fit with
// the smallest norm takes over and tells whether the planes still have an equidistant axis.
constexpr double kConeDeterminant = 1e-10;
// Least squares: directions along which the normals' matrix N^T N has eigenvalues below this share of its largest
// are left out (the smallest-norm solution); 1e-12 in eigenvalues is 1e-6 in singular values.
constexpr double kLeastSquaresCutoff = 1e-12;
// A best fit equidistant to this (|n · a - 1|, relative) is exact: the planes do touch one cone.
constexpr double kExactResidual = 1e-9;
// A best fit that misses its planes' equal distance by more than this (a quarter of the face distance) is no fit:
// such a node is treated as Folded.
constexpr double kBestFitResidualMax = 0.25;

std::string nodeName(int v) { return "node " + std::to_string(v + 1); }

double angleDeg(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)) * kDeg; }

// The least-squares solution of smallest norm of n_i · x = r_i over k unit normals: exact for three in general
// position (Cramer), and for one or two; directions the normals barely constrain are left out.
Vec3 solveOnPlanes(const Vec3* n, int k, const double* r) {
  const double det = k == 3 ? n[0].dot(n[1].cross(n[2])) : 0.0;
  if (k == 3 && std::abs(det) >= kConeDeterminant)
    return (r[0] * n[1].cross(n[2]) + r[1] * n[2].cross(n[0]) + r[2] * n[0].cross(n[1])) / det;
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  Vec3 b = Vec3::Zero();
  for (int i = 0; i < k; ++i) m += n[i] * n[i].transpose(), b += r[i] * n[i];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(m);
  const double largest = es.eigenvalues()(2);
  Vec3 x = Vec3::Zero();
  for (int j = 0; j < 3; ++j)
    if (es.eigenvalues()(j) > kLeastSquaresCutoff * largest)
      x += es.eigenvectors().col(j) * (es.eigenvectors().col(j).dot(b) / es.eigenvalues()(j));
  return x;
}

// The boundary rule (see BoundaryRule in the header): the free turns of the boundary nodes' axes solved for
// planar boundary beams, nearest the reference axes, run by run.
void applyBoundaryRule(const PolyMesh& mesh, NodeAxes& ax) {
  const int nv = static_cast<int>(mesh.V.rows());
  // Free directions of each node's axis (columns of B_v): one for a Boundary node (along its edge of two faces),
  // two for a Corner (within its face), none otherwise.
  std::vector<int> first(nv + 1, 0);
  std::vector<Vec3> basis;
  for (int v = 0; v < nv; ++v) {
    first[v] = static_cast<int>(basis.size());
    const int* faces = ax.nodeFaces.data() + ax.nodeFaceOffsets[v];
    if (ax.kind[v] == NodeKind::Boundary) {
      const Vec3 e = ax.planes[faces[0]].normal.cross(ax.planes[faces[1]].normal);
      if (e.norm() > 1e-9) {
        basis.push_back(e.normalized());
        continue;
      }
      // Two faces in one plane: their axes are free within it, as a corner's.
    }
    if (ax.kind[v] == NodeKind::Boundary || ax.kind[v] == NodeKind::Corner) {
      const Vec3 n = ax.axis.row(v).transpose().normalized();
      const Vec3 p = n.unitOrthogonal();
      basis.push_back(p);
      basis.push_back(n.cross(p));
    }
  }
  first[nv] = static_cast<int>(basis.size());
  // Boundary edges, and runs of them joined by nodes with free turns (union-find over the edges).
  std::vector<int> boundary;
  for (int e = 0; e < static_cast<int>(ax.edges.size()); ++e)
    if (ax.edges[e].right < 0) boundary.push_back(e);
  ax.boundaryBeams = static_cast<int>(boundary.size());
  if (boundary.empty()) return;
  std::vector<int> parent(boundary.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::vector<int> edgeAt(nv, -1);  // a boundary edge at each node with free turns
  for (int i = 0; i < static_cast<int>(boundary.size()); ++i)
    for (int v : {ax.edges[boundary[i]].a, ax.edges[boundary[i]].b}) {
      if (first[v + 1] == first[v]) continue;
      if (edgeAt[v] < 0) edgeAt[v] = i;
      else parent[find(i)] = find(edgeAt[v]);
    }
  std::vector<std::vector<int>> runs(boundary.size());
  for (int i = 0; i < static_cast<int>(boundary.size()); ++i) runs[find(i)].push_back(i);
  const Points reference = ax.axis;
  double turnMax = 0;
  for (const std::vector<int>& run : runs) {
    if (run.empty()) continue;
    // Unknowns of the run: the free turns of its nodes, numbered in order of appearance.
    std::vector<int> nodes;
    std::vector<int> column(nv, -1);
    int m = 0;
    for (int i : run)
      for (int v : {ax.edges[boundary[i]].a, ax.edges[boundary[i]].b})
        if (first[v + 1] > first[v] && column[v] < 0) column[v] = m, m += first[v + 1] - first[v], nodes.push_back(v);
    if (m == 0) continue;  // both ends fixed: nothing to choose
    ++ax.boundaryRuns;
    // One equation per edge: u · a_a - u · a_b = 0, u = e × n_f, with a = reference + B x.
    const int r = static_cast<int>(run.size());
    std::vector<Eigen::Triplet<double>> triplets;
    Eigen::VectorXd rhs(r);
    for (int row = 0; row < r; ++row) {
      const MeshEdge& e = ax.edges[boundary[run[row]]];
      const Vec3 u = (ax.position.row(e.b) - ax.position.row(e.a)).transpose().cross(ax.planes[e.left].normal).normalized();
      rhs(row) = u.dot(reference.row(e.b).transpose() - reference.row(e.a).transpose());
      for (const auto& [v, sign] : {std::pair<int, double>{e.a, 1.0}, {e.b, -1.0}})
        for (int j = first[v]; j < first[v + 1]; ++j)
          if (column[v] >= 0) triplets.emplace_back(row, column[v] + j - first[v], sign * u.dot(basis[j]));
    }
    Eigen::SparseMatrix<double> C(r, m);
    C.setFromTriplets(triplets.begin(), triplets.end());
    // The smallest turns that solve C x = rhs: x = Cᵀ y, (C Cᵀ) y = rhs; a ridge of round-off size keeps a
    // singular C Cᵀ (dependent equations) factorable, and the residual then tells whether x solves them.
    Eigen::SparseMatrix<double> CCt = C * C.transpose();
    double ridge = 0;
    for (int row = 0; row < r; ++row) ridge = std::max(ridge, CCt.coeff(row, row));
    for (int row = 0; row < r; ++row) CCt.coeffRef(row, row) += 1e-14 * std::max(ridge, 1e-300);
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(CCt);
    bool planar = ldlt.info() == Eigen::Success;
    Eigen::VectorXd x;
    if (planar) {
      x = C.transpose() * ldlt.solve(rhs);
      planar = x.allFinite() && (C * x - rhs).cwiseAbs().maxCoeff() <= 1e-10;
    }
    double runTurn = 0;
    if (planar)
      for (int v : nodes) {
        Vec3 a = reference.row(v).transpose();
        for (int j = first[v]; j < first[v + 1]; ++j) a += x(column[v] + j - first[v]) * basis[j];
        runTurn = std::max(runTurn, angleDeg(a, reference.row(v).transpose()));
      }
    if (planar && runTurn <= kBoundaryTurnLimitDeg) {
      ++ax.boundaryRunsPlanar;
      turnMax = std::max(turnMax, runTurn);
      for (int v : nodes)
        for (int j = first[v]; j < first[v + 1]; ++j) ax.axis.row(v) += x(column[v] + j - first[v]) * basis[j].transpose();
    } else {
      ax.notes.push_back("boundary: the run of " + std::to_string(r) + " boundary beams from " + nodeName(ax.edges[boundary[run[0]]].a) +
                         (planar ? " would need its axes turned by up to " + formatNumber(runTurn) + "° to be planar"
                                 : " has no planar solution") +
                         " (the limit is " + formatNumber(kBoundaryTurnLimitDeg) +
                         "°): its axes stay along the surface normal and its beams twist");
    }
  }
  ax.boundaryTurnMaxDeg = turnMax;
}

// The face distance at which edge e's offset, e (1 + d s) with s its stretch per unit of face distance, gets
// shorter than kOffsetEdgeVanishes of the mean edge (`edge`): +inf / -inf where it never shrinks that way; NaN
// for an edge that short already (nodes that nearly coincide), which no offset is judged by.
double vanishingDistance(const NodeAxes& ax, const MeshEdge& e, double edge) {
  const Eigen::RowVector3d d = ax.position.row(e.b) - ax.position.row(e.a);
  const double length = d.norm();
  if (!(length >= kOffsetEdgeVanishes * edge)) return std::numeric_limits<double>::quiet_NaN();
  const double s = (ax.axis.row(e.b) - ax.axis.row(e.a)).dot(d) / (length * length);
  return s == 0 ? kInf : (kOffsetEdgeVanishes * edge / length - 1) / s;
}

// The mesh with every node at position + d a (unchecked).
PolyMesh shifted(const PolyMesh& mesh, const NodeAxes& ax, double d) {
  PolyMesh out;
  out.V = ax.position + d * ax.axis;
  out.offsets = mesh.offsets;
  out.indices = mesh.indices;
  return out;
}

std::string edgeName(const MeshEdge& e) {
  return "the edge between nodes " + std::to_string(e.a + 1) + " and " + std::to_string(e.b + 1) + " of panel " + panelLabel(e.left) +
         (e.right >= 0 ? " (and " + panelLabel(e.right) + ")" : std::string());
}

std::string rangeText(const NodeAxes& ax) {
  return "face distances from " + (std::isfinite(ax.offsetMin) ? formatNumber(ax.offsetMin) : std::string("-infinity")) +
         " to " + (std::isfinite(ax.offsetMax) ? formatNumber(ax.offsetMax) : std::string("infinity")) + " can be taken";
}

// Checks the offset `out` = shifted(mesh, ax, d) (see checkOffsetDistance); the faces of `out` that cross
// themselves (seen along their normals) go to `crossing`.
void checkShifted(const PolyMesh& mesh, const NodeAxes& ax, const PolyMesh& out, double d, const std::string& name,
                  double value, std::vector<int>* crossing) {
  if (!std::isfinite(d) || d == 0)
    throw Error(ErrorCode::InvalidParameter, name + " must be a finite number other than 0 (got " + formatNumber(value) + ")");
  if (d > ax.offsetMax || d < ax.offsetMin) {
    // The edge that vanishes first on this side.
    int worst = -1;
    double at = 0;
    for (int e = 0; e < static_cast<int>(ax.edges.size()); ++e) {
      const double dv = vanishingDistance(ax, ax.edges[e], ax.meanEdge);
      if ((d > 0) == (dv > 0) && (worst < 0 || std::abs(dv) < std::abs(at))) worst = e, at = dv;
    }
    throw Error(ErrorCode::InvalidParameter,
                name + " = " + formatNumber(value) + (d == value ? "" : " (face distance " + formatNumber(d) + ")") +
                    " is more than the offset can take: " + edgeName(ax.edges[worst]) + " vanishes at face distance " + formatNumber(at) + "; " + rangeText(ax));
  }
  if (!crossing) return;
  for (int f = 0; f < mesh.faceCount(); ++f) {
    // A convex face whose corners are all Cone nodes keeps every edge's direction in the offset (each lies on the
    // line where its two shifted planes meet) and every edge's length positive: it stays convex.
    bool cones = ax.convex[f];
    for (int k = 0; k < mesh.faceSize(f) && cones; ++k) cones = ax.kind[mesh.face(f)[k]] == NodeKind::Cone;
    if (!cones && faceSelfIntersects(out, f, ax.planes[f].normal)) crossing->push_back(f);
  }
}

// A note naming the panels whose offset at `name` crosses itself, if any.
void noteCrossing(const std::vector<int>& crossing, const std::string& name, double value, std::vector<std::string>& notes) {
  if (crossing.empty()) return;
  std::string names;
  for (std::size_t i = 0; i < crossing.size() && i < 12; ++i) names += (i ? ", " : "") + panelLabel(crossing[i]);
  if (crossing.size() > 12) names += ", ...";
  notes.push_back(std::to_string(crossing.size()) + " panels cross themselves at " + name + " = " + formatNumber(value) +
                  " (pinched panels whose corners nearly touch): " + names);
}

Vec3 boxOrigin(const Points& V) {
  if (V.rows() == 0) return Vec3::Zero();
  const Vec3 lo = V.colwise().minCoeff().transpose(), hi = V.colwise().maxCoeff().transpose();
  const Vec3 centre = 0.5 * (lo + hi);
  return centre.norm() > 10 * (hi - lo).norm() ? centre : Vec3::Zero();
}

}  // namespace

const char* nodeKindName(NodeKind kind) {
  switch (kind) {
    case NodeKind::Cone: return "cone";
    case NodeKind::Boundary: return "boundary";
    case NodeKind::Corner: return "corner";
    case NodeKind::BestFit: return "best-fit";
    case NodeKind::Folded: return "folded";
    case NodeKind::Free: return "free";
  }
  return "?";
}

NodeAxes nodeAxes(const PolyMesh& mesh) {
  checkPolyMesh(mesh, "structure");
  const int nf = mesh.faceCount(), nv = static_cast<int>(mesh.V.rows());
  NodeAxes ax;
  // Face planes: least squares, the normal turned like the face's vector area (computed about the centroid, so
  // that site coordinates keep their digits), which also finds faces without area.
  ax.planes.resize(nf);
  ax.convex.resize(nf);
  parallelRanges(nf, kPointsPerThread, [&](int begin, int end) {
    for (int f = begin; f < end; ++f) {
      FacePlane plane = leastSquaresPlane(mesh, f);
      const int n = mesh.faceSize(f);
      const int* ids = mesh.face(f);
      Vec3 area = Vec3::Zero();
      double radius = 0;
      for (int k = 0; k < n; ++k) {
        const Vec3 p = mesh.vertex(ids[k]) - plane.centroid, q = mesh.vertex(ids[(k + 1) % n]) - plane.centroid;
        area += p.cross(q);
        radius = std::max(radius, p.norm());
      }
      if (!(area.norm() > 1e-12 * radius * radius))
        throw Error(ErrorCode::InvalidInput, "structure: face " + std::to_string(f) + " (" + panelLabel(f) +
                                                 ") is degenerate: it has no area");
      if (area.dot(plane.normal) < 0) plane.normal = -plane.normal;
      ax.planes[f] = plane;
      // Convex: every corner turns left seen from the normal side.
      bool convex = true;
      for (int k = 0; k < n && convex; ++k) {
        const Vec3 p = mesh.vertex(ids[k]), q = mesh.vertex(ids[(k + 1) % n]), r = mesh.vertex(ids[(k + 2) % n]);
        convex = (q - p).cross(r - q).dot(plane.normal) > 0;
      }
      ax.convex[f] = convex;
    }
  });
  ax.edges = meshEdges(mesh, "structure");
  // Faces at each node.
  ax.nodeFaceOffsets.assign(nv + 1, 0);
  for (int id : mesh.indices) ++ax.nodeFaceOffsets[id + 1];
  for (int v = 0; v < nv; ++v) ax.nodeFaceOffsets[v + 1] += ax.nodeFaceOffsets[v];
  ax.nodeFaces.resize(mesh.indices.size());
  {
    std::vector<int> fill(ax.nodeFaceOffsets.begin(), ax.nodeFaceOffsets.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < mesh.faceSize(f); ++k) ax.nodeFaces[fill[mesh.face(f)[k]]++] = f;
  }
  // Axes node by node, and the nodes onto their planes.
  ax.axis.setZero(nv, 3);
  ax.position = mesh.V;
  ax.kind.assign(nv, NodeKind::Free);
  ax.residual.assign(nv, 0.0);
  const double foldedScale = 1 / std::sin(kFoldedAxisDeg / kDeg);
  const double edge = ax.meanEdge = mesh.meanEdgeLength();
  int free = 0;
  std::vector<Vec3> normals;
  std::vector<double> ones, gaps;
  for (int v = 0; v < nv; ++v) {
    const int k = ax.nodeFaceOffsets[v + 1] - ax.nodeFaceOffsets[v];
    const int* faces = ax.nodeFaces.data() + ax.nodeFaceOffsets[v];
    if (k == 0) {
      ++free;
      continue;
    }
    normals.resize(k), ones.assign(k, 1.0), gaps.resize(k);
    for (int i = 0; i < k; ++i) {
      const FacePlane& plane = ax.planes[faces[i]];
      normals[i] = plane.normal;
      gaps[i] = plane.normal.dot(plane.centroid - mesh.vertex(v));
    }
    Vec3 a = solveOnPlanes(normals.data(), k, ones.data());
    NodeKind kind = k == 1 ? NodeKind::Corner : k == 2 ? NodeKind::Boundary : k == 3 ? NodeKind::Cone : NodeKind::BestFit;
    double residual = 0;
    for (const Vec3& n : normals) residual = std::max(residual, std::abs(n.dot(a) - 1));
    if (kind == NodeKind::Cone && residual > kExactResidual) kind = NodeKind::BestFit;  // planes parallel to one line
    if (!(a.norm() <= foldedScale) || (kind == NodeKind::BestFit && residual > kBestFitResidualMax)) {
      kind = NodeKind::Folded;
      Vec3 mean = Vec3::Zero();
      for (const Vec3& n : normals) mean += n;
      a = mean.norm() > 1e-6 * k ? Vec3(mean.normalized()) : normals[0];
    }
    if (kind == NodeKind::BestFit || kind == NodeKind::Folded) {
      ax.residual[v] = residual;
      (kind == NodeKind::BestFit ? ax.bestFit : ax.folded).push_back(v);
    }
    if (kind != NodeKind::Folded) {
      const Vec3 move = solveOnPlanes(normals.data(), k, gaps.data());
      ax.position.row(v) += move.transpose();
      ax.snapMax = std::max(ax.snapMax, move.norm() / edge);
    }
    ax.kind[v] = kind;
    ax.axis.row(v) = a.transpose();
  }
  // Folded nodes: the mean axis of their neighbours with axes of their own, spread inwards where they cluster, so
  // that offsets and beams pass over the fold without a leap (the unit mean normal stays where none is near).
  if (!ax.folded.empty()) {
    std::vector<int> at(nv + 1, 0), other;
    for (const MeshEdge& e : ax.edges) ++at[e.a + 1], ++at[e.b + 1];
    for (int v = 0; v < nv; ++v) at[v + 1] += at[v];
    other.resize(at[nv]);
    std::vector<int> fill(at.begin(), at.end() - 1);
    for (const MeshEdge& e : ax.edges) other[fill[e.a]++] = e.b, other[fill[e.b]++] = e.a;
    std::vector<char> known(nv);
    for (int v = 0; v < nv; ++v) known[v] = ax.kind[v] != NodeKind::Folded && ax.kind[v] != NodeKind::Free;
    std::vector<int> pending = ax.folded, later;
    std::vector<std::pair<int, Vec3>> found;
    while (!pending.empty()) {
      later.clear(), found.clear();
      for (int v : pending) {
        Vec3 sum = Vec3::Zero();
        int count = 0;
        for (int i = at[v]; i < at[v + 1]; ++i)
          if (known[other[i]]) sum += ax.axis.row(other[i]).transpose(), ++count;
        if (count > 0) found.emplace_back(v, sum / count);
        else later.push_back(v);
      }
      if (found.empty()) break;
      for (const auto& [v, a] : found) ax.axis.row(v) = a.transpose(), known[v] = 1;
      pending.swap(later);
    }
    for (int v : ax.folded) {
      double residual = 0;
      for (int i = ax.nodeFaceOffsets[v]; i < ax.nodeFaceOffsets[v + 1]; ++i)
        residual = std::max(residual, std::abs(ax.planes[ax.nodeFaces[i]].normal.dot(ax.axis.row(v).transpose()) - 1));
      ax.residual[v] = residual;
    }
  }
  applyBoundaryRule(mesh, ax);
  // Boundary beams' twist, and how far offsets can go before an edge vanishes.
  ax.offsetMin = -kInf, ax.offsetMax = kInf;
  int shortEdges = 0;
  for (const MeshEdge& e : ax.edges) {
    const double dv = vanishingDistance(ax, e, edge);
    if (std::isnan(dv)) ++shortEdges;
    else if (dv > 0) ax.offsetMax = std::min(ax.offsetMax, dv);
    else ax.offsetMin = std::max(ax.offsetMin, dv);
    if (e.right >= 0) continue;
    const Vec3 d = (ax.position.row(e.b) - ax.position.row(e.a)).transpose();
    const double twist = angleDeg(d.cross(ax.axis.row(e.a).transpose()), d.cross(ax.axis.row(e.b).transpose()));
    ax.boundaryTwistMaxDeg = std::max(ax.boundaryTwistMaxDeg, twist);
    ax.boundaryBeamsPlanar += twist <= 1e-9 * kDeg;
  }
  // Notes: what the structure could not do exactly, by name.
  if (!ax.bestFit.empty()) {
    std::string names;
    for (std::size_t i = 0; i < ax.bestFit.size() && i < 12; ++i) names += (i ? ", " : "") + std::to_string(ax.bestFit[i] + 1);
    if (ax.bestFit.size() > 12) names += ", ...";
    double worst = 0;
    for (int v : ax.bestFit) worst = std::max(worst, ax.residual[v]);
    ax.notes.push_back(std::to_string(ax.bestFit.size()) +
                       " nodes of four or more panels (or three whose planes are parallel to one line) have no axis "
                       "equidistant from all their planes: nodes " + names +
                       " take the least-squares axis; their offset nodes miss the shifted planes by up to " +
                       formatNumber(worst) + " of the face distance, and the beams at them twist");
  }
  if (!ax.folded.empty()) {
    std::string names;
    for (std::size_t i = 0; i < ax.folded.size() && i < 12; ++i) names += (i ? ", " : "") + std::to_string(ax.folded[i] + 1);
    if (ax.folded.size() > 12) names += ", ...";
    ax.notes.push_back(std::to_string(ax.folded.size()) + " nodes where panels fold onto each other (an axis within " +
                       formatNumber(kFoldedAxisDeg) + "° of their planes): nodes " + names +
                       " take the mean axis of the nodes around them; offsets and beams are not exact at them");
  }
  if (ax.snapMax > 1e-6)
    ax.notes.push_back("nodes moved onto their panels' planes by up to " + formatNumber(ax.snapMax) +
                       " of the mean edge (where two panels at a node are nearly coplanar)");
  if (ax.boundaryBeams > 0)
    ax.notes.push_back("boundary: " + std::to_string(ax.boundaryBeamsPlanar) + " of " + std::to_string(ax.boundaryBeams) +
                       " boundary beams planar (" + std::to_string(ax.boundaryRunsPlanar) + " of " +
                       std::to_string(ax.boundaryRuns) + " runs solved, axes turned by up to " +
                       formatNumber(ax.boundaryTurnMaxDeg) + "° from the surface normal), largest twist " +
                       formatNumber(ax.boundaryTwistMaxDeg) + "°");
  if (shortEdges > 0)
    ax.notes.push_back(std::to_string(shortEdges) + " edges shorter than " + formatNumber(kOffsetEdgeVanishes) +
                       " of the mean edge (nodes that nearly coincide): their beams are degenerate, and offsets are not "
                       "judged by them");
  if (free > 0)
    ax.notes.push_back(std::to_string(free) + " vertices belong to no panel: they stay in place in every offset");
  return ax;
}

void checkOffsetDistance(const PolyMesh& mesh, const NodeAxes& axes, double d, const std::string& name, double value,
                         std::vector<int>* crossing) {
  checkShifted(mesh, axes, shifted(mesh, axes, std::isfinite(d) ? d : 0.0), d, name, value, crossing);
}

PolyMesh offsetMesh(const PolyMesh& mesh, const NodeAxes& axes, double d, std::vector<int>* crossing) {
  PolyMesh out = shifted(mesh, axes, std::isfinite(d) ? d : 0.0);
  checkShifted(mesh, axes, out, d, "offset", d, crossing);
  return out;
}

PolyMesh offsetMesh(const PolyMesh& mesh, double d) {
  if (!std::isfinite(d) || d == 0)
    throw Error(ErrorCode::InvalidParameter, "offset must be a finite number other than 0 (got " + formatNumber(d) + ")");
  return offsetMesh(mesh, nodeAxes(mesh), d);
}

BeamLayer beamLayer(const PolyMesh& mesh, const NodeAxes& axes, double h) {
  if (!(h > 0) || !std::isfinite(h))
    throw Error(ErrorCode::InvalidParameter, "beamHeight must be a positive number (got " + formatNumber(h) + ")");
  const PolyMesh back = shifted(mesh, axes, -h);
  BeamLayer layer;
  checkShifted(mesh, axes, back, -h, "beamHeight", h, &layer.crossing);
  layer.height = h;
  layer.beams.resize(axes.edges.size());
  for (std::size_t i = 0; i < axes.edges.size(); ++i) {
    const MeshEdge& e = axes.edges[i];
    Beam& b = layer.beams[i];
    b.corners = {axes.position.row(e.a).transpose(), axes.position.row(e.b).transpose(), back.vertex(e.b), back.vertex(e.a)};
    const Vec3 centroid = 0.25 * (b.corners[0] + b.corners[1] + b.corners[2] + b.corners[3]);
    // Relative to the centroid, so that site coordinates keep their digits.
    std::array<Vec3, 4> c;
    for (int k = 0; k < 4; ++k) c[k] = b.corners[k] - centroid;
    b.normal = (c[2] - c[0]).cross(c[3] - c[1]).normalized();
    b.planeOffset = b.normal.dot(centroid);
    double distance = 0, edges = 0;
    for (int k = 0; k < 4; ++k) distance = std::max(distance, std::abs(b.normal.dot(c[k]))), edges += (c[(k + 1) % 4] - c[k]).norm();
    b.planarity = distance / (edges / 4);
    const Vec3 along = (c[1] - c[0]).normalized();
    b.heightA = along.cross(c[3] - c[0]).norm();
    b.heightB = along.cross(c[2] - c[1]).norm();
    b.twistDeg = angleDeg(along.cross(axes.axis.row(e.a).transpose()), along.cross(axes.axis.row(e.b).transpose()));
    layer.planarityMax = std::max(layer.planarityMax, b.planarity);
    auto exact = [&](int v) { return axes.kind[v] != NodeKind::BestFit && axes.kind[v] != NodeKind::Folded; };
    if (e.right >= 0 && exact(e.a) && exact(e.b) && (c[1] - c[0]).norm() >= kOffsetEdgeVanishes * axes.meanEdge)
      layer.interiorPlanarityMax = std::max(layer.interiorPlanarityMax, b.planarity);
    layer.length += (c[1] - c[0]).norm();
  }
  return layer;
}

void validate(const StructureOptions& o) {
  if (o.offset && (!std::isfinite(*o.offset) || *o.offset == 0))
    throw Error(ErrorCode::InvalidParameter, "offset must be a finite number other than 0 (got " + formatNumber(*o.offset) + ")");
  for (const auto& [name, value] : {std::pair<const char*, const std::optional<double>&>{"beamHeight", o.beamHeight},
                                    {"beamWidth", o.beamWidth},
                                    {"panelThickness", o.panelThickness}})
    if (value && (!std::isfinite(*value) || !(*value > 0)))
      throw Error(ErrorCode::InvalidParameter, std::string(name) + " must be a positive number (got " + formatNumber(*value) + ")");
}

Structure buildStructure(const PolyMesh& mesh, const StructureOptions& options) {
  validate(options);
  Structure s;
  s.axes = nodeAxes(mesh);
  const NodeAxes& ax = s.axes;
  const double edge = mesh.meanEdgeLength();
  const double h = options.beamHeight.value_or(edge / 5);
  s.beamWidth = options.beamWidth.value_or(h / 4);
  s.panelThickness = options.panelThickness.value_or(edge / 50);
  std::vector<int> crossing;
  if (options.offset) {
    s.offset = offsetMesh(mesh, ax, *options.offset, &crossing);
    noteCrossing(crossing, "offset", *options.offset, s.notes);
  }
  s.beams = beamLayer(mesh, ax, h);
  noteCrossing(s.beams.crossing, "beamHeight", h, s.notes);
  const PolyMesh top = shifted(mesh, ax, s.panelThickness);
  crossing.clear();
  checkShifted(mesh, ax, top, s.panelThickness, "panelThickness", s.panelThickness, &crossing);
  noteCrossing(crossing, "panelThickness", s.panelThickness, s.notes);

  StructureModel& model = s.model;
  model.origin = boxOrigin(mesh.V);
  const Eigen::RowVector3d o = model.origin.transpose();
  // Panels: each face between its plane and the plane shifted by t; the bottom and top triangulated alike (a fan
  // for a convex face, ear clipping in the face's plane for a non-convex one, so it stays inside its outline), the
  // sides one quad per edge. Written straight into the arrays: this and the beams are most of the structure's time.
  {
    SolidPart& part = model.panels;
    const int nf = mesh.faceCount(), corners = static_cast<int>(mesh.indices.size());
    part.elements = nf;
    part.V.resize(2 * corners, 3);
    part.F.resize(4 * corners - 4 * nf, 3);  // n - 2 at the bottom and at the top, 2 n at the sides
    part.element.resize(part.F.rows());
    double* V = part.V.data();
    int* F = part.F.data();
    int t = 0;
    std::vector<int> ids, fan;
    for (int f = 0; f < nf; ++f) {
      const int n = mesh.faceSize(f), base = 2 * mesh.offsets[f];
      const int* id = mesh.face(f);
      for (int k = 0; k < n; ++k)
        for (int c = 0; c < 3; ++c) {
          V[3 * (base + k) + c] = ax.position(id[k], c) - o[c];
          V[3 * (base + n + k) + c] = top.V(id[k], c) - o[c];
        }
      // A fan from the first corner whose fan triangles all turn like the face (any corner of a convex face; a
      // reflex one of the K < 0 hexagons, §3); ear clipping where there is none.
      fan.clear();
      auto corner = [&](int k) { return Vec3(V[3 * (base + k)], V[3 * (base + k) + 1], V[3 * (base + k) + 2]); };
      const Vec3& normal = ax.planes[f].normal;
      int apex = ax.convex[f] ? 0 : -1;
      for (int j = 0; j < n && apex < 0; ++j) {
        bool turns = true;
        for (int k = 1; k + 1 < n && turns; ++k)
          turns = (corner((j + k) % n) - corner(j)).cross(corner((j + k + 1) % n) - corner(j)).dot(normal) > 0;
        if (turns) apex = j;
      }
      if (apex >= 0) {
        for (int k = 1; k + 1 < n; ++k) fan.insert(fan.end(), {apex, (apex + k) % n, (apex + k + 1) % n});
      } else {
        ids.resize(n);
        std::iota(ids.begin(), ids.end(), 0);
        triangulatePolygon(ids, V + 3 * base, fan);
      }
      const int first = t;
      auto add = [&](int a, int b, int c) { F[3 * t] = a, F[3 * t + 1] = b, F[3 * t + 2] = c, ++t; };
      for (std::size_t k = 0; k + 2 < fan.size(); k += 3) {
        add(base + fan[k], base + fan[k + 2], base + fan[k + 1]);              // bottom, reversed
        add(base + n + fan[k], base + n + fan[k + 1], base + n + fan[k + 2]);  // top
      }
      for (int k = 0; k < n; ++k) {
        const int a = base + k, b = base + (k + 1) % n;
        add(a, b, b + n);
        add(a, b + n, a + n);
      }
      std::fill(part.element.begin() + first, part.element.begin() + t, f);
    }
    part.F.conservativeResize(t, 3);  // a polygon ear clipping leaves unfinished has fewer triangles
    part.element.resize(t);
  }
  // Beams: each quad thickened by the width across its plane, half to either side.
  {
    SolidPart& part = model.beams;
    const int nb = static_cast<int>(s.beams.beams.size());
    part.elements = nb;
    part.V.resize(8 * nb, 3);
    part.F.resize(12 * nb, 3);
    part.element.resize(12 * nb);
    double* V = part.V.data();
    int* F = part.F.data();
    // The quad turns counterclockwise about its normal: the + side (corners 4..7) keeps its order, the - side
    // (0..3) reverses it, and each side quad turns outwards.
    static constexpr int kBox[12][3] = {{4, 5, 6}, {4, 6, 7}, {0, 2, 1}, {0, 3, 2}, {0, 1, 5}, {0, 5, 4},
                                        {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
    for (int i = 0; i < nb; ++i) {
      const Beam& b = s.beams.beams[i];
      const Vec3 half = 0.5 * s.beamWidth * b.normal;
      for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 3; ++c) {
          V[3 * (8 * i + k) + c] = b.corners[k][c] - half[c] - o[c];
          V[3 * (8 * i + 4 + k) + c] = b.corners[k][c] + half[c] - o[c];
        }
      for (int t = 0; t < 12; ++t) {
        for (int c = 0; c < 3; ++c) F[3 * (12 * i + t) + c] = 8 * i + kBox[t][c];
        part.element[12 * i + t] = i;
      }
    }
  }
  // Axes: from the beams' back layer to the panels' top.
  int withFaces = 0;
  for (NodeKind k : ax.kind) withFaces += k != NodeKind::Free;
  model.axes.resize(2 * withFaces, 3);
  for (int v = 0, row = 0; v < static_cast<int>(mesh.V.rows()); ++v) {
    if (ax.kind[v] == NodeKind::Free) continue;
    model.axes.row(row++) = ax.position.row(v) - h * ax.axis.row(v) - o;
    model.axes.row(row++) = top.V.row(v) - o;
  }
  return s;
}

std::string nodesCsv(const PolyMesh& mesh, const NodeAxes& ax) {
  std::string s =
      "node,kind,faces,x,y,z,axis_x,axis_y,axis_z,scale,panels,axis_face_angles_deg,normal_deviation_deg,residual\n";
  for (int v = 0; v < static_cast<int>(mesh.V.rows()); ++v) {
    const int* faces = ax.nodeFaces.data() + ax.nodeFaceOffsets[v];
    const int k = ax.nodeFaceOffsets[v + 1] - ax.nodeFaceOffsets[v];
    const Vec3 a = ax.axis.row(v).transpose();
    const double scale = a.norm();
    const Vec3 unit = scale > 0 ? Vec3(a / scale) : Vec3::Zero();
    s += std::to_string(v + 1) + "," + nodeKindName(ax.kind[v]) + "," + std::to_string(k);
    for (int c = 0; c < 3; ++c) s += "," + formatNumber(ax.position(v, c));
    for (int c = 0; c < 3; ++c) s += "," + formatNumber(unit[c]);
    s += "," + formatNumber(scale) + ",";
    Vec3 mean = Vec3::Zero();
    for (int i = 0; i < k; ++i) s += (i ? ";" : "") + panelLabel(faces[i]), mean += ax.planes[faces[i]].normal;
    s += ",";
    // Between the axis and a panel's plane: 90° less its angle to the panel's normal.
    for (int i = 0; i < k; ++i)
      s += (i ? ";" : "") + formatNumber(90 - angleDeg(unit, ax.planes[faces[i]].normal));
    s += "," + (k > 0 && scale > 0 ? formatNumber(angleDeg(unit, mean)) : std::string()) + "," + formatNumber(ax.residual[v]) + "\n";
  }
  return s;
}

std::string beamsCsv(const PolyMesh& mesh, const NodeAxes& axes, const BeamLayer& layer) {
  PolyMesh onPlanes = mesh;
  onPlanes.V = axes.position;
  const std::string base = beamsCsv(onPlanes);
  std::string s;
  s.reserve(base.size() * 3);
  std::size_t line = 0;
  for (std::size_t row = 0; line < base.size(); ++row) {
    const std::size_t end = base.find('\n', line);
    s.append(base, line, end - line);
    line = end + 1;
    if (row == 0) {
      s += ",height_a,height_b,plane_nx,plane_ny,plane_nz,plane_offset,planarity,twist_deg";
      for (int k = 1; k <= 4; ++k) s += ",q" + std::to_string(k) + "x,q" + std::to_string(k) + "y,q" + std::to_string(k) + "z";
    } else {
      const Beam& b = layer.beams.at(row - 1);
      for (double x : {b.heightA, b.heightB, b.normal.x(), b.normal.y(), b.normal.z(), b.planeOffset, b.planarity, b.twistDeg})
        s += "," + formatNumber(x);
      for (const Vec3& c : b.corners)
        for (int k = 0; k < 3; ++k) s += "," + formatNumber(c[k]);
    }
    s += "\n";
  }
  return s;
}

std::string toObj(const StructureModel& model) {
  std::string out = "# phex structure: panels P<n> (face n) and beams B<k> (edge k of the beam schedule)\n";
  char buf[96];
  int written = 0;  // OBJ vertices so far
  for (const SolidPart* part : {&model.panels, &model.beams}) {
    const std::string prefix = part == &model.panels ? "o P" : "o B";
    for (int t = 0; t < part->F.rows();) {
      // One object per element: the vertices its triangles use (a contiguous block), then its triangles.
      const int element = part->element[t];
      int end = t, lo = part->F(t, 0), hi = lo;
      for (; end < part->F.rows() && part->element[end] == element; ++end)
        for (int c = 0; c < 3; ++c) lo = std::min(lo, part->F(end, c)), hi = std::max(hi, part->F(end, c));
      out += prefix + std::to_string(element + 1) + "\n";
      for (int v = lo; v <= hi; ++v) {
        std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g\n", part->V(v, 0) + model.origin.x(),
                      part->V(v, 1) + model.origin.y(), part->V(v, 2) + model.origin.z());
        out += buf;
      }
      for (; t < end; ++t)
        out += "f " + std::to_string(part->F(t, 0) - lo + written + 1) + " " + std::to_string(part->F(t, 1) - lo + written + 1) +
               " " + std::to_string(part->F(t, 2) - lo + written + 1) + "\n";
      written += hi - lo + 1;
    }
  }
  return out;
}

}  // namespace phex
