#include "phex/mesh_io.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numeric>
#include <string_view>
#include <system_error>

#include <fast_float/fast_float.h>

#include "phex/error.hpp"

namespace phex {
namespace {

std::string fileLabel(const std::string& name) { return "'" + name + "'"; }

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw Error(ErrorCode::InvalidInput, fileLabel(name) + ": " + what);
}
// `where` is a position: "line 12", "byte 84 (triangle 0)".
[[noreturn]] void failAt(const std::string& name, const std::string& where, const std::string& what) {
  throw Error(ErrorCode::InvalidInput, fileLabel(name) + " " + where + ": " + what);
}

std::string formatPoint(const double* p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.9g, %.9g, %.9g)", p[0], p[1], p[2]);
  return buf;
}

// A mesh as the readers produce it, before cleanTriMesh.
struct RawMesh {
  std::vector<double> xyz;  // 3 per vertex
  std::vector<int> tri;     // 3 per triangle
  int vertexCount() const { return static_cast<int>(xyz.size() / 3); }
};

TriMesh toTriMesh(const RawMesh& raw) {
  TriMesh mesh;
  mesh.V = Eigen::Map<const Points>(raw.xyz.data(), raw.vertexCount(), 3);
  mesh.F = Eigen::Map<const Triangles>(raw.tri.data(), static_cast<Eigen::Index>(raw.tri.size() / 3), 3);
  return mesh;
}

void checkTriangleLimit(const std::string& name, std::uint64_t triangles) {  // 64 bits: counts from files, in wasm too
  if (triangles > kMaxMeshTriangles)
    fail(name, "more than " + std::to_string(kMaxMeshTriangles) + " triangles (phex's limit)");
}

void checkVertexLimit(const std::string& name, std::uint64_t vertices) {
  if (vertices > kMaxMeshVertices)
    fail(name, "more than " + std::to_string(kMaxMeshVertices) + " vertices (phex's limit)");
}

// ---------------------------------------------------------------------------------------------------
// The tokenizer shared by the text formats: whitespace-separated tokens with line numbers; a byte that
// cannot appear in text (NUL, other control characters) is an error, since it means binary data.
class TextReader {
 public:
  TextReader(const std::uint8_t* data, std::size_t size, std::string name, std::size_t start = 0, int line = 1,
             bool hashComments = false)
      : data_(data), size_(size), pos_(start), line_(line), hashComments_(hashComments), name_(std::move(name)) {}

  // The next token, crossing line ends; false at the end of the data.
  bool token(std::string_view& out) {
    skipSpace(true);
    return take(out);
  }
  // The next token on the current line; false at the line's end.
  bool tokenOnLine(std::string_view& out) {
    skipSpace(false);
    return take(out);
  }
  // A token that must exist; `what` says what was expected.
  std::string_view require(const char* what) {
    std::string_view t;
    if (!token(t)) fail(std::string("file ends where ") + what + " was expected");
    return t;
  }
  // Skips the rest of the current line, including its end.
  void skipLine() {
    while (pos_ < size_ && data_[pos_] != '\n' && data_[pos_] != '\r') checkTextByte(pos_++);
    if (pos_ < size_ && data_[pos_] == '\r') ++pos_;
    if (pos_ < size_ && data_[pos_] == '\n') ++pos_;
    ++line_;
  }
  bool atEnd() {
    skipSpace(true);
    return pos_ >= size_;
  }
  int line() const { return line_; }

  [[noreturn]] void fail(const std::string& what) const {
    throw Error(ErrorCode::InvalidInput, fileLabel(name_) + " line " + std::to_string(line_) + ": " + what);
  }

  // Decimal numbers as strtod reads them (correctly rounded; a leading '+' allowed, inf and nan read and
  // then refused as coordinates), by fast_float: musl's strtod, which wasm runs, goes through software long
  // double and is several times slower. Hexadecimal floats are not read.
  double number(std::string_view t, const char* what, bool requireFinite = true) {
    if (t.size() >= 64) fail(std::string(what) + " '" + std::string(t.substr(0, 20)) + "...' is too long for a number");
    const char* first = t.data();
    const char* last = t.data() + t.size();
    if (first != last && *first == '+' && last - first > 1 && first[1] != '-' && first[1] != '+') ++first;
    double x = 0;
    const fast_float::from_chars_result r = fast_float::from_chars(first, last, x);
    if (t.empty() || r.ec != std::errc() || r.ptr != last) fail(std::string(what) + " '" + std::string(t) + "' is not a number");
    if (requireFinite && !std::isfinite(x)) fail(std::string(what) + " is " + std::string(t) + " (coordinates must be finite)");
    return x;
  }
  // 64 bits in wasm too (its long has 32): the same numbers are in range, with the same messages, everywhere.
  long long integer(std::string_view t, const char* what) {
    char buf[32];
    if (t.size() >= sizeof buf) fail(std::string(what) + " '" + std::string(t.substr(0, 20)) + "...' is too long for an integer");
    std::memcpy(buf, t.data(), t.size());
    buf[t.size()] = '\0';
    char* end = nullptr;
    errno = 0;
    const long long x = std::strtoll(buf, &end, 10);
    if (t.empty() || end != buf + t.size()) fail(std::string(what) + " '" + std::string(t) + "' is not an integer");
    if (errno == ERANGE) fail(std::string(what) + " " + std::string(t) + " is out of range");
    return x;
  }
  // Where the next token would start: the bytes before it are read.
  std::size_t position() const { return pos_; }

 private:
  static bool isSpace(std::uint8_t c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }
  void checkTextByte(std::size_t at) const {
    const std::uint8_t c = data_[at];
    if ((c < 0x20 && !isSpace(c) && c != '\n' && c != '\r') || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", c);
      fail(std::string("binary byte ") + hex + " at byte offset " + std::to_string(at) +
           " in a text file (is this a binary file with the wrong extension?)");
    }
  }
  void skipSpace(bool crossLines) {
    while (pos_ < size_) {
      const std::uint8_t c = data_[pos_];
      if (isSpace(c)) {
        ++pos_;
      } else if (c == '\n' || c == '\r') {
        if (!crossLines) return;
        skipLine();
      } else if (c == '#' && hashComments_) {
        while (pos_ < size_ && data_[pos_] != '\n' && data_[pos_] != '\r') checkTextByte(pos_++);
      } else {
        checkTextByte(pos_);
        return;
      }
    }
  }
  bool take(std::string_view& out) {
    const std::size_t begin = pos_;
    while (pos_ < size_ && data_[pos_] > 0x20 && data_[pos_] != 0x7f && !(hashComments_ && data_[pos_] == '#')) ++pos_;
    if (pos_ < size_) checkTextByte(pos_);
    out = std::string_view(reinterpret_cast<const char*>(data_) + begin, pos_ - begin);
    return !out.empty();
  }

  const std::uint8_t* data_;
  std::size_t size_, pos_;
  int line_;
  bool hashComments_;
  std::string name_;
};

