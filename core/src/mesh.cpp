#include "phex/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <vector>

#include "phex/error.hpp"

namespace phex {

void PolyMesh::addFace(const std::vector<int>& ids) {
  indices.insert(indices.end(), ids.begin(), ids.end());
  offsets.push_back(static_cast<int>(indices.size()));
}

double TriMesh::meanEdgeLength() const {
  double sum = 0.0;
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) sum += (V.row(F(f, k)) - V.row(F(f, (k + 1) % 3))).norm();
  return F.rows() ? sum / (3.0 * F.rows()) : 0.0;
}

std::vector<double> TriMesh::edgeLengths() const {
  std::vector<double> lengths;
  lengths.reserve(3 * static_cast<std::size_t>(F.rows()));
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) lengths.push_back((V.row(F(f, k)) - V.row(F(f, (k + 1) % 3))).norm());
  return lengths;
}

double TriMesh::medianEdgeLength() const {
  std::vector<double> lengths = edgeLengths();
  if (lengths.empty()) return 0.0;
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  return lengths[lengths.size() / 2];
}

double TriMesh::area() const {
  double a = 0;
  for (int f = 0; f < F.rows(); ++f) a += 0.5 * (V.row(F(f, 1)) - V.row(F(f, 0))).cross(V.row(F(f, 2)) - V.row(F(f, 0))).norm();
  return a;
}

double TriMesh::triangleSize() const {
  return F.rows() > 0 ? std::sqrt(4 * area() / (std::sqrt(3.0) * double(F.rows()))) : 0.0;
}

double PolyMesh::meanEdgeLength() const {
  double sum = 0.0;
  long count = 0;
  for (int f = 0; f < faceCount(); ++f) {
    const int n = faceSize(f);
    const int* ids = face(f);
    for (int i = 0; i < n; ++i) sum += (V.row(ids[i]) - V.row(ids[(i + 1) % n])).norm(), ++count;
  }
  return count ? sum / count : 0.0;
}

namespace {
void appendVertices(std::string& out, const Points& V) {
  char buf[96];
  for (int i = 0; i < V.rows(); ++i) {
    std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g\n", V(i, 0), V(i, 1), V(i, 2));
    out += buf;
  }
}
}  // namespace

std::string toObj(const PolyMesh& mesh) {
  std::string out = "# phex P-Hex mesh\n";
  appendVertices(out, mesh.V);
  for (int f = 0; f < mesh.faceCount(); ++f) {
    out += 'f';
    for (int i = 0; i < mesh.faceSize(f); ++i) out += ' ' + std::to_string(mesh.face(f)[i] + 1);
    out += '\n';
  }
  return out;
}

std::string toObj(const TriMesh& mesh) {
  std::string out = "# phex triangulation\n";
  appendVertices(out, mesh.V);
  for (int f = 0; f < mesh.F.rows(); ++f)
    out += "f " + std::to_string(mesh.F(f, 0) + 1) + ' ' + std::to_string(mesh.F(f, 1) + 1) + ' ' +
           std::to_string(mesh.F(f, 2) + 1) + '\n';
  return out;
}

std::string toPly(const PolyMesh& mesh) {
  std::string out = "ply\nformat ascii 1.0\ncomment phex P-Hex mesh\nelement vertex " + std::to_string(mesh.V.rows()) +
                    "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
                    std::to_string(mesh.faceCount()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  char buf[96];
  for (int i = 0; i < mesh.V.rows(); ++i) {
    std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g\n", mesh.V(i, 0), mesh.V(i, 1), mesh.V(i, 2));
    out += buf;
  }
  for (int f = 0; f < mesh.faceCount(); ++f) {
    out += std::to_string(mesh.faceSize(f));
    for (int i = 0; i < mesh.faceSize(f); ++i) out += ' ' + std::to_string(mesh.face(f)[i]);
    out += '\n';
  }
  return out;
}

void writeTextFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw Error(ErrorCode::Io, "cannot open '" + path + "' for writing (does its directory exist?)");
  out << text;
  out.close();
  if (!out) throw Error(ErrorCode::Io, "failed writing '" + path + "'");
}

PointIndex::PointIndex(const Points& points) : points_(points), slots_(exactPointSlots(points.rows())) {
  auto rowOf = [this](int r) { return row(r); };
  for (int r = 0; r < points.rows(); ++r) {
    int& slot = slots_[exactPointSlot(slots_, points(r, 0), points(r, 1), points(r, 2), rowOf)];
    if (slot < 0) slot = r;  // of equal rows, the first
  }
}

int PointIndex::find(double x, double y, double z) const {
  return slots_[exactPointSlot(slots_, x, y, z, [this](int r) { return row(r); })];
}

}  // namespace phex
