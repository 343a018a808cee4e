#include <catch.hpp>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>

#include "phex/error.hpp"
#include "phex/mesh_io.hpp"
#include "phex/mesh_surface.hpp"

using namespace phex;

namespace {

// A tetrahedron with outward triangles, and the same mesh written in each format by hand.
const double kTetraV[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
const int kTetraF[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

TriMesh readText(const std::string& text, const std::string& format, MeshReadReport* report = nullptr) {
  return readMeshBytes(reinterpret_cast<const std::uint8_t*>(text.data()), text.size(), format, "test." + format, report);
}
TriMesh readBinary(const std::vector<std::uint8_t>& bytes, const std::string& format, MeshReadReport* report = nullptr) {
  return readMeshBytes(bytes.data(), bytes.size(), format, "test." + format, report);
}

double signedVolume(const TriMesh& m) {
  double v = 0;
  for (int f = 0; f < m.F.rows(); ++f)
    v += m.V.row(m.F(f, 0)).dot(m.V.row(m.F(f, 1)).cross(m.V.row(m.F(f, 2))));
  return v / 6;
}

// Vertices may come in another order (STL numbers them by first appearance): match them by position.
void checkTetra(const TriMesh& m) {
  REQUIRE(m.V.rows() == 4);
  REQUIRE(m.F.rows() == 4);
  int fileId[4] = {-1, -1, -1, -1};
  for (int v = 0; v < 4; ++v)
    for (int t = 0; t < 4; ++t)
      if (m.V(v, 0) == kTetraV[t][0] && m.V(v, 1) == kTetraV[t][1] && m.V(v, 2) == kTetraV[t][2]) fileId[v] = t;
  for (int f = 0; f < 4; ++f)
    for (int k = 0; k < 3; ++k) CHECK(fileId[m.F(f, k)] == kTetraF[f][k]);
  CHECK(signedVolume(m) == Approx(1.0 / 6));
}

std::string tetraObj() {
  std::string s = "# tetra\no tetra\n";
  for (auto& v : kTetraV) s += "v " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + "\n";
  s += "vt 0 0\nvn 0 0 1\ns off\n";
  // Each index form once, and negative (relative) indices.
  s += "f 1 3 2\nf 1/1 2/1 4/1\nf 1//1 4//1 3//1\nf -3/1/1 -2/1/1 -1/1/1\n";
  return s;
}

std::string tetraOff() {
  std::string s = "OFF\n# a comment\n4 4 6\n";
  for (auto& v : kTetraV) s += std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + "\n";
  for (auto& f : kTetraF) s += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n";
  return s;
}

// Little helpers that write binary values in a chosen byte order.
struct Bytes {
  std::vector<std::uint8_t> data;
  bool bigEndian = false;
  template <class T>
  void put(T value) {
    std::uint8_t b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if (bigEndian) std::reverse(b, b + sizeof(T));
    data.insert(data.end(), b, b + sizeof(T));
  }
  void text(const std::string& s) { data.insert(data.end(), s.begin(), s.end()); }
};

// PLY with properties phex must skip by type: a float normal and a uchar colour per vertex, a uint flag
// per face, and an extra element with a list.
std::vector<std::uint8_t> tetraPly(const std::string& encoding) {
  Bytes b;
  b.bigEndian = encoding == "binary_big_endian";
  b.text("ply\nformat " + encoding + " 1.0\ncomment made by hand\nelement vertex 4\nproperty float nx\n"
         "property double x\nproperty double y\nproperty float z\nproperty uchar red\n"
         "element face 4\nproperty uint flags\nproperty list uchar int vertex_indices\n"
         "element extra 2\nproperty list int short things\nproperty double w\nend_header\n");
  for (auto& v : kTetraV) {
    if (encoding == "ascii") {
      b.text("0.5 " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + " 255\n");
    } else {
      b.put(0.5f), b.put(v[0]), b.put(v[1]), b.put(static_cast<float>(v[2])), b.put(std::uint8_t(255));
    }
  }
  for (auto& f : kTetraF) {
    if (encoding == "ascii") {
      b.text("7 3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n");
    } else {
      b.put(std::uint32_t(7)), b.put(std::uint8_t(3));
      for (int k = 0; k < 3; ++k) b.put(std::int32_t(f[k]));
    }
  }
  for (int e = 0; e < 2; ++e) {
    if (encoding == "ascii") {
      b.text("2 -1 5 3.5\n");
    } else {
      b.put(std::int32_t(2)), b.put(std::int16_t(-1)), b.put(std::int16_t(5)), b.put(3.5);
    }
  }
  return b.data;
}

std::vector<std::uint8_t> tetraStlBinary() {
  Bytes b;
  std::string header = "solid but binary: the size rule decides";
  header.resize(80, ' ');
  b.text(header);
  b.put(std::uint32_t(4));
  for (auto& f : kTetraF) {
    for (int k = 0; k < 3; ++k) b.put(0.0f);
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) b.put(static_cast<float>(kTetraV[f[c]][k]));
    b.put(std::uint16_t(0));
  }
  return b.data;
}

std::string tetraStlAscii() {
  std::string s = "solid tetra with a name\n";
  for (auto& f : kTetraF) {
    s += "  facet normal 0 0 0\n    outer loop\n";
    for (int c = 0; c < 3; ++c)
      s += "      vertex " + std::to_string(kTetraV[f[c]][0]) + " " + std::to_string(kTetraV[f[c]][1]) + " " +
           std::to_string(kTetraV[f[c]][2]) + "\n";
    s += "    endloop\n  endfacet\n";
  }
  return s + "endsolid tetra\n";
}

std::string tempPath(const std::string& file) { return "/tmp/phex_test_mesh_io_" + file; }

void writeBytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

TEST_CASE("mesh_io: OBJ round trip with every index form and negative indices") {
  MeshReadReport report;
  checkTetra(readText(tetraObj(), "obj", &report));
  CHECK(report.format == "obj");
  CHECK(report.flippedTriangles == 0);
}

TEST_CASE("mesh_io: OFF round trip") { checkTetra(readText(tetraOff(), "off")); }

TEST_CASE("mesh_io: PLY round trip in ascii, little- and big-endian binary, skipping other properties") {
  for (const char* encoding : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    INFO(encoding);
    MeshReadReport report;
    checkTetra(readBinary(tetraPly(encoding), "ply", &report));
    CHECK(report.encoding == encoding);
  }
}

TEST_CASE("mesh_io: STL binary (header starting with 'solid') and ASCII, corners welded exactly") {
  MeshReadReport report;
  checkTetra(readBinary(tetraStlBinary(), "stl", &report));
  CHECK(report.encoding == "binary_little_endian");
  CHECK(report.fileVertices == 4);
  checkTetra(readText(tetraStlAscii(), "stl", &report));
  CHECK(report.encoding == "ascii");
}

TEST_CASE("mesh_io: readMesh picks the format from the extension, or sniffs it") {
  writeBytes(tempPath("tetra.STL"), tetraStlBinary());
  checkTetra(readMesh(tempPath("tetra.STL")));
  const std::string ply = tempPath("tetra.mesh");
  writeBytes(ply, tetraPly("binary_big_endian"));
  MeshReadReport report;
  checkTetra(readMesh(ply, &report));
  CHECK(report.format == "ply");
  const std::string obj = tempPath("tetra.txt");
  const std::string text = tetraObj();
  writeBytes(obj, std::vector<std::uint8_t>(text.begin(), text.end()));
  checkTetra(readMesh(obj, &report));
  CHECK(report.format == "obj");
}

TEST_CASE("mesh_io: a missing file is an Io error naming the path") {
  try {
    readMesh("/nonexistent/dir/shape.obj");
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.code() == ErrorCode::Io);
    CHECK_THAT(e.what(), Catch::Contains("/nonexistent/dir/shape.obj"));
  }
}

TEST_CASE("mesh_io: non-convex polygons are ear-triangulated inside their outline") {
  // An L-shaped hexagon of area 3: a fan from its first corner would leave the outline. Vertex 7 is unused.
  const std::string obj = "v 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 0\nv 2 0 0\nv 2 1 0\nv 7 7 7\nf 2 3 4 5 6 1\n";
  const TriMesh m = readText(obj, "obj");
  REQUIRE(m.F.rows() == 4);
  CHECK(m.V.rows() == 6);
  double area = 0;
  for (int f = 0; f < m.F.rows(); ++f) {
    const double a = (m.V.row(m.F(f, 1)) - m.V.row(m.F(f, 0))).cross(m.V.row(m.F(f, 2)) - m.V.row(m.F(f, 0)))(2) / 2;
    CHECK(a > 0);
    area += a;
  }
  CHECK(area == Approx(3.0));
}

// Every defect: a phex::Error(InvalidInput) whose message names the file and where, or what, it is.
void checkInvalid(const std::function<void()>& read, const std::vector<std::string>& fragments) {
  try {
    read();
    FAIL("no error");
  } catch (const Error& e) {
    INFO(e.what());
    CHECK(e.code() == ErrorCode::InvalidInput);
    for (const std::string& f : fragments) CHECK_THAT(e.what(), Catch::Contains(f));
  }
}

TEST_CASE("mesh_io: truncated files") {
  std::vector<std::uint8_t> stl = tetraStlBinary();
  stl.resize(stl.size() - 10);
  checkInvalid([&] { readBinary(stl, "stl"); }, {"'test.stl'", "declares 4 triangles", "truncated"});
  std::vector<std::uint8_t> ply = tetraPly("binary_little_endian");
  ply.resize(ply.size() - 30);
  checkInvalid([&] { readBinary(ply, "ply"); }, {"'test.ply' byte", "2 'extra' elements", "only 2 bytes are left"});
  std::string off = tetraOff();
  off.resize(off.find("3 0 3 2"));
  checkInvalid([&] { readText(off, "off"); }, {"'test.off' line 10", "after 2 of the 4 faces"});
  checkInvalid([&] { readText("v 0 0\n", "obj"); }, {"line 1", "fewer than 3 coordinates"});
}

TEST_CASE("mesh_io: wrong or missing counts") {
  checkInvalid([&] { readText(tetraOff() + "3 0 1 2\n", "off"); }, {"line 12", "unexpected data after the 4 faces"});
  std::string off = tetraOff();
  off.replace(off.find("4 4 6"), 5, "4 4");
  checkInvalid([&] { readText(off, "off"); }, {"line 4", "edge count"});
  std::vector<std::uint8_t> ply = tetraPly("binary_little_endian");
  ply.push_back(0);
  checkInvalid([&] { readBinary(ply, "ply"); }, {"unexpected data after the last element"});
  std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 1000000\nproperty float x\n"
                       "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  checkInvalid([&] { readText(header + "abc", "ply"); }, {"declares 1000000 'vertex' elements", "truncated file or wrong count"});
  checkInvalid([&] { readText("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "off"); }, {"line 6", "fewer than the 4 vertices"});
}

TEST_CASE("mesh_io: vertex index out of range") {
  checkInvalid([&] { readText("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n", "obj"); }, {"line 5", "vertex index 9", "3 vertices"});
  checkInvalid([&] { readText("v 0 0 0\nv 1 0 0\nf 1 2 -5\n", "obj"); }, {"line 3", "-5"});
  checkInvalid([&] { readText("v 0 0 0\nv 1 0 0\nf 0 1 2\n", "obj"); }, {"line 3", "index 0"});
  checkInvalid([&] { readText("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "off"); }, {"line 6", "vertex index 3 is out of range"});
  std::vector<std::uint8_t> ply = tetraPly("binary_big_endian");
  // The last index of face 3 is the 4 bytes before the extra element (2 x (4 + 2 + 2 + 8) bytes).
  ply[ply.size() - 32 - 1] = 42;
  checkInvalid([&] { readBinary(ply, "ply"); }, {"face 3", "vertex index 42 is out of range"});
}

TEST_CASE("mesh_io: NaN and infinite coordinates") {
  checkInvalid([&] { readText("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "obj"); }, {"line 2", "nan", "finite"});
  checkInvalid([&] { readText("OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n", "off"); }, {"line 4", "inf"});
  std::vector<std::uint8_t> stl = tetraStlBinary();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&stl[84 + 50 * 2 + 12 + 4], &nan, 4);
  checkInvalid([&] { readBinary(stl, "stl"); }, {"byte 200", "triangle 2", "NaN"});
  Bytes ply;
  ply.text("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_header\n");
  for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, std::numeric_limits<float>::infinity(), 0.f}) ply.put(c);
  checkInvalid([&] { readBinary(ply.data, "ply"); }, {"vertex 2", "infinite"});
}

TEST_CASE("mesh_io: text in a binary file, and binary bytes in a text file") {
  std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                    "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  checkInvalid([&] { readText(ply, "ply"); }, {"'test.ply' byte", "is text", "ascii"});
  std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  obj[10] = '\0';
  checkInvalid([&] { readText(obj, "obj"); }, {"line 2", "binary byte 0x00 at byte offset 10"});
  checkInvalid([&] { readText("solid x\nfacet normal 0 0 0\nouter lop\n", "stl"); }, {"line 3", "expected 'loop', found 'lop'"});
  checkInvalid([&] { readText(std::string(100, 'x'), "stl"); }, {"declares", "bytes"});
}

TEST_CASE("mesh_io: a file without faces") {
  checkInvalid([&] { readText("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "obj"); }, {"'test.obj'", "has no faces"});
  checkInvalid([&] { readText("OFF\n0 0 0\n", "off"); }, {"has no faces"});
  checkInvalid([&] { readText("solid empty\nendsolid empty\n", "stl"); }, {"has no faces"});
  checkInvalid([&] { readText("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                              "end_header\n0 0 0\n", "ply"); },
               {"no face element"});
}

TEST_CASE("mesh_io: non-manifold edges and vertices are rejected") {
  // Three triangles on the edge 1-2.
  checkInvalid([&] { readText("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\nv 1 1 -1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n", "obj"); },
               {"non-manifold edge between vertices 0", "and 1", "3 triangles"});
  // Two triangles touching at one vertex (a bowtie).
  checkInvalid([&] { readText("v 0 0 0\nv 1 0 0\nv 0 1 0\nv -1 0 0\nv 0 -1 0\nf 1 2 3\nf 1 4 5\n", "obj"); },
               {"non-manifold vertex 0", "separate fans"});
}

TEST_CASE("mesh_io: inconsistent orientation is repaired; a non-orientable surface is rejected") {
  // The second triangle of a square is flipped in the file; on a tie the first triangle's orientation wins.
  MeshReadReport report;
  TriMesh m = readText("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 4 3\n", "obj", &report);
  CHECK(report.flippedTriangles == 1);
  REQUIRE(m.F.rows() == 2);
  for (int f = 0; f < 2; ++f)
    CHECK((m.V.row(m.F(f, 1)) - m.V.row(m.F(f, 0))).cross(m.V.row(m.F(f, 2)) - m.V.row(m.F(f, 0)))(2) > 0);
  // A closed tetrahedron written inside out comes back with outward normals.
  std::string inside = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n";
  m = readText(inside, "obj", &report);
  CHECK(report.flippedTriangles == 4);
  CHECK(signedVolume(m) == Approx(1.0 / 6));
  // A Moebius band of 8 quads: no consistent orientation exists.
  std::string moebius;
  const int n = 8;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * 3.141592653589793 * i / n, t = a / 2;
    for (int s : {-1, 1}) {
      const double r = 2 + 0.5 * s * std::cos(t);
      moebius += "v " + std::to_string(r * std::cos(a)) + " " + std::to_string(r * std::sin(a)) + " " +
                 std::to_string(0.5 * s * std::sin(t)) + "\n";
    }
  }
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i + 1, b = 2 * i + 2;
    const int c = i + 1 < n ? 2 * i + 3 : 2, d = i + 1 < n ? 2 * i + 4 : 1;  // the last quad joins with a half twist
    moebius += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(d) + " " + std::to_string(c) + "\n";
  }
  checkInvalid([&] { readText(moebius, "obj"); }, {"cannot be oriented consistently", "not orientable"});
}

TEST_CASE("mesh_io: degenerate triangles are dropped and counted, unused vertices removed in order") {
  MeshReadReport report;
  const TriMesh m = readText("v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 5 5 5\nf 2 3 4\nf 2 3 5\nf 2 2 4\n", "obj", &report);
  CHECK(m.F.rows() == 1);
  CHECK(report.degenerateTriangles == 2);  // zero area (collinear) and a repeated vertex
  CHECK(report.unusedVertices == 3);
  CHECK(report.fileVertex == std::vector<int>{1, 2, 3});
  CHECK(m.V(0, 0) == 0.0);
  CHECK(m.V(1, 0) == 1.0);
  checkInvalid([&] { readText("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n", "obj"); },
               {"all 2 triangles are degenerate"});
}

TEST_CASE("mesh_io: limits and unknown formats") {
  checkInvalid([&] { readText("hello", ""); }, {"cannot tell the mesh format"});
  CHECK_THROWS_AS(readText("v 0 0 0", "dxf"), Error);
  checkInvalid([&] { readText("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                              "element face 30000000\nproperty list uchar int vertex_indices\nend_header\n", "ply"); },
               {"line 7", "more than 20000000 faces"});
}

// Files the fuzzers found (tests/fuzz/regressions): every number is range-checked before a cast, every count
// bounded by the bytes left; each is refused at once with a message naming the problem.
TEST_CASE("mesh_io: integers out of their range are refused before any cast") {
  const std::string header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                             "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  checkInvalid([&] { readText(header + "3 9223372036854775807 0 0\n", "ply"); },
               {"line 13", "a list item 9223372036854775807 of face 0 is out of range for its type int"});
  checkInvalid([&] { readText(header + "3 99999999999999999999 0 0\n", "ply"); }, {"line 13", "99999999999999999999 is out of range"});
  checkInvalid([&] { readText(header + "3 -1 0 1\n", "ply"); }, {"vertex index -1 is out of range"});
  checkInvalid([&] { readText(header + "9223372036854775807 0 1 2\n", "ply"); },
               {"line 13", "the list length 9223372036854775807 of face 0 is out of range for its type uchar"});
  std::string wide = header;
  wide.replace(wide.find("uchar"), 5, "uint");
  checkInvalid([&] { readText(wide + "4294967295 0 1 2\n", "ply"); }, {"declares 4294967295 items", "bytes are left"});
  checkInvalid([&] { readText("OFF\n99999999999999999999 1 0\n", "off"); }, {"line 2", "vertex count 99999999999999999999 is out of range"});
  // A relative OBJ index of LONG_MIN reaches before the first vertex, with more vertices after it or not.
  const std::string five = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 0\n";
  for (const std::string& after : {std::string(), five})
    checkInvalid([&] { readText(five + "f 1 2 3 -9223372036854775808\n" + after, "obj"); },
                 {"line 6", "relative vertex index -9223372036854775808 reaches before the first vertex (5 defined so far)"});
  checkInvalid([&] { readText(five + "f 1 2 -99999999999999999999\n", "obj"); }, {"line 6", "is out of range"});
}

TEST_CASE("mesh_io: counts are bounded by the bytes left, also for elements of nothing") {
  for (const char* format : {"ascii", "binary_little_endian"}) {
    INFO(format);
    const std::string ply = std::string("ply\nformat ") + format + " 1.0\nelement e 9223372036854775807\nend_header\n";
    checkInvalid([&] { readText(ply, "ply"); }, {"declares 9223372036854775807 'e' elements but no properties"});
  }
  // An element of no properties and no count is harmless.
  const std::string tri = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                          "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  CHECK(readText("ply\nformat ascii 1.0\nelement nothing 0\n" + tri, "ply").F.rows() == 1);
  checkInvalid([&] { readText("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n" + tri, "ply"); },
               {"a second 'vertex' element"});
  // Counts are checked against the bytes left after the elements before them; list lengths too.
  auto binaryTriangle = [](const std::string& faces, const std::string& countType) {
    Bytes b;
    b.text("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           "element face " + faces + "\nproperty list " + countType + " int vertex_indices\nend_header\n");
    for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) b.put(c);
    return b;
  };
  Bytes twoFaces = binaryTriangle("2", "uchar");
  twoFaces.put(std::uint8_t(3));
  checkInvalid([&] { readBinary(twoFaces.data, "ply"); }, {"declares 2 'face' elements of at least 1 bytes, but only 1 bytes are left"});
  Bytes longList = binaryTriangle("1", "uint");
  longList.put(std::uint32_t(0xffffffffu));
  longList.put(std::int32_t(0));
  checkInvalid([&] { readBinary(longList.data, "ply"); }, {"face 0", "declares 4294967295 items, but only 4 bytes are left"});
}

TEST_CASE("mesh_io: coordinates beyond ±1e50 are refused, naming the vertex") {
  // Two triangles, one near x = +1e308 and one near x = -1e308: their extent overflows to infinity.
  const std::string far = "v 1e308 0 0\nv 1e308 1 0\nv 1e308 0 1\nv -1e308 0 0\nv -1e308 1 0\nv -1e308 0 1\nf 1 2 3\nf 4 5 6\n";
  checkInvalid([&] { readText(far, "obj"); }, {"'test.obj'", "vertex 0 (1e+308, 0, 0) has x = 1e+308, beyond ±1e50"});
  checkInvalid([&] { readText("OFF\n3 1 0\n0 0 0\n1 -2e50 0\n0 1 0\n3 0 1 2\n", "off"); }, {"vertex 1", "y = -2e+50"});
  // Up to the limit a mesh is read as it is.
  CHECK(readText("v 1e50 0 0\nv 1e50 1 0\nv 1e50 0 1\nv -1e50 0 0\nv -1e50 1 0\nv -1e50 0 1\nf 1 2 3\nf 4 5 6\n", "obj").V.rows() == 6);
}

TEST_CASE("mesh surface: a mesh spanning less than 1e-50 is refused, naming its extent") {
  // Fuzzing's find: a triangle 1e-81 across had normals of length 0.95 (their squared norms underflowed).
  TriMesh tiny;
  tiny.V.resize(3, 3);
  tiny.V << 0, 0, 0, 1e-81, 0, 0, 0, 1e-81, 0;
  tiny.F.resize(1, 3);
  tiny.F << 0, 1, 2;
  checkInvalid([&] { MeshSurface(tiny, "tiny.obj"); }, {"'tiny.obj'", "spans only 1.41e-81 (its box's diagonal), under 1e-50"});
  // At the limit the surface is built, its normals unit.
  TriMesh small = tiny;
  small.V *= 1e31;
  const MeshSurface s(small, "small.obj");
  CHECK(std::abs(s.vertexGeometry(0).normal.norm() - 1) < 1e-12);
}

TEST_CASE("mesh_io: a polygon of 40,000 corners is ear-clipped in near-linear time, without a fan") {
  // A flat cap (a circle) as CAD tools write it, and a star whose every other corner is reflex.
  const int n = 40000;
  for (const double dent : {0.0, 0.3}) {
    INFO("dent " << dent);
    std::string obj;
    for (int i = 0; i < n; ++i) {
      const double a = 2 * 3.141592653589793 * i / n, r = 1 - dent * (i % 2);
      obj += "v " + std::to_string(r * std::cos(a)) + " " + std::to_string(r * std::sin(a)) + " 0\n";
    }
    obj += "f";
    for (int i = 1; i <= n; ++i) obj += " " + std::to_string(i);
    obj += "\n";
    const TriMesh m = readText(obj, "obj");
    REQUIRE(m.F.rows() == n - 2);
    std::vector<int> valence(n, 0);
    double area = 0, outline = 0;
    for (int f = 0; f < m.F.rows(); ++f) {
      const double a = (m.V.row(m.F(f, 1)) - m.V.row(m.F(f, 0))).cross(m.V.row(m.F(f, 2)) - m.V.row(m.F(f, 0)))(2) / 2;
      CHECK(a > 0);
      area += a;
      for (int k = 0; k < 3; ++k) ++valence[m.F(f, k)];
    }
    for (int i = 0; i < n; ++i) outline += (m.V(i, 0) * m.V((i + 1) % n, 1) - m.V((i + 1) % n, 0) * m.V(i, 1)) / 2;
    CHECK(area == Approx(outline).epsilon(1e-9));
    // A fan from one corner (what clipping the first ear over and over gives) would meet n - 2 triangles there.
    CHECK(*std::max_element(valence.begin(), valence.end()) < 64);
  }
}