// ---------------------------------------------------------------------------------------------------
// Polygons become triangles by ear clipping in the polygon's Newell plane, so non-convex faces stay inside
// their outline; a polygon with no ear left (self-intersecting or degenerate) is finished as a fan. Near-linear
// (CAD tools write caps of tens of thousands of corners): the corners form a ring and the ears a list in ring
// order; clipping an ear changes only its two neighbours, which are looked at again (in a simple polygon only
// reflex corners can lie in an ear, so no other corner's ear comes or goes). Reflex corners are found through
// a k-d tree. The next ear clipped is the one after the next neighbour, which keeps a convex polygon's
// triangles from fanning out of one corner.
class PolygonTriangulator {
 public:
  // Appends the triangles of polygon `ids` (vertex ids into xyz, 3 per vertex) to `tri`; false (and nothing
  // appended) where its ears took more than kPolygonTestsPerCorner point tests per corner.
  bool add(const std::vector<int>& ids, const double* xyz, std::vector<int>& tri) {
    const int n = static_cast<int>(ids.size());
    if (n == 3) {
      tri.insert(tri.end(), ids.begin(), ids.end());
      return true;
    }
    auto P = [&](int i) { return Vec3(xyz[3 * ids[i]], xyz[3 * ids[i] + 1], xyz[3 * ids[i] + 2]); };
    Vec3 normal = Vec3::Zero();
    for (int i = 0; i < n; ++i) normal += P(i).cross(P((i + 1) % n));
    prev_.resize(n);
    next_.resize(n);
    for (int i = 0; i < n; ++i) prev_[i] = (i + n - 1) % n, next_[i] = (i + 1) % n;
    const std::size_t before = tri.size();
    int first = 0, remaining = n;
    // Coordinates so large that the normal overflows are refused later (cleanTriMesh).
    if (normal.norm() > 0 && std::isfinite(normal.norm())) {
      const Vec3 u = normal.unitOrthogonal(), v = normal.normalized().cross(u);
      q_.resize(n);
      for (int i = 0; i < n; ++i) q_[i] = Vec2(P(i).dot(u), P(i).dot(v));  // counter-clockwise
      if (!clipEars(ids, tri, first, remaining)) {
        tri.resize(before);
        return false;
      }
    }
    // What is left, as a fan from its lowest corner (three corners: that triangle).
    int low = first;
    for (int i = next_[first]; i != first; i = next_[i]) low = std::min(low, i);
    for (int i = next_[low]; next_[i] != low; i = next_[i]) tri.insert(tri.end(), {ids[low], ids[i], ids[next_[i]]});
    return true;
  }

 private:
  static double cross2(const Vec2& a, const Vec2& b, const Vec2& c) {
    return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  }
  // Convex: turning left by more than cleanTriMesh's degenerate triangles do (relative to the longest side),
  // so that no ear is dropped there as degenerate and leaves a hole (rounded coordinates make such corners).
  bool isReflex(int b) const {
    const Vec2 &a = q_[prev_[b]], &p = q_[b], &c = q_[next_[b]];
    const double longest = std::max({(p - a).squaredNorm(), (c - p).squaredNorm(), (a - c).squaredNorm()});
    return !(cross2(a, p, c) > 1e-10 * longest);
  }

  // The reflex corners as a k-d tree: an array ordered by median splits, x and y in turn (ties by index, so
  // that the tree is the same with every standard library). Corners that stopped being reflex stay in it,
  // skipped; corners that became reflex (self-intersecting polygons) wait in extra_ until it is rebuilt.
  static constexpr int kLeaf = 8;
  void buildTree(int first) {
    tree_.clear();
    extra_.clear();
    int i = first;
    do {
      if (reflex_[i]) tree_.push_back(i);
      i = next_[i];
    } while (i != first);
    active_ = static_cast<int>(tree_.size());
    treeLo_ = treeHi_ = q_[first];
    for (int r : tree_) treeLo_ = treeLo_.cwiseMin(q_[r]), treeHi_ = treeHi_.cwiseMax(q_[r]);
    split(0, active_, 0);
  }
  void split(int begin, int end, int axis) {
    if (end - begin <= kLeaf) return;
    const int mid = (begin + end) / 2;
    std::nth_element(tree_.begin() + begin, tree_.begin() + mid, tree_.begin() + end, [&](int a, int b) {
      return q_[a](axis) < q_[b](axis) || (q_[a](axis) == q_[b](axis) && a < b);
    });
    split(begin, mid, 1 - axis);
    split(mid + 1, end, 1 - axis);
  }
  // Corner b is an ear: convex, and no reflex corner but its neighbours lies in its triangle (edges included).
  bool isEar(int b) {
    ++tests_;
    if (reflex_[b]) return false;
    const int a = prev_[b], c = next_[b];
    const Vec2 lo = q_[a].cwiseMin(q_[b]).cwiseMin(q_[c]), hi = q_[a].cwiseMax(q_[b]).cwiseMax(q_[c]);
    auto inside = [&](int r) {
      ++tests_;
      return reflex_[r] && r != a && r != c && cross2(q_[a], q_[b], q_[r]) >= 0 && cross2(q_[b], q_[c], q_[r]) >= 0 &&
             cross2(q_[c], q_[a], q_[r]) >= 0;
    };
    for (int r : extra_)
      if (inside(r)) return false;
    // Whether the triangle misses a node's rectangle: all of it outside one of the (counter-clockwise) edges.
    auto misses = [&](const Vec2& rlo, const Vec2& rhi) {
      for (const auto& [p, e] : {std::pair(q_[a], Vec2(q_[b] - q_[a])), std::pair(q_[b], Vec2(q_[c] - q_[b])),
                                 std::pair(q_[c], Vec2(q_[a] - q_[c]))}) {
        const Vec2 farthest(e.y() < 0 ? rhi.x() : rlo.x(), e.x() > 0 ? rhi.y() : rlo.y());  // most to the left
        if (e.x() * (farthest.y() - p.y()) - e.y() * (farthest.x() - p.x()) < 0) return true;
      }
      return false;
    };
    struct Range {
      int begin, end, axis;
      Vec2 lo, hi;  // the node's rectangle
    };
    Range stack[64];  // two per level at most: the tree is 25 levels deep for kMaxMeshTriangles corners
    int top = 0;
    stack[top++] = {0, static_cast<int>(tree_.size()), 0, treeLo_, treeHi_};
    while (top > 0) {
      const Range t = stack[--top];
      if (t.end - t.begin <= kLeaf) {
        for (int k = t.begin; k < t.end; ++k)
          if (inside(tree_[k])) return false;
        continue;
      }
      const int mid = (t.begin + t.end) / 2, r = tree_[mid];
      if (inside(r)) return false;
      const double at = q_[r](t.axis);
      Vec2 leftHi = t.hi, rightLo = t.lo;
      leftHi(t.axis) = at, rightLo(t.axis) = at;
      if (lo(t.axis) <= at && !misses(t.lo, leftHi)) stack[top++] = {t.begin, mid, 1 - t.axis, t.lo, leftHi};
      if (hi(t.axis) >= at && !misses(rightLo, t.hi)) stack[top++] = {mid + 1, t.end, 1 - t.axis, rightLo, t.hi};
    }
    return true;
  }

