// phex — mesh containers passed between stages (plain data, row-major so they copy flat to JS).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "phex/geometry.hpp"

namespace phex {

using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;     // #V by 3 positions
using Triangles = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;     // #F by 3 vertex ids, CCW seen from the normal side

struct TriMesh {
  Points V;
  Triangles F;
  // Mean edge length over all triangles (each shared edge counted from both sides).
  double meanEdgeLength() const;
  // Every triangle's three edge lengths, in order (each shared edge counted from both sides).
  std::vector<double> edgeLengths() const;
  // Median edge length over all triangles (each shared edge counted from both sides); 0 without triangles.
  double medianEdgeLength() const;
  // Sum of the triangles' areas.
  double area() const;
  // The edge of the equilateral triangle of the mean triangle area: the triangles' size; 0 without triangles. The
  // mean or median edge would count long thin triangles by their long edges (a vault's grid along its straight
  // direction, a needle's length).
  double triangleSize() const;
};

// The rows of a point matrix by their exact coordinates (-0 and +0 alike; of equal rows the first): open addressing
// over row numbers, the coordinates read from the matrix, which must outlive the index unchanged. The rounds
// against folds match a dual's 200k points at 100k faces each round: an unordered_map of them took 40 ms a round.
class PointIndex {
 public:
  explicit PointIndex(const Points& points);
  // The row with these coordinates, or -1.
  int find(double x, double y, double z) const;

 private:
  const Points& points_;
  std::vector<int> slots_;  // row numbers (exactPointSlots)
  Vec3 row(int r) const { return points_.row(r).transpose(); }
};

// A polygon mesh: face f has the vertex ids indices[offsets[f] .. offsets[f+1]), CCW seen from the normal side.
struct PolyMesh {
  Points V;
  std::vector<int> offsets{0};  // #F + 1 entries, offsets[0] = 0
  std::vector<int> indices;     // offsets.back() entries

  int faceCount() const { return static_cast<int>(offsets.size()) - 1; }
  int faceSize(int f) const { return offsets[f + 1] - offsets[f]; }
  const int* face(int f) const { return indices.data() + offsets[f]; }
  Vec3 vertex(int v) const { return V.row(v).transpose(); }
  void addFace(const std::vector<int>& ids);
  // Mean edge length over all faces (each shared edge counted from both sides).
  double meanEdgeLength() const;
};

// The faces at each vertex of a polygon mesh as one flat array (compressed rows): those of vertex v are
// faces[start[v] .. start[v + 1]), in increasing order; only the faces `keep` accepts.
struct FacesAtVertices {
  std::vector<int> start, faces;
};
template <class Keep>
FacesAtVertices facesAtVertices(const PolyMesh& mesh, Keep keep) {
  const int nv = static_cast<int>(mesh.V.rows()), nf = mesh.faceCount();
  FacesAtVertices a;
  a.start.assign(nv + 1, 0);
  for (int f = 0; f < nf; ++f)
    if (keep(f))
      for (int i = 0; i < mesh.faceSize(f); ++i) ++a.start[mesh.face(f)[i] + 1];
  for (int v = 0; v < nv; ++v) a.start[v + 1] += a.start[v];
  a.faces.resize(a.start[nv]);
  std::vector<int> fill(a.start.begin(), a.start.end() - 1);
  for (int f = 0; f < nf; ++f)
    if (keep(f))
      for (int i = 0; i < mesh.faceSize(f); ++i) a.faces[fill[mesh.face(f)[i]]++] = f;
  return a;
}

// Wavefront OBJ text of a polygon / triangle mesh (1-based indices, 17 significant digits).
std::string toObj(const PolyMesh& mesh);
std::string toObj(const TriMesh& mesh);
// ASCII PLY of a polygon mesh (vertex x y z as double, face vertex_indices as a uint list).
std::string toPly(const PolyMesh& mesh);
// Writes `text` to `path`; throws phex::Error(Io) naming the path when it cannot.
void writeTextFile(const std::string& path, const std::string& text);

}  // namespace phex
