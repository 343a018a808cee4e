// phex — strict readers of triangle meshes (OBJ, OFF, PLY, STL) for MeshSurface.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "phex/mesh.hpp"

namespace phex {

// Largest input phex reads: files above kMaxMeshFileBytes, or with more than kMaxMeshTriangles triangles
// (after polygons are triangulated) or kMaxMeshVertices vertices, are rejected with Error(InvalidInput).
constexpr std::size_t kMaxMeshFileBytes = std::size_t(512) << 20;  // 512 MiB
constexpr std::size_t kMaxMeshTriangles = 20000000;
constexpr std::size_t kMaxMeshVertices = 20000000;
// Coordinates are at most this far from 0 in any unit: phex multiplies lengths (areas, volumes, cross
// products of cross products), which must stay finite, as must the extent of the mesh.
constexpr double kMaxMeshCoordinate = 1e50;
// Nor may a mesh span less than this (its box's diagonal): its lengths' products (areas, cross products of cross
// products, the squared norms normals are made unit by) would underflow to zero or lose their digits.
constexpr double kMinMeshExtent = 1e-50;
// Polygons are ear-clipped in near-linear time (40,000 corners: a round cap in 20 ms, a star or a spiral in 50,
// a comb of 10,000 teeth in 200); one so convoluted that its ears take more than kPolygonTestsPerCorner point
// tests per corner (and a million), about a second per 100,000 corners, is rejected, naming it.
constexpr int kPolygonTestsPerCorner = 1024;

// What cleaning did to the file's mesh; every field is informational (nothing here is an error).
struct MeshReadReport {
  std::string format;              // "obj", "off", "ply", "stl"
  std::string encoding;            // "ascii", "binary_little_endian", "binary_big_endian"
  int fileVertices = 0;            // vertices in the file (STL: distinct positions after exact welding)
  int fileTriangles = 0;           // triangles in the file, after polygons were triangulated
  int degenerateTriangles = 0;     // dropped: a repeated vertex or zero area
  int unusedVertices = 0;          // dropped: referenced by no kept triangle
  int flippedTriangles = 0;        // reversed to orient each connected component consistently
  // #V of the result: the file vertex each mesh vertex comes from (0-based, file order; STL: order of
  // first appearance). Increasing, so mesh vertices keep the file's order.
  std::vector<int> fileVertex;
};

// Reads a triangle mesh. The format comes from the extension (.obj .off .ply .stl, any case), or is
// sniffed from the content when the extension is none of these. Coordinates keep the file's units.
// Throws Error(Io) naming `path` when it cannot be opened or read, and Error(InvalidInput) naming the
// file and the line (text) or byte offset / element index (binary) of the first defect.
TriMesh readMesh(const std::string& path, MeshReadReport* report = nullptr);

// The same from bytes in memory (the wasm binding passes an ArrayBuffer's bytes). `format` is "obj",
// "off", "ply" or "stl" (empty: sniffed); `name` only appears in messages.
TriMesh readMeshBytes(const std::uint8_t* data, std::size_t size, const std::string& format,
                      const std::string& name, MeshReadReport* report = nullptr);

// The checks and repairs every reader ends with; usable on a mesh from anywhere (e.g. typed arrays).
//   V  #V by 3 positions, F  #F by 3 vertex ids (0-based).
// Rejects (Error(InvalidInput), message starting with `name`): no triangles, an index out of range,
// a non-finite coordinate or one beyond ±kMaxMeshCoordinate, an edge with more than two triangles, a
// non-orientable component (neighbours that no choice of orientations makes consistent), a vertex whose
// triangles form more than one fan (two sheets touching at a point), or only degenerate triangles.
// Repairs (counted in `report`): drops triangles with a repeated vertex or zero area; flips triangles
// so each connected component is consistently oriented (a closed component with outward normals, an
// open one keeping the orientation of most of its triangles in the file); removes unused vertices,
// keeping the order of the others.
TriMesh cleanTriMesh(const TriMesh& raw, const std::string& name, MeshReadReport* report = nullptr);

// Appends the triangles of one polygon to `tri` (vertex ids, three per triangle, turning as the polygon does): ear
// clipping in the polygon's Newell plane, so a non-convex face stays inside its outline; a polygon with no ear
// left (self-intersecting or degenerate) is finished as a fan. `ids` index the points of `xyz` (x, y, z each).
// Near-linear in the corners; false (nothing appended) for a polygon so convoluted that its ears take more than
// kPolygonTestsPerCorner point tests per corner and a million in all (a hexagon takes a few dozen).
bool triangulatePolygon(const std::vector<int>& ids, const double* xyz, std::vector<int>& tri);

}  // namespace phex