  // The ears, a circular list in ring order (earNext_ / earPrev_; -1: not an ear).
  void linkEar(int x, int before) {  // before: an ear, or -1 when there is none
    if (before < 0) {
      earNext_[x] = earPrev_[x] = x;
    } else {
      earNext_[x] = before, earPrev_[x] = earPrev_[before];
      earNext_[earPrev_[before]] = x, earPrev_[before] = x;
    }
    ++ears_;
  }
  void unlinkEar(int x) {
    earNext_[earPrev_[x]] = earNext_[x], earPrev_[earNext_[x]] = earPrev_[x];
    earNext_[x] = earPrev_[x] = -1;
    --ears_;
  }
  // Every corner left looked at, into an empty list (at the start, and where no ear is left: a
  // self-intersecting polygon); the first ear from `first` on, or -1.
  int findEars(int first) {
    int head = -1, i = first;
    do {
      if (isEar(i)) linkEar(i, head), head = head < 0 ? i : head;  // before the head: at the end of the circle
      i = next_[i];
    } while (i != first);
    return head;
  }

  bool clipEars(const std::vector<int>& ids, std::vector<int>& tri, int& first, int& remaining) {
    const int n = remaining;
    reflex_.resize(n);
    for (int i = 0; i < n; ++i) reflex_[i] = isReflex(i);
    buildTree(first);
    earNext_.assign(n, -1);
    earPrev_.assign(n, -1);
    ears_ = 0;
    tests_ = 0;
    const long long budget = static_cast<long long>(kPolygonTestsPerCorner) * n + 1000000;
    int ear = findEars(first);
    while (remaining > 3 && tests_ <= budget) {
      if (ear < 0 && (ear = findEars(first)) < 0) break;  // no ear at all: the fan
      const int b = ear, a = prev_[b], c = next_[b];
      tri.insert(tri.end(), {ids[a], ids[b], ids[c]});
      next_[a] = c, prev_[c] = a;
      --remaining;
      first = c;
      const int after = earNext_[b] == b ? -1 : earNext_[b];
      unlinkEar(b);
      // The first ear past c (in ring order), where the scan goes on: skipping c spreads the triangles.
      const int beyond = after == c ? (earNext_[c] == c ? -1 : earNext_[c]) : after;
      // The neighbours' corners changed: a reflex one may have become convex (or, in a self-intersecting
      // polygon, the other way round), and either may have become an ear or stopped being one.
      for (int x : {a, c}) {
        const bool now = isReflex(x);
        if (reflex_[x] && !now) --active_;
        if (!reflex_[x] && now) extra_.push_back(x), ++active_;
        reflex_[x] = now;
      }
      // Rebuilt when most of the tree is skipped, or many corners wait beside it: amortized n log n.
      if (2 * active_ + kLeaf < static_cast<int>(tree_.size()) || static_cast<int>(extra_.size()) > kLeaf + active_ / 4)
        buildTree(first);
      for (int x : {c, a}) {  // c first: a goes in before it
        const bool now = isEar(x), listed = earNext_[x] >= 0;
        if (listed && !now) unlinkEar(x);
        if (!listed && now) linkEar(x, x == a && earNext_[c] >= 0 ? c : beyond);
      }
      ear = ears_ == 0 ? -1 : beyond >= 0 && earNext_[beyond] >= 0 ? beyond : earNext_[c] >= 0 ? earNext_[c] : earNext_[a];
    }
    return tests_ <= budget;
  }

  std::vector<int> prev_, next_, tree_, extra_, earNext_, earPrev_;
  std::vector<char> reflex_;
  std::vector<Vec2> q_;
  Vec2 treeLo_, treeHi_;  // the reflex corners' box
  int active_ = 0;  // reflex corners, in the tree or in extra_
  int ears_ = 0;
  long long tests_ = 0;
};

}  // namespace

bool triangulatePolygon(const std::vector<int>& ids, const double* xyz, std::vector<int>& tri) {
  thread_local PolygonTriangulator triangulator;  // its buffers kept from one polygon to the next
  return triangulator.add(ids, xyz, tri);
}

namespace {

std::string convolutedPolygon(std::size_t corners) {
  return std::to_string(corners) + " corners: too convoluted to triangulate (its ears took more than " +
         std::to_string(kPolygonTestsPerCorner) + " point tests per corner): split it into smaller polygons";
}

// ---------------------------------------------------------------------------------------------------
// OBJ: `v x y z [w]` and `f a b c ...` with a = i, i/t, i//n or i/t/n (negative i counts back from the
// last vertex defined); every other record is ignored.
RawMesh readObj(const std::uint8_t* data, std::size_t size, const std::string& name) {
  TextReader in(data, size, name, 0, 1, true);
  RawMesh mesh;
  std::vector<int> polygonIds, offsets{0}, polygonLine;
  long long forwardIndex = 0;
  int forwardLine = 0;
  std::string_view t;
  while (in.token(t)) {
    if (t == "v") {
      for (int k = 0; k < 3; ++k) {
        std::string_view c;
        if (!in.tokenOnLine(c)) in.fail("vertex has fewer than 3 coordinates");
        mesh.xyz.push_back(in.number(c, "coordinate"));
      }
      checkVertexLimit(name, mesh.xyz.size() / 3);
    } else if (t == "f") {
      const int before = static_cast<int>(polygonIds.size());
      std::string_view ref;
      while (in.tokenOnLine(ref)) {
        const long long i = in.integer(ref.substr(0, ref.find('/')), "vertex index");
        const long long defined = mesh.vertexCount();
        if (i == 0) in.fail("vertex index 0 (OBJ counts from 1)");
        if (i < -defined)  // not -i > defined: -LONG_MIN overflows
          in.fail("relative vertex index " + std::to_string(i) + " reaches before the first vertex (" +
                  std::to_string(defined) + " defined so far)");
        if (i > static_cast<long long>(kMaxMeshVertices)) in.fail("vertex index " + std::to_string(i) + " is out of range");
        if (i > defined && i > forwardIndex) forwardIndex = i, forwardLine = in.line();
        polygonIds.push_back(static_cast<int>(i < 0 ? defined + i : i - 1));
      }
      if (static_cast<int>(polygonIds.size()) - before < 3)
        in.fail("face has " + std::to_string(static_cast<int>(polygonIds.size()) - before) + " vertices (at least 3 needed)");
      offsets.push_back(static_cast<int>(polygonIds.size()));
      polygonLine.push_back(in.line());
      checkTriangleLimit(name, polygonIds.size() - 2 * (offsets.size() - 1));
    }
    in.skipLine();
  }
  if (forwardIndex > mesh.vertexCount())
    failAt(name, "line " + std::to_string(forwardLine), "vertex index " + std::to_string(forwardIndex) +
                   " is out of range (the file has " + std::to_string(mesh.vertexCount()) + " vertices)");
  std::vector<int> ids;
  for (std::size_t f = 0; f + 1 < offsets.size(); ++f) {
    ids.assign(polygonIds.begin() + offsets[f], polygonIds.begin() + offsets[f + 1]);
    if (!triangulatePolygon(ids, mesh.xyz.data(), mesh.tri))
      failAt(name, "line " + std::to_string(polygonLine[f]), "a face of " + convolutedPolygon(ids.size()));
  }
  return mesh;
}

// OFF: `OFF`, then `#vertices #faces #edges`, the vertices, then `n i1 .. in` per face. Anything after
// the coordinates or indices on a line (COFF / NOFF colours and normals) is ignored.
RawMesh readOff(const std::uint8_t* data, std::size_t size, const std::string& name) {
  TextReader in(data, size, name, 0, 1, true);
  const std::string_view magic = in.require("the OFF header");
  if (magic != "OFF" && magic != "COFF" && magic != "NOFF" && magic != "CNOFF")
    in.fail("expected 'OFF' on the first line, found '" + std::string(magic.substr(0, 20)) + "'");
  const long long nv = in.integer(in.require("the vertex count"), "vertex count");
  const long long nf = in.integer(in.require("the face count"), "face count");
  in.integer(in.require("the edge count"), "edge count");
  if (nv < 0 || nf < 0) in.fail("negative vertex or face count");
  checkVertexLimit(name, static_cast<std::uint64_t>(nv));
  checkTriangleLimit(name, static_cast<std::uint64_t>(nf));
  // Each vertex and face needs at least 6 bytes of text: a count beyond that is wrong, not a reason to allocate.
  if (static_cast<std::size_t>(nv + nf) > size / 6) in.fail("the header declares more vertices and faces than the file can hold");
  in.skipLine();
  RawMesh mesh;
  mesh.xyz.reserve(3 * nv);
  for (long long v = 0; v < nv; ++v) {
    std::string_view c;
    for (int k = 0; k < 3; ++k) {
      if (!in.token(c)) in.fail("file ends after " + std::to_string(v) + " of the " + std::to_string(nv) + " vertices declared");
      mesh.xyz.push_back(in.number(c, "coordinate"));
    }
    in.skipLine();
  }
  std::vector<int> ids;
  for (long long f = 0; f < nf; ++f) {
    std::string_view c;
    if (!in.token(c)) in.fail("file ends after " + std::to_string(f) + " of the " + std::to_string(nf) + " faces declared");
    const long long n = in.integer(c, "face size");
    if (n < 3) in.fail("face " + std::to_string(f) + " has " + std::to_string(n) + " vertices (at least 3 needed)");
    ids.clear();
    for (long long k = 0; k < n; ++k) {
      if (!in.tokenOnLine(c)) in.fail("face " + std::to_string(f) + " lists fewer than the " + std::to_string(n) + " vertices it declares");
      const long long i = in.integer(c, "vertex index");
      if (i < 0 || i >= nv)
        in.fail("face " + std::to_string(f) + ": vertex index " + std::to_string(i) + " is out of range (the file has " +
                std::to_string(nv) + " vertices, counted from 0)");
      ids.push_back(static_cast<int>(i));
    }
    if (!triangulatePolygon(ids, mesh.xyz.data(), mesh.tri)) in.fail("face " + std::to_string(f) + " of " + convolutedPolygon(ids.size()));
    checkTriangleLimit(name, mesh.tri.size() / 3);
    in.skipLine();
  }
  if (!in.atEnd()) in.fail("unexpected data after the " + std::to_string(nf) + " faces declared (is the face count right?)");
  return mesh;
}

// ---------------------------------------------------------------------------------------------------
// PLY: ascii or binary, any element and property order; the vertex element's x y z and the face
// element's vertex_indices (or vertex_index) list are read, every other property is skipped by its type.
enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool plyType(const std::string& s, PlyType& t) {
  static const std::pair<const char*, PlyType> names[] = {
      {"char", PlyType::Int8},    {"int8", PlyType::Int8},     {"uchar", PlyType::UInt8},   {"uint8", PlyType::UInt8},
      {"short", PlyType::Int16},  {"int16", PlyType::Int16},   {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16},
      {"int", PlyType::Int32},    {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},   {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64}, {"float64", PlyType::Float64}};
  for (const auto& [n, type] : names)
    if (s == n) return t = type, true;
  return false;
}

std::size_t plySize(PlyType t) {
  switch (t) {
    case PlyType::Int8: case PlyType::UInt8: return 1;
    case PlyType::Int16: case PlyType::UInt16: return 2;
    case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 1;
}

bool plyIsInteger(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

// The values an integer type holds, and its name, for ascii values that must fit the type declared.
void plyRange(PlyType t, long long& lo, long long& hi, const char*& name) {
  switch (t) {
    case PlyType::Int8: lo = INT8_MIN, hi = INT8_MAX, name = "char"; return;
    case PlyType::UInt8: lo = 0, hi = UINT8_MAX, name = "uchar"; return;
    case PlyType::Int16: lo = INT16_MIN, hi = INT16_MAX, name = "short"; return;
    case PlyType::UInt16: lo = 0, hi = UINT16_MAX, name = "ushort"; return;
    case PlyType::Int32: lo = INT32_MIN, hi = INT32_MAX, name = "int"; return;
    default: lo = 0, hi = UINT32_MAX, name = "uint"; return;
  }
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool isList = false;
  PlyType countType = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;  // not size_t: wasm's has 32 bits, and the header's count is checked whole
  std::vector<PlyProperty> properties;
};

// Reads values one by one from the body, in ascii or binary; every error names the element and its index.
class PlyBody {
 public:
  PlyBody(const std::uint8_t* data, std::size_t size, std::size_t start, int line, const std::string& name,
          const std::string& encoding)
      : data_(data), size_(size), pos_(start), ascii_(encoding == "ascii"), bigEndian_(encoding == "binary_big_endian"),
        text_(data, size, name, start, line), name_(name) {}

  void at(const std::string& element, std::uint64_t index) { element_ = element, index_ = index; }

  double value(PlyType t, const char* what) {
    if (ascii_) {
      std::string_view tok;
      if (!text_.token(tok)) fail("file ends inside " + where());
      if (!plyIsInteger(t)) return text_.number(tok, what, false);
      // An integer out of its type's range is no value the type holds (and no count or index phex can use).
      const long long x = text_.integer(tok, what);
      long long lo, hi;
      const char* type;
      plyRange(t, lo, hi, type);
      if (x < lo || x > hi)
        fail(std::string(what) + " " + std::string(tok) + " of " + where() + " is out of range for its type " + type + " (" +
             std::to_string(lo) + " to " + std::to_string(hi) + ")");
      return static_cast<double>(x);
    }
    const std::size_t n = plySize(t);
    if (pos_ + n > size_) fail("file ends inside " + where() + " (truncated)");
    std::uint8_t b[8];
    std::memcpy(b, data_ + pos_, n);
    if (bigEndian_) std::reverse(b, b + n);  // PLY binary values are stored whole; the host is little-endian (x86, wasm)
    pos_ += n;
    double x = 0;
    switch (t) {
      case PlyType::Int8: { std::int8_t v; std::memcpy(&v, b, 1); x = v; break; }
      case PlyType::UInt8: x = b[0]; break;
      case PlyType::Int16: { std::int16_t v; std::memcpy(&v, b, 2); x = v; break; }
      case PlyType::UInt16: { std::uint16_t v; std::memcpy(&v, b, 2); x = v; break; }
      case PlyType::Int32: { std::int32_t v; std::memcpy(&v, b, 4); x = v; break; }
      case PlyType::UInt32: { std::uint32_t v; std::memcpy(&v, b, 4); x = v; break; }
      case PlyType::Float32: { float v; std::memcpy(&v, b, 4); x = v; break; }
      case PlyType::Float64: { std::memcpy(&x, b, 8); break; }
    }
    return x;
  }

  // After the last element: trailing bytes mean the counts are wrong.
  void expectEnd(const std::string& last) {
    if (ascii_ ? !text_.atEnd() : pos_ != size_)
      fail("unexpected data after the last element ('" + last + "'): are the element counts right?");
  }

  [[noreturn]] void fail(const std::string& what) {
    if (ascii_) text_.fail(what);
    throw Error(ErrorCode::InvalidInput, fileLabel(name_) + " byte " + std::to_string(pos_) + ": " + what);
  }

  std::string where() const { return element_ + " " + std::to_string(index_); }
  bool ascii() const { return ascii_; }
  std::size_t left() const { return size_ - (ascii_ ? text_.position() : pos_); }

 private:
  const std::uint8_t* data_;
  std::size_t size_, pos_;
  bool ascii_, bigEndian_;
  TextReader text_;
  std::string name_, element_;
  std::uint64_t index_ = 0;
};

// True when the bytes look like text (only printable characters and line ends): binary data does not.
bool looksLikeText(const std::uint8_t* data, std::size_t size) {
  if (size < 16) return false;
  for (std::size_t i = 0; i < std::min<std::size_t>(size, 256); ++i)
    if ((data[i] < 0x20 && data[i] != '\n' && data[i] != '\r' && data[i] != '\t') || data[i] > 0x7e) return false;
  return true;
}

RawMesh readPly(const std::uint8_t* data, std::size_t size, const std::string& name, std::string& encoding) {
  // The header is text up to `end_header`; a body byte may follow on the same line end.
  TextReader header(data, size, name);
  std::string_view t;
  if (!header.tokenOnLine(t) || t != "ply") header.fail("expected 'ply' on the first line");
  header.skipLine();
  std::vector<PlyElement> elements;
  std::size_t bodyStart = 0;
  int bodyLine = 0;
  for (;;) {
    if (!header.token(t)) header.fail("file ends before 'end_header'");
    const std::string word(t);
    if (word == "format") {
      encoding = std::string(header.require("the format"));
      if (encoding != "ascii" && encoding != "binary_little_endian" && encoding != "binary_big_endian")
        header.fail("unknown PLY format '" + encoding + "'");
      header.skipLine();
    } else if (word == "comment" || word == "obj_info") {
      header.skipLine();
    } else if (word == "element") {
      PlyElement e;
      e.name = std::string(header.require("the element name"));
      const long long count = header.integer(header.require("the element count"), "element count");
      if (count < 0) header.fail("negative count for element '" + e.name + "'");
      for (const PlyElement& before : elements)
        if (before.name == e.name && (e.name == "vertex" || e.name == "face")) header.fail("a second '" + e.name + "' element");
      e.count = static_cast<std::uint64_t>(count);
      const std::size_t limit = e.name == "vertex" ? kMaxMeshVertices : kMaxMeshTriangles;
      if ((e.name == "vertex" || e.name == "face") && e.count > limit)
        header.fail("more than " + std::to_string(limit) + " " + (e.name == "vertex" ? "vertices" : "faces") + " (phex's limit)");
      elements.push_back(e);
      header.skipLine();
    } else if (word == "property") {
      if (elements.empty()) header.fail("property before any element");
      PlyProperty p;
      std::string type(header.require("the property type"));
      if (type == "list") {
        p.isList = true;
        if (!plyType(std::string(header.require("the list count type")), p.countType) || !plyIsInteger(p.countType))
          header.fail("a list count must have an integer type");
        type = std::string(header.require("the list item type"));
      }
      if (!plyType(type, p.type)) header.fail("unknown property type '" + type + "'");
      p.name = std::string(header.require("the property name"));
      elements.back().properties.push_back(p);
      header.skipLine();
    } else if (word == "end_header") {
      // The body starts right after this line's end, even when its first byte looks like a space.
      const std::uint8_t* end = data + size;
      const std::uint8_t* p = reinterpret_cast<const std::uint8_t*>(t.data() + t.size());
      while (p < end && (*p == ' ' || *p == '\t')) ++p;
      if (p < end && *p == '\r') ++p;
      if (p < end && *p == '\n') ++p;
      bodyStart = static_cast<std::size_t>(p - data);
      bodyLine = header.line() + 1;
      break;
    } else {
      header.fail("unknown header line '" + word + "'");
    }
  }
  if (encoding.empty()) header.fail("no 'format' line in the header");

  PlyBody body(data, size, bodyStart, bodyLine, name, encoding);
  RawMesh mesh;
  bool sawVertex = false, sawFace = false;
  for (const PlyElement& e : elements) {
    // Every element takes bytes (binary: its values and list counts; ascii: at least a digit and a space per
    // value, the file's last value without its space): a count beyond the bytes left is a wrong count, not a
    // reason to allocate or to loop. An element of no properties takes none, and so has no count to read.
    if (e.properties.empty() && e.count > 0)
      body.fail("the header declares " + std::to_string(e.count) + " '" + e.name +
                "' elements but no properties for them (a broken header)");
    std::size_t minBytes = 0;
    for (const PlyProperty& p : e.properties) minBytes += p.isList ? plySize(p.countType) : plySize(p.type);
    if (body.ascii()) minBytes = 2 * e.properties.size();
    const std::size_t left = body.left();
    if (minBytes > 0 && e.count > (left + (body.ascii() ? 1 : 0)) / minBytes)
      body.fail("the header declares " + std::to_string(e.count) + " '" + e.name + "' elements of at least " +
                std::to_string(minBytes) + " bytes, but only " + std::to_string(left) +
                " bytes are left (truncated file or wrong count)");
    const bool isVertex = e.name == "vertex", isFace = e.name == "face";
    int xyz[3] = {-1, -1, -1}, indices = -1;
    for (int i = 0; i < static_cast<int>(e.properties.size()); ++i) {
      const PlyProperty& p = e.properties[i];
      for (int k = 0; k < 3; ++k)
        if (isVertex && !p.isList && p.name == std::string(1, static_cast<char>('x' + k))) xyz[k] = i;
      if (isFace && p.isList && (p.name == "vertex_indices" || p.name == "vertex_index")) indices = i;
    }
    if (isVertex) {
      if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) fail(name, "the vertex element lacks an x, y or z property");
      mesh.xyz.resize(3 * static_cast<std::size_t>(e.count));
      sawVertex = true;
    }
    if (isFace) {
      if (indices < 0) fail(name, "the face element has no vertex_indices list");
      if (!plyIsInteger(e.properties[indices].type)) fail(name, "face vertex indices must have an integer type");
      mesh.tri.reserve(3 * static_cast<std::size_t>(e.count));
      sawFace = true;
    }
    std::vector<int> ids;
    for (std::uint64_t i = 0; i < e.count; ++i) {
      body.at(e.name, i);
      for (int k = 0; k < static_cast<int>(e.properties.size()); ++k) {
        const PlyProperty& p = e.properties[k];
        if (!p.isList) {
          const double x = body.value(p.type, "a value");
          for (int c = 0; c < 3; ++c) {
            if (!isVertex || k != xyz[c]) continue;
            if (!std::isfinite(x)) body.fail(p.name + " of " + body.where() + " is " + (std::isnan(x) ? "NaN" : "infinite"));
            mesh.xyz[3 * i + c] = x;
          }
          continue;
        }
        const double n = body.value(p.countType, "the list length");
        if (n < 0) body.fail("negative list length in " + body.where());
        // Each item takes at least a byte (binary: its size): a longer list than the bytes left is a wrong length.
        if (n > static_cast<double>(body.left() / (body.ascii() ? 1 : plySize(p.type))))
          body.fail("the list of " + body.where() + " declares " + std::to_string(static_cast<long long>(n)) + " items, but only " +
                    std::to_string(body.left()) + " bytes are left (truncated file or wrong length)");
        const bool keep = isFace && k == indices;
        if (keep) {
          if (n < 3) body.fail(body.where() + " has " + std::to_string(static_cast<long long>(n)) + " vertices (at least 3 needed)");
          if (!sawVertex) fail(name, "the face element comes before the vertex element");
          ids.clear();
        }
        for (long long j = 0; j < static_cast<long long>(n); ++j) {
          const double x = body.value(p.type, "a list item");
          if (!keep) continue;
          if (x < 0 || x >= mesh.vertexCount())
            body.fail(body.where() + ": vertex index " + std::to_string(static_cast<long long>(x)) +
                      " is out of range (the file has " + std::to_string(mesh.vertexCount()) + " vertices, counted from 0)");
          ids.push_back(static_cast<int>(x));
        }
        if (keep) {
          if (!triangulatePolygon(ids, mesh.xyz.data(), mesh.tri)) body.fail(body.where() + " of " + convolutedPolygon(ids.size()));
          checkTriangleLimit(name, mesh.tri.size() / 3);
        }
      }
    }
  }
  if (!sawVertex) fail(name, "no vertex element in the header");
  if (!sawFace) fail(name, "no face element in the header (phex needs a triangle mesh, not a point cloud)");
  body.expectEnd(elements.empty() ? "" : elements.back().name);
  return mesh;
}

// ---------------------------------------------------------------------------------------------------
// STL corners are welded where their coordinates are bit-for-bit equal (after -0 -> +0): an open-addressing
// table of vertex ids, hashed on the coordinates.
class Welder {
 public:
  Welder(RawMesh& mesh, std::size_t corners) : mesh_(mesh), table_(exactPointSlots(corners)) {}
  int add(double x, double y, double z) {
    const double p[3] = {x + 0.0, y + 0.0, z + 0.0};  // + 0.0 turns -0 into +0
    const std::size_t slot = exactPointSlot(table_, p[0], p[1], p[2], [&](int id) {
      const double* q = &mesh_.xyz[3 * static_cast<std::size_t>(id)];
      return Vec3(q[0], q[1], q[2]);
    });
    if (table_[slot] < 0) {
      table_[slot] = mesh_.vertexCount();
      mesh_.xyz.insert(mesh_.xyz.end(), p, p + 3);
    }
    return table_[slot];
  }

 private:
  RawMesh& mesh_;
  std::vector<int> table_;
};

bool stlBinarySize(const std::uint8_t* data, std::size_t size, std::uint32_t& count) {
  if (size < 84) return false;
  std::memcpy(&count, data + 80, 4);  // little-endian on every host phex targets
  return 84 + 50 * static_cast<std::uint64_t>(count) == size;
}

bool startsWithSolid(const std::uint8_t* data, std::size_t size) {
  std::size_t i = 0;
  while (i < size && (data[i] == ' ' || data[i] == '\t' || data[i] == '\r' || data[i] == '\n')) ++i;
  return size - i >= 5 && std::memcmp(data + i, "solid", 5) == 0;
}

RawMesh readStlBinary(const std::uint8_t* data, std::uint32_t count, const std::string& name) {
  checkTriangleLimit(name, count);
  RawMesh mesh;
  mesh.tri.reserve(3 * static_cast<std::size_t>(count));
  Welder welder(mesh, 3 * static_cast<std::size_t>(count));
  for (std::uint32_t f = 0; f < count; ++f) {
    const std::uint8_t* record = data + 84 + 50 * static_cast<std::size_t>(f);
    float c[9];
    std::memcpy(c, record + 12, sizeof c);  // skip the facet normal: phex uses the winding
    for (int k = 0; k < 9; ++k)
      if (!std::isfinite(c[k]))
        failAt(name, "byte " + std::to_string(84 + 50 * static_cast<std::size_t>(f) + 12 + 4 * k) + " (triangle " + std::to_string(f) + ")",
               std::string("coordinate is ") + (std::isnan(c[k]) ? "NaN" : "infinite"));
    for (int k = 0; k < 3; ++k) mesh.tri.push_back(welder.add(c[3 * k], c[3 * k + 1], c[3 * k + 2]));
  }
  return mesh;
}

RawMesh readStlAscii(const std::uint8_t* data, std::size_t size, const std::string& name) {
  TextReader in(data, size, name);
  RawMesh mesh;
  Welder welder(mesh, std::min<std::size_t>(size / 16, 3 * kMaxMeshTriangles));
  auto expect = [&](const char* word) {
    const std::string_view t = in.require((std::string("'") + word + "'").c_str());
    if (t != word) in.fail(std::string("expected '") + word + "', found '" + std::string(t.substr(0, 20)) + "'");
  };
  std::string_view t;
  while (in.token(t)) {
    if (t != "solid") in.fail("expected 'solid', found '" + std::string(t.substr(0, 20)) + "'");
    in.skipLine();  // the solid's name
    for (;;) {
      t = in.require("'facet' or 'endsolid'");
      if (t == "endsolid") {
        in.skipLine();
        break;
      }
      if (t != "facet") in.fail("expected 'facet' or 'endsolid', found '" + std::string(t.substr(0, 20)) + "'");
      expect("normal");
      for (int k = 0; k < 3; ++k) in.number(in.require("a normal coordinate"), "normal coordinate");
      expect("outer");
      expect("loop");
      for (int v = 0; v < 3; ++v) {
        expect("vertex");
        double p[3];
        for (double& c : p) c = in.number(in.require("a vertex coordinate"), "coordinate");
        mesh.tri.push_back(welder.add(p[0], p[1], p[2]));
      }
      expect("endloop");
      expect("endfacet");
      checkTriangleLimit(name, mesh.tri.size() / 3);
    }
  }
  return mesh;
}

RawMesh readStl(const std::uint8_t* data, std::size_t size, const std::string& name, std::string& encoding) {
  std::uint32_t count = 0;
  // The size rule decides: many binary writers start their 80-byte header with "solid" too.
  if (stlBinarySize(data, size, count)) {
    encoding = "binary_little_endian";
    return readStlBinary(data, count, name);
  }
  // "solid" followed by binary bytes is a binary file whose size does not match its count.
  if (startsWithSolid(data, size) && looksLikeText(data, std::min<std::size_t>(size, 256))) {
    encoding = "ascii";
    return readStlAscii(data, size, name);
  }
  if (size < 84) fail(name, "only " + std::to_string(size) + " bytes: too short for a binary STL (84-byte header) and not ASCII STL (no 'solid')");
  fail(name, "binary STL header declares " + std::to_string(count) + " triangles, which needs " +
                 std::to_string(84 + 50 * static_cast<std::uint64_t>(count)) + " bytes, but the file has " +
                 std::to_string(size) + " (truncated file or wrong count)");
}

std::string sniffFormat(const std::uint8_t* data, std::size_t size, const std::string& name) {
  auto starts = [&](const char* word) {
    const std::size_t n = std::strlen(word);
    return size >= n && std::memcmp(data, word, n) == 0;
  };
  std::uint32_t count;
  if (starts("ply\n") || starts("ply\r")) return "ply";
  if (starts("OFF") || starts("COFF") || starts("NOFF") || starts("CNOFF")) return "off";
  if (stlBinarySize(data, size, count) || startsWithSolid(data, size)) return "stl";
  for (std::size_t i = 0; i + 1 < size && i < (1u << 20); ++i)
    if ((i == 0 || data[i - 1] == '\n') && (data[i] == 'v' || data[i] == 'f') && data[i + 1] == ' ') return "obj";
  fail(name, "cannot tell the mesh format (expected an .obj, .off, .ply or .stl file)");
}

// ---------------------------------------------------------------------------------------------------
// Corners of every vertex, in compressed rows: the triangles around vertex v are
// corner[start[v] .. start[v+1]) / 3.
struct VertexCorners {
  std::vector<int> start, corner;
  VertexCorners(const std::vector<int>& tri, int nv) : start(nv + 1, 0), corner(tri.size()) {
    for (int v : tri) ++start[v + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int c = 0; c < static_cast<int>(tri.size()); ++c) corner[fill[tri[c]]++] = c;
  }
};

int findRoot(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

}  // namespace

TriMesh cleanTriMesh(const TriMesh& raw, const std::string& name, MeshReadReport* report) {
  const int nv = static_cast<int>(raw.V.rows());
  const int nfIn = static_cast<int>(raw.F.rows());
  if (nfIn == 0) fail(name, "has no faces");
  checkTriangleLimit(name, static_cast<std::size_t>(nfIn));
  checkVertexLimit(name, static_cast<std::size_t>(nv));
  for (int v = 0; v < nv; ++v) {
    if (!raw.V.row(v).allFinite()) fail(name, "vertex " + std::to_string(v) + " has a coordinate that is not finite");
    for (int a = 0; a < 3; ++a)
      if (std::abs(raw.V(v, a)) > kMaxMeshCoordinate) {
        char value[64];
        std::snprintf(value, sizeof value, "%.9g", raw.V(v, a));
        fail(name, "vertex " + std::to_string(v) + " " + formatPoint(&raw.V(v, 0)) + " has " + "xyz"[a] + " = " + value +
                       ", beyond ±1e50: the extent of the mesh and the products of its lengths must stay finite");
      }
  }
  auto point = [&](int v) -> Vec3 { return raw.V.row(v).transpose(); };

  // Degenerate triangles carry no surface: drop them (counted), as long as something is left.
  std::vector<int> tri;
  tri.reserve(3 * static_cast<std::size_t>(nfIn));
  int degenerate = 0;
  for (int f = 0; f < nfIn; ++f) {
    const int a = raw.F(f, 0), b = raw.F(f, 1), c = raw.F(f, 2);
    for (int v : {a, b, c})
      if (v < 0 || v >= nv)
        fail(name, "triangle " + std::to_string(f) + " refers to vertex " + std::to_string(v) + ", out of range (" +
                       std::to_string(nv) + " vertices, counted from 0)");
    const Vec3 e1 = point(b) - point(a), e2 = point(c) - point(a), e3 = point(c) - point(b);
    const double longest = std::max({e1.squaredNorm(), e2.squaredNorm(), e3.squaredNorm()});
    if (a == b || b == c || a == c || !(e1.cross(e2).norm() > 1e-12 * longest)) {
      ++degenerate;
      continue;
    }
    tri.insert(tri.end(), {a, b, c});
  }
  const int nf = static_cast<int>(tri.size() / 3);
  if (nf == 0) fail(name, "all " + std::to_string(nfIn) + " triangles are degenerate (a repeated vertex or zero area)");

  // Neighbour across each edge, from the corners sorted by their edge (so that a vertex in many triangles, a
  // fan's hub, costs no more than any other); an edge in three or more triangles is non-manifold.
  const VertexCorners around(tri, nv);
  std::vector<std::pair<std::uint64_t, int>> edges(tri.size());
  for (int c = 0; c < 3 * nf; ++c) {
    const std::uint64_t a = static_cast<std::uint32_t>(tri[c]), b = static_cast<std::uint32_t>(tri[3 * (c / 3) + (c + 1) % 3]);
    edges[c] = {std::min(a, b) << 32 | std::max(a, b), c};
  }
  std::sort(edges.begin(), edges.end());
  std::vector<int> neighbour(tri.size(), -1);
  std::size_t crowded = edges.size();  // the group of the first corner whose edge is in three triangles or more
  for (std::size_t i = 0, j; i < edges.size(); i = j) {
    for (j = i + 1; j < edges.size() && edges[j].first == edges[i].first;) ++j;
    if (j - i == 2) neighbour[edges[i].second] = edges[i + 1].second / 3, neighbour[edges[i + 1].second] = edges[i].second / 3;
    if (j - i > 2 && (crowded == edges.size() || edges[i].second < edges[crowded].second)) crowded = i;
  }
  if (crowded < edges.size()) {
    const int c = edges[crowded].second, a = tri[c], b = tri[3 * (c / 3) + (c + 1) % 3];
    std::string faces;
    std::size_t j = crowded;
    for (; j < edges.size() && edges[j].first == edges[crowded].first; ++j) faces += (faces.empty() ? "" : ", ") + std::to_string(edges[j].second / 3);
    fail(name, "non-manifold edge between vertices " + std::to_string(a) + " " + formatPoint(&raw.V(a, 0)) + " and " +
                   std::to_string(b) + " " + formatPoint(&raw.V(b, 0)) + ": it belongs to " + std::to_string(j - crowded) +
                   " triangles (" + faces + "), at most 2 allowed");
  }
  // Does triangle g traverse the edge a->b in the same direction as a triangle holding a->b?
  auto sameDirection = [&](int g, int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (tri[3 * g + k] == a) return tri[3 * g + (k + 1) % 3] == b;
    return false;
  };

  // Orientation: a breadth-first walk per connected component decides which triangles to flip.
  std::vector<signed char> flip(nf, -1);  // -1 unvisited, 0 keep, 1 flip
  std::vector<int> queue, component;
  int flipped = 0;
  for (int seed = 0; seed < nf; ++seed) {
    if (flip[seed] >= 0) continue;
    flip[seed] = 0;
    queue.assign(1, seed);
    component.clear();
    bool closed = true;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int f = queue[q];
      component.push_back(f);
      for (int k = 0; k < 3; ++k) {
        const int g = neighbour[3 * f + k];
        if (g < 0) {
          closed = false;
          continue;
        }
        const int a = tri[3 * f + k], b = tri[3 * f + (k + 1) % 3];
        const signed char want = static_cast<signed char>(flip[f] ^ (sameDirection(g, a, b) ? 1 : 0));
        if (flip[g] < 0) {
          flip[g] = want;
          queue.push_back(g);
        } else if (flip[g] != want) {
          fail(name, "triangles " + std::to_string(f) + " and " + std::to_string(g) + " (sharing the edge from vertex " +
                         std::to_string(a) + " to " + std::to_string(b) +
                         ") cannot be oriented consistently: the surface is not orientable (like a Moebius band)");
        }
      }
    }
    // A closed component faces outward (positive enclosed volume); an open one keeps the file's majority.
    bool reverse;
    if (closed) {
      double volume = 0;
      for (int f : component) {
        const double v = point(tri[3 * f]).dot(point(tri[3 * f + 1]).cross(point(tri[3 * f + 2])));
        volume += flip[f] ? -v : v;
      }
      reverse = volume < 0;
    } else {
      const long count = std::count_if(component.begin(), component.end(), [&](int f) { return flip[f] == 1; });
      reverse = 2 * count > static_cast<long>(component.size());
    }
    for (int f : component) {
      if (reverse) flip[f] ^= 1;
      flipped += flip[f];
    }
  }

  // A vertex whose corners split into several fans (joined across shared edges) is where sheets touch.
  std::vector<int> parent(tri.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (int c = 0; c < 3 * nf; ++c) {
    const int g = neighbour[c];
    if (g < 0) continue;
    const int f = c / 3, a = tri[c], b = tri[3 * f + (c + 1) % 3];
    for (int k = 0; k < 3; ++k) {
      const int v = tri[3 * g + k];
      if (v == a) parent[findRoot(parent, 3 * g + k)] = findRoot(parent, c);
      if (v == b) parent[findRoot(parent, 3 * g + k)] = findRoot(parent, 3 * f + (c + 1) % 3);
    }
  }
  for (int v = 0; v < nv; ++v) {
    const int begin = around.start[v], end = around.start[v + 1];
    for (int i = begin + 1; i < end; ++i)
      if (findRoot(parent, around.corner[i]) != findRoot(parent, around.corner[begin]))
        fail(name, "non-manifold vertex " + std::to_string(v) + " " + formatPoint(&raw.V(v, 0)) +
                       ": its triangles form separate fans (surfaces touching at a point)");
  }

  // Unused vertices go; the others keep their order.
  std::vector<int> newId(nv, -1);
  std::vector<int> fileVertex;
  for (int v = 0; v < nv; ++v)
    if (around.start[v + 1] > around.start[v]) newId[v] = static_cast<int>(fileVertex.size()), fileVertex.push_back(v);
  TriMesh mesh;
  mesh.V.resize(static_cast<Eigen::Index>(fileVertex.size()), 3);
  for (int i = 0; i < static_cast<int>(fileVertex.size()); ++i) mesh.V.row(i) = raw.V.row(fileVertex[i]);
  mesh.F.resize(nf, 3);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) mesh.F(f, k) = newId[tri[3 * f + (flip[f] ? (3 - k) % 3 : k)]];

  if (report) {
    report->fileVertices = nv;
    report->fileTriangles = nfIn;
    report->degenerateTriangles = degenerate;
    report->unusedVertices = nv - static_cast<int>(fileVertex.size());
    report->flippedTriangles = flipped;
    report->fileVertex = std::move(fileVertex);
  }
  return mesh;
}

TriMesh readMeshBytes(const std::uint8_t* data, std::size_t size, const std::string& format, const std::string& name,
                      MeshReadReport* report) {
  if (size > kMaxMeshFileBytes)
    fail(name, std::to_string(size >> 20) + " MiB is more than phex reads (" + std::to_string(kMaxMeshFileBytes >> 20) + " MiB)");
  if (size == 0) fail(name, "the file is empty");
  const std::string fmt = format.empty() ? sniffFormat(data, size, name) : format;
  std::string encoding = "ascii";
  RawMesh raw;
  if (fmt == "obj") {
    raw = readObj(data, size, name);
  } else if (fmt == "off") {
    raw = readOff(data, size, name);
  } else if (fmt == "stl") {
    raw = readStl(data, size, name, encoding);
  } else if (fmt == "ply") {
    try {
      raw = readPly(data, size, name, encoding);
    } catch (const Error& e) {
      // A binary body that fails to parse and reads as text was most likely written as ascii.
      if (encoding == "ascii" || e.code() != ErrorCode::InvalidInput) throw;
      const std::string head(reinterpret_cast<const char*>(data), std::min<std::size_t>(size, 65536));
      const std::size_t at = head.find("end_header");
      const std::size_t start = at == std::string::npos ? size : std::min(size, at + 11);
      if (looksLikeText(data + start, size - start))
        throw Error(ErrorCode::InvalidInput, std::string(e.what()) + "; the header declares " + encoding +
                                                 " but the data after 'end_header' (byte " + std::to_string(start) +
                                                 ") is text: should the format line say ascii?");
      throw;
    }
  } else {
    throw Error(ErrorCode::InvalidParameter, "unknown mesh format '" + fmt + "' for " + fileLabel(name) + " (use obj, off, ply or stl)");
  }
  if (raw.tri.empty()) fail(name, "has no faces");
  if (report) {
    report->format = fmt;
    report->encoding = encoding;
  }
  return cleanTriMesh(toTriMesh(raw), name, report);
}

TriMesh readMesh(const std::string& path, MeshReadReport* report) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw Error(ErrorCode::Io, "cannot open mesh file '" + path + "' (does it exist and is it readable?)");
  const std::streamoff size = in.tellg();
  if (size < 0) throw Error(ErrorCode::Io, "cannot read mesh file '" + path + "'");
  if (static_cast<std::uint64_t>(size) > kMaxMeshFileBytes)
    fail(path, std::to_string(static_cast<std::uint64_t>(size) >> 20) + " MiB is more than phex reads (" +
                   std::to_string(kMaxMeshFileBytes >> 20) + " MiB)");
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  in.seekg(0);
  if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), size))
    throw Error(ErrorCode::Io, "failed reading mesh file '" + path + "'");
  std::string ext;
  const std::size_t dot = path.find_last_of('.'), slash = path.find_last_of("/\\");
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != "obj" && ext != "off" && ext != "ply" && ext != "stl") ext.clear();
  return readMeshBytes(bytes.data(), bytes.size(), ext, path, report);
}

}  // namespace phex
