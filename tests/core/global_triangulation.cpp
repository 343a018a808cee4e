#include <algorithm>
#include <array>
#include <cctype>
#include <catch.hpp>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <set>

#include "../../core/src/global/global.hpp"
#include "implicit_surfaces.hpp"
#include "notes.hpp"
#include "phex/duality.hpp"
#include "phex/error.hpp"
#include "phex/global_triangulation.hpp"
#include "phex/mesh_io.hpp"
#include "phex/mesh_surface.hpp"
#include "phex/parallel.hpp"
#include "phex/pipeline.hpp"
#include "phex/surfaces.hpp"
#include "phex/triangulation.hpp"

using namespace phex;
using test::allNotes;

namespace {

// Boundary edges (with one triangle) and edges with more than two, or used twice the same way.
struct EdgeCount {
  int boundary = 0, bad = 0;
};
EdgeCount countEdges(const TriMesh& mesh) {
  std::map<std::pair<int, int>, int> directed;
  for (int f = 0; f < mesh.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++directed[{mesh.F(f, k), mesh.F(f, (k + 1) % 3)}];
  EdgeCount c;
  for (const auto& [e, n] : directed) {
    if (n > 1) ++c.bad;
    if (!directed.count({e.second, e.first})) ++c.boundary;
  }
  return c;
}

GlobalOptions atFaces(int faces) {
  GlobalOptions o;
  o.faces = faces;
  return o;
}

// The share of interior vertices of valence 6 of the global triangulation of `surface` laid with `o`.
double laidValence6(const Surface& surface, const GlobalOptions& o) {
  return checkTriangulation(globalTriangulation(surface, o), surface).regularFraction;
}

TriMesh readTestMesh(const std::string& file) { return readMesh(std::string(PHEX_TEST_DATA) + "/" + file); }

MeshInput upload(const std::string& file) {
  std::ifstream in(std::string(PHEX_TEST_DATA) + "/" + file, std::ios::binary);
  MeshInput m;
  m.bytes.assign(std::istreambuf_iterator<char>(in), {});
  m.format = file.substr(file.rfind('.') + 1);
  m.name = file;
  return m;
}

// Pipeline parameters for `mesh` uploaded as an OBJ file named `name`, laid by the global method at `faces`.
PipelineParams globalUpload(const TriMesh& mesh, const std::string& name, int faces) {
  PipelineParams p;
  p.method = TriangulationMethod::Global;
  p.faces = faces;
  MeshInput m;
  const std::string obj = toObj(mesh);
  m.bytes.assign(obj.begin(), obj.end());
  m.format = "obj";
  m.name = name;
  p.mesh = m;
  return p;
}

}  // namespace

TEST_CASE("global triangulation: closed surfaces of genus 0 to 3 keep their genus, and the P-Hex dual has sum(6 - n) = 12(1 - g)") {
  for (int g = 0; g <= 3; ++g) {
    CAPTURE(g);
    const MeshSurface surface(test::closedSurfaceOfGenus(g, 32), "genus");
    const Triangulation t = globalTriangulation(surface, atFaces(700));
    const EdgeCount edges = countEdges(t.mesh);
    CHECK(edges.boundary == 0);  // closed, as the input
    CHECK(edges.bad == 0);       // a manifold
    CHECK(test::eulerCharacteristic(t.mesh) == 2 - 2 * g);
    // The field's singular points turn by 6 chi sixths in all (Poincare-Hopf).
    int turns = 0;
    for (const FieldSingularity& s : t.singularities) turns += s.index;
    CHECK(turns == 12 * (1 - g));
    // Every node of the dual joins three faces; its faces of n sides sum 6 - n to 12 (1 - g).
    const DualMesh dual = dupinDual(t, surface);
    std::vector<int> faces(dual.mesh.V.rows(), 0);
    int sum = 0;
    for (int f = 0; f < dual.mesh.faceCount(); ++f) {
      sum += 6 - dual.mesh.faceSize(f);
      for (int k = 0; k < dual.mesh.faceSize(f); ++k) ++faces[dual.mesh.face(f)[k]];
    }
    CHECK(sum == 12 * (1 - g));
    CHECK(std::count(faces.begin(), faces.end(), 3) == static_cast<long>(faces.size()));
  }
}

TEST_CASE("global triangulation: the shared free-form models keep their topology and come within 10 % of the faces asked") {
  // PH-CPF's and Directional's example meshes (tests/data, their licences in its README).
  const std::vector<std::pair<std::string, int>> models = {
      {"phcpf_car_r.off", 0}, {"phcpf_3holes_r.off", 0}, {"phcpf_six_s0.off", 2},
      {"phcpf_intersection.off", -1}, {"directional_botanic-garden-bubble.off", 1}, {"directional_Concerthall.off", 1}};
  for (const auto& [file, loops] : models) {
    CAPTURE(file);
    const MeshSurface surface(readTestMesh(file), file);
    const Triangulation t = globalTriangulation(surface, atFaces(1000));
    CHECK(std::abs(double(t.mesh.V.rows()) / 1000 - 1) <= 0.1);
    const EdgeCount edges = countEdges(t.mesh);
    CHECK(edges.bad == 0);
    CHECK((edges.boundary == 0) == surface.isClosed());
    CHECK(test::eulerCharacteristic(t.mesh) == test::eulerCharacteristic(surface.mesh()));
    // Boundary vertices lie on the input's boundary: within round-off of one of its edges.
    const VertexRings rings = vertexRings(t.mesh);
    const TriMesh& in = surface.mesh();
    double worst = 0;
    for (int v = 0; v < t.mesh.V.rows(); ++v) {
      if (rings.closed[v]) continue;
      const Vec3 p = t.mesh.V.row(v).transpose();
      double nearest = std::numeric_limits<double>::infinity();
      for (const std::vector<int>& loop : surface.boundaryLoops())
        for (std::size_t i = 0; i < loop.size(); ++i) {
          const Vec3 a = in.V.row(loop[i]).transpose(), b = in.V.row(loop[(i + 1) % loop.size()]).transpose();
          const double s = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
          nearest = std::min(nearest, (a + s * (b - a) - p).norm());
        }
      worst = std::max(worst, nearest);
    }
    CHECK(worst <= 1e-9 * surface.bounds().diagonal().norm());
    if (loops >= 0) {
      // As many boundary loops as the input (the intersection's creases are not boundaries).
      int boundaryVertices = 0;
      for (int v = 0; v < t.mesh.V.rows(); ++v) boundaryVertices += !rings.closed[v];
      CHECK((boundaryVertices > 0) == (loops > 0));
    }
    // Most interior vertices of valence 6 (hexagons of the P-Hex mesh).
    const TriangulationCheck check = checkTriangulation(t, surface);
    CHECK(check.regularFraction >= 0.8);
    // As few singular points as the shapes need: the intersection shell's field turned around 800-1500 of them
    // (its vertex normals, fitted over rings across its ridges, turned past perpendicular) where now about 30.
    INFO(t.singularities.size() << " singular points, " << check.regularFraction << " of the interior vertices regular");
    CHECK(t.singularities.size() <= 80);
  }
}

TEST_CASE("global triangulation: planar to 1e-9 with every node of three faces and no face cut, where the surface allows") {
  // Surfaces without parabolic curves, where the lattice's stars are valid (Props. 4, 5): the pipeline needs no cut.
  for (const std::string name : {"catenoid", "hyperbolic-paraboloid"}) {
    CAPTURE(name);
    PipelineParams p;
    p.surface = name;
    p.method = TriangulationMethod::Global;
    p.faces = 800;
    const PipelineResult r = runPipeline(p);
    CHECK(r.solve.converged);
    CHECK(r.metrics.planarityMax <= 1e-9);
    CHECK(r.interiorFacesSplit == 0);
    CHECK(r.metrics.selfIntersectingCount == 0);
    CHECK(std::abs(double(r.hex.faceCount()) / 800 - 1) <= 0.1);
    // Nodes away from the boundary panels join three faces. (A boundary panel the solve leaves off planar is still
    // cut in two: at 800 faces one at a corner of the hyperbolic paraboloid's square.)
    std::vector<int> faces(r.hex.V.rows(), 0);
    std::vector<char> onPanel(r.hex.V.rows(), 0);
    for (int f = 0; f < r.hex.faceCount(); ++f)
      for (int k = 0; k < r.hex.faceSize(f); ++k) ++faces[r.hex.face(f)[k]], onPanel[r.hex.face(f)[k]] |= r.dual.boundaryFace[f];
    for (std::size_t v = 0; v < faces.size(); ++v)
      if (!onPanel[v]) CHECK(faces[v] == 3);
    CHECK(r.metrics.surfaceDistanceMax <= 0.002);
    CHECK(r.coverageGap <= 1);  // no hole: every sample of the surface within a mean edge of the panels
  }
  SECTION("a closed genus-0 upload: 12 pentagons' worth of singular points, closed P-Hex mesh") {
    const TriMesh egg = test::closedSurfaceOfGenus(0, 32);
    const PipelineParams p = globalUpload(egg, "egg.obj", 800);
    const PipelineResult r = runPipeline(p);
    CHECK(r.solve.converged);
    CHECK(r.interiorFacesSplit == 0);
    int sum = 0;
    for (int f = 0; f < r.hex.faceCount(); ++f) sum += 6 - r.hex.faceSize(f);
    CHECK(sum == 12);
    for (int f = 0; f < r.hex.faceCount(); ++f) CHECK(r.dual.boundaryFace[f] == 0);
    CHECK(r.coverageGap <= 1);
  }
}

TEST_CASE("global triangulation: on a parametric patch the boundary runs along the domain's sides") {
  // The field mesh of an analytic surface is its parameter lattice split k x k. The lattice's half-shifted rows
  // ended half a step in from the sides, so the field mesh's boundary zigzagged along two of them: the global
  // method took the saw teeth for the surface's edge (boundary vertices up to 0.08 in from the hyperbolic
  // paraboloid's side x = 1 at 2000 faces, the field along the teeth), and its boundary panels folded: 3 to 17
  // of them cut in two at 800-4000 faces, each cut making a node of four faces.
  const ParametricSurfacePtr s = makeSurface("hyperbolic-paraboloid");
  const Triangulation t = globalTriangulation(*s, atFaces(2000));
  const VertexRings rings = vertexRings(t.mesh);
  int boundary = 0;
  for (int v = 0; v < t.mesh.V.rows(); ++v) {
    if (rings.closed[v]) continue;
    ++boundary;
    CHECK(std::max(std::abs(t.mesh.V(v, 0)), std::abs(t.mesh.V(v, 1))) > 1 - 1e-9);  // on a side of [-1, 1]^2
  }
  CHECK(boundary > 100);
  PipelineParams p;
  p.surface = "hyperbolic-paraboloid";
  p.method = TriangulationMethod::Global;
  p.faces = 1500;
  const PipelineResult r = runPipeline(p);
  CHECK(r.solve.converged);
  CHECK(r.boundaryPanelsSplit == 0);
  CHECK(r.interiorFacesSplit == 0);
  CHECK(r.metrics.vertexValence.rbegin()->first <= 3);  // every node of three faces at most (two or one on the boundary)
}

TEST_CASE("global triangulation: the same mesh with one thread and with two") {
  const ParametricSurfacePtr torus = makeSurface("torus");
  setThreadCount(1);
  const Triangulation one = globalTriangulation(*torus, atFaces(500));
  setThreadCount(2);
  const Triangulation two = globalTriangulation(*torus, atFaces(500));
  setThreadCount(0);
  REQUIRE(one.mesh.V.rows() == two.mesh.V.rows());
  REQUIRE(one.mesh.F.rows() == two.mesh.F.rows());
  CHECK(one.mesh.V == two.mesh.V);
  CHECK(one.mesh.F == two.mesh.F);
}

TEST_CASE("global triangulation: options out of range, and a cell larger than the surface, are errors naming them") {
  const ParametricSurfacePtr torus = makeSurface("torus");
  auto fails = [&](GlobalOptions o, const std::string& word) {
    try {
      globalTriangulation(*torus, o);
      FAIL("no error for " << word);
    } catch (const Error& e) {
      CHECK(std::string(e.what()).find(word) != std::string::npos);
    }
  };
  GlobalOptions o = atFaces(500);
  o.anisotropy = 0.5;
  fails(o, "anisotropy");
  o = atFaces(500);
  o.alignment = -1;
  fails(o, "alignment");
  o = atFaces(500);
  o.curvatureSizing = std::nan("");
  fails(o, "curvatureSizing");
  o = GlobalOptions();
  fails(o, "cell");
  o.cell = 100;  // the torus spans 2.8
  fails(o, "larger than the surface");
  // The pipeline names them too, and still runs after.
  PipelineParams p;
  p.method = TriangulationMethod::Global;
  p.anisotropy = 9;
  CHECK_THROWS_AS(runPipeline(p), Error);
  p.anisotropy = 1.5;
  p.faces = 300;
  CHECK(runPipeline(p).hex.faceCount() > 0);
}

TEST_CASE("global triangulation: a part smaller than a cell is named in the notes, the rest tiled") {
  // A torus and, far from it, a tiny sphere: the sphere gets no panel at this cell.
  TriMesh big = test::closedSurfaceOfGenus(1, 28), small = test::closedSurfaceOfGenus(0, 8);
  small.V *= 0.02;
  small.V.rowwise() += Eigen::RowVector3d(5, 0, 0);
  TriMesh both;
  both.V.resize(big.V.rows() + small.V.rows(), 3);
  both.V << big.V, small.V;
  both.F.resize(big.F.rows() + small.F.rows(), 3);
  both.F << big.F, (small.F.array() + int(big.V.rows())).matrix();
  const MeshSurface surface(both, "two parts");
  const Triangulation t = globalTriangulation(surface, atFaces(400));
  bool named = false;
  for (const std::string& n : t.notes) named = named || n.find("too small for the cell") != std::string::npos;
  CHECK(named);
  CHECK(countEdges(t.mesh).boundary == 0);
  CHECK(test::eulerCharacteristic(t.mesh) == 0);

  // Through the pipeline: the part left bare is a gap of several panel edges, named in the notes with its place.
  const PipelineParams p = globalUpload(both, "two-parts.obj", 400);
  const PipelineResult r = runPipeline(p);
  CHECK(r.coverageGap > 3);
  std::string gapNote;
  for (const std::string& n : r.triangulation.notes)
    if (n.find("mean panel edges from the nearest panel") != std::string::npos) gapNote = n;
  INFO(gapNote);
  CHECK(gapNote.rfind("the surface near (5", 0) == 0);
}

TEST_CASE("pipeline: under auto, a closed upload whose Euler characteristic is not 0 goes global without trial lays") {
  // Genus 2 (V - F / 2 = -2): no conjugate network without singular points, so no trial lay is run. The torus
  // (genus 1) may carry one: its trial lays run, and it goes global only by what they find.
  for (int g : {2, 1}) {
    CAPTURE(g);
    PipelineParams p = globalUpload(test::closedSurfaceOfGenus(g, 32), "genus.obj", 600);
    p.method = TriangulationMethod::Auto;
    const PipelineResult r = runPipeline(p);
    const std::string notes = allNotes(r.triangulation);
    INFO(notes);
    const bool skipped = notes.find("closed with Euler characteristic") != std::string::npos;
    if (g == 2) {
      CHECK(r.method == TriangulationMethod::Global);
      CHECK(notes.find("closed with Euler characteristic -2 (genus 2)") != std::string::npos);
      CHECK(notes.find("trial lays") == std::string::npos);
    } else {
      CHECK_FALSE(skipped);
    }
  }
}

TEST_CASE("pipeline: where both duals' solves stall, the one that cut fewer faces is kept") {
  // PH-CPF's genus-3 model and Directional's concert-hall roof at 3000 faces: neither dual's solve reaches 1e-9.
  // Kept by planarity, the tangent dual's won, having cut 609 and 469 faces (60 % and 66 % hexagons); the Dupin
  // dual's cuts 4 and 6.
  for (const std::string file : {"phcpf_3holes_r.off", "directional_Concerthall.off"}) {
    CAPTURE(file);
    PipelineParams p;
    p.mesh = upload(file);
    p.faces = 3000;
    const PipelineResult r = runPipeline(p);
    CHECK(r.method == TriangulationMethod::Global);
    INFO(r.interiorFacesSplit << " interior faces cut of " << r.hex.faceCount());
    CHECK(r.interiorFacesSplit <= r.hex.faceCount() / 100);
  }
}

TEST_CASE("pipeline: a surface fully covered by its panels has no gap note") {
  PipelineParams p;
  p.surface = "torus";
  p.faces = 600;
  const PipelineResult r = runPipeline(p);
  CHECK(r.coverageGap < 0.5);
  for (const std::string& n : r.triangulation.notes) CHECK(n.find("from the nearest panel") == std::string::npos);
}

TEST_CASE("global triangulation: a needle triangle is tiled from a field mesh as fine as its area needs") {
  // 2.4 long and 0.06 wide: split by its median edge it took 14k field-mesh vertices and left most of it bare.
  TriMesh needle;
  needle.V.resize(3, 3);
  needle.V << 1, 0, 0, 1.0625, 0, 0, -1, 0, 1.125;
  needle.F.resize(1, 3);
  needle.F << 0, 1, 2;
  const MeshSurface surface(needle, "needle");
  const Triangulation t = globalTriangulation(surface, atFaces(32));
  REQUIRE(t.mesh.F.rows() > 0);
  const std::string& note = t.notes.at(0);
  const std::size_t at = note.find(" field-mesh vertices");
  REQUIRE(at != std::string::npos);
  const std::size_t from = note.rfind(' ', at - 1) + 1;
  const int vertices = std::stoi(note.substr(from, at - from));
  INFO(note);
  CHECK(vertices < 10000);
  CHECK(countEdges(t.mesh).boundary > 0);
}

namespace {
// A thinned upload's field mesh (global::thinned): about as many vertices as field-mesh edges of `edge` need, the
// upload's topology, boundary loops and orientation kept, every vertex on the surface.
void checkThinnedFieldMesh(const global::FieldMesh& m, const MeshSurface& surface, const TriMesh& upload, double edge) {
  const double diagonal = surface.bounds().diagonal().norm();
  const double wanted = 2 * upload.area() / (std::sqrt(3.0) * edge * edge);
  INFO(m.vertexCount() << " field-mesh vertices, " << wanted << " wanted, from " << upload.V.rows());
  CHECK(m.vertexCount() < 2 * wanted);
  CHECK(m.vertexCount() > 0.5 * wanted);
  TriMesh field;
  field.V = m.V;
  field.F = m.F;
  CHECK(test::eulerCharacteristic(field) == test::eulerCharacteristic(upload));
  CHECK(countEdges(field).bad == 0);
  CHECK(m.loops.size() == surface.boundaryLoops().size());
  // The boundary loops are the upload's: each of its boundary vertices is one of the field mesh's.
  std::set<std::array<double, 3>> points;
  for (int v = 0; v < m.vertexCount(); ++v) points.insert({m.V(v, 0), m.V(v, 1), m.V(v, 2)});
  for (const std::vector<int>& loop : surface.boundaryLoops())
    for (int v : loop) CHECK(points.count({upload.V(v, 0), upload.V(v, 1), upload.V(v, 2)}) == 1);
  // On the surface, and no triangle turned over against the surface's normal; where the remeshed upload was split,
  // but for a few points left on their triangle where their closest points folded over (global::untangleSplit), off
  // the surface by its sagitta.
  double off = 0, offSplit = 0;
  int turned = 0, offPoints = 0;
  for (int v = 0; v < m.vertexCount(); ++v) {
    const double d = (surface.closestPoint(m.point(v)).point - m.point(v)).norm();
    (d > 1e-9 * diagonal ? offSplit : off) = std::max(d > 1e-9 * diagonal ? offSplit : off, d);
    offPoints += d > 1e-9 * diagonal;
  }
  INFO(offPoints << " points off the surface, up to " << offSplit << " (field-mesh edge " << edge << ")");
  if (m.thinnedSplit == 1) CHECK(offPoints == 0);
  CHECK(offPoints <= m.vertexCount() / 1000);
  CHECK(offSplit <= 0.1 * m.thinnedSplit * edge);  // a sagitta of the remeshed triangles, not a point astray
  for (int f = 0; f < m.F.rows(); ++f) {
    const Vec3 a = m.point(m.F(f, 0)), b = m.point(m.F(f, 1)), c = m.point(m.F(f, 2));
    turned += (b - a).cross(c - a).dot(surface.closestPoint((a + b + c) / 3).normal) <= 0;
  }
  CHECK(off <= 1e-9 * diagonal);
  CHECK(turned == 0);
}
}  // namespace

// An upload far finer than the cell (a scan, a marching-cubes mesh) is thinned before its field mesh is laid.
TEST_CASE("global field: an upload far finer than the cell is thinned to the field mesh's density, its topology and boundary kept") {
  for (const std::string name : {"freeform", "torus"}) {
    CAPTURE(name);
    const auto analytic = makeSurface(name);
    const double diagonal = analytic->bounds().diagonal().norm();
    const TriMesh upload = latticeTriangulation(*analytic, diagonal / 150).mesh;
    const MeshSurface surface(upload, name);
    const double edge = diagonal / 30;
    const global::FieldMesh m = global::fieldMesh(surface, edge, 1.5, 0.25, nullptr);
    REQUIRE(m.thinnedFrom == upload.V.rows());
    CHECK(m.thinnedTo < upload.V.rows() / 10);
    CHECK(m.thinnedSplit == 1);
    checkThinnedFieldMesh(m, surface, upload, edge);
  }
}

// An uneven upload coarser than the field mesh (marching tetrahedra: long edges among short ones, which the bisection
// splits into far more vertices than the field needs) is remeshed at about its own edge, a whole number of field-mesh
// edges, and split as many times: not split edge by edge down to the field's (the generated genus 2 at 100k faces,
// 48k vertices remeshed to 526k, took 12.7 s of a 33 s run and half its 1.2 GB). At three field-mesh edges this one's
// closest points fold over at a concave edge of its facets: the points there stay on their remeshed triangles.
TEST_CASE("global field: an uneven upload coarser than the field mesh is remeshed at its own edge, then split") {
  const TriMesh upload = test::closedSurfaceOfGenus(2, 40);
  const MeshSurface surface(upload, "genus2.obj");
  const double median = upload.medianEdgeLength();
  for (const auto& [ratio, times] : {std::pair{2.0, 2}, std::pair{3.0, 3}, std::pair{1.2, 1}}) {
    CAPTURE(ratio);
    const double edge = median / ratio;
    const global::FieldMesh m = global::fieldMesh(surface, edge, 1.5, 0.25, nullptr);
    REQUIRE(m.thinnedFrom == upload.V.rows());
    CHECK(m.thinnedSplit == times);
    // Remeshed at about the upload's own density, not the field mesh's (at one field-mesh edge: ratio^2 as many).
    if (times > 1) CHECK(m.thinnedTo < 3 * upload.V.rows());
    checkThinnedFieldMesh(m, surface, upload, edge);
  }
}

// The same where the uneven upload was refined into a smooth surface (a coarse upload: MeshSurface::refined): the
// upload is remeshed with its points found on the refined surface, not split and bisected as the refinement left it
// (the generated genus 1 refined 3 x 3 at 100k faces: 1.9M field-mesh vertices, 3.6 times those it needs).
TEST_CASE("global field: an uneven upload refined smooth is remeshed on its refinement, not laid on it as refined") {
  const TriMesh upload = test::closedSurfaceOfGenus(1, 40);
  MeshSurface plain(upload, "genus1.obj");
  MeshSurface refined(plain.refined(3), "genus1.obj refined");
  refined.setRefinement(upload, 3);
  const double edge = upload.medianEdgeLength() / 3;
  const global::FieldMesh m = global::fieldMesh(refined, edge, 1.5, 0.25, nullptr);
  REQUIRE(m.thinnedFrom == upload.V.rows());  // the upload's vertices, not the refinement's
  CHECK(m.thinnedSplit >= 2);
  CHECK(m.thinnedTo < 3 * upload.V.rows());
  checkThinnedFieldMesh(m, refined, upload, edge);
  // Its points on the refined surface (checkThinnedFieldMesh: to 1e-9 of the diagonal), which lies off the upload's
  // facets: off them by more than round-off somewhere.
  double offFacets = 0;
  for (int v = 0; v < m.vertexCount(); ++v) offFacets = std::max(offFacets, (plain.closestPoint(m.point(v)).point - m.point(v)).norm());
  CHECK(offFacets > 1e-4 * edge);
}

// An uneven upload (marching tetrahedra: slivers among its triangles) or a noisy one (noisyUpload: a coarse torus,
// whose fits over two rings miss its vertices) is refined into a smooth surface from triangles of one cell on, a
// regular smooth one from 1.5 (pipeline.cpp, kCoarseUneven): at 1.2 cells the first two are refined, not the third.
TEST_CASE("pipeline: an uneven or noisy upload is refined smooth from triangles of one cell, a regular one from 1.5") {
  auto refinedAt = [](const TriMesh& upload, const std::string& name) {
    const bool noisy = noisyUpload(MeshSurface(upload));
    // Faces for triangles of about 1.2 cells: F triangles of mean area A / F against sqrt(3) / 2 cell^2 a face.
    PipelineParams p = globalUpload(upload, name, static_cast<int>(0.72 * double(upload.F.rows())));
    p.relay = false;
    const PipelineResult r = runPipeline(p);
    CHECK(r.solve.converged);
    bool refined = false;
    for (const std::string& note : r.triangulation.notes) {
      if (note.find("laid on a smooth surface") == std::string::npos) continue;
      refined = true;
      // The reason named where a noisy upload's triangles are under 1.5 cells: its facets.
      CHECK((note.find("a noisy mesh's facets kink the lay from one cell on") != std::string::npos) == noisy);
    }
    return refined;
  };
  CHECK(refinedAt(test::closedSurfaceOfGenus(1, 24), "genus1.obj"));
  const auto torus = makeSurface("torus");
  const TriMesh coarse = latticeTriangulation(*torus, 0.12).mesh, fine = latticeTriangulation(*torus, 0.05).mesh;
  REQUIRE(noisyUpload(MeshSurface(coarse)));
  REQUIRE_FALSE(noisyUpload(MeshSurface(fine)));
  REQUIRE_FALSE(noisyUpload(MeshSurface(test::closedSurfaceOfGenus(1, 24))));  // refined as uneven
  CHECK(refinedAt(coarse, "coarse-torus.obj"));
  CHECK_FALSE(refinedAt(fine, "torus.obj"));
}

// The generated genus 3 (marching tetrahedra, 59k vertices, its long edges bisected) at 1000 faces laid its field on 65
// field-mesh vertices a lattice point and stalled off planar (4e-2, with a gap of 4 panel edges); remeshed to the
// field's edge (7 a point), it reaches a P-Hex mesh.
TEST_CASE("pipeline: the generated genus 3 at 1000 faces, thinned for its field, reaches a P-Hex mesh") {
  const PipelineParams p = globalUpload(test::closedSurfaceOfGenus(3, 60), "genus3.obj", 1000);
  const PipelineResult r = runPipeline(p);
  bool thinned = false;
  for (const std::string& note : r.triangulation.notes) thinned |= note.find("remeshed to") != std::string::npos;
  CHECK(thinned);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.coverageGap <= 1);
  CHECK(std::abs(double(r.hex.faceCount()) / 1000 - 1) <= 0.1);
}

// The cell's integrable scale on a large coarse mesh (over kDirectScale vertices) is solved iteratively,
// preconditioned on aggregates of vertices: the same scale as the factorized equations give.
TEST_CASE("global field: the integrable scale solved iteratively equals the factorized solve") {
  const auto torus = makeSurface("torus");
  const global::FieldMesh m = global::fieldMesh(*torus, 0.04, 1.5, 0.25, nullptr);
  std::vector<global::Level> levels = global::hierarchy(m, std::vector<double>(m.vertexCount(), 1.0));
  const std::vector<std::vector<Vec3>> fields = global::orientationField(levels, 1.0, {}, nullptr);
  const std::vector<double> direct = global::integrableScale(m, fields[0], 1.0, std::numeric_limits<int>::max());
  const std::vector<double> iterative = global::integrableScale(m, fields[0], 1.0, 0);
  REQUIRE(direct.size() == iterative.size());
  double lo = direct[0], hi = direct[0], apart = 0;
  for (std::size_t v = 0; v < direct.size(); ++v) {
    lo = std::min(lo, direct[v]), hi = std::max(hi, direct[v]);
    apart = std::max(apart, std::abs(iterative[v] - direct[v]) / direct[v]);
  }
  CHECK(hi / lo > 1.2);  // the torus' cells do grow outwards: there is a scale to find
  CHECK(apart < 1e-6);
}

namespace {

// The half-edges of a triangle mesh, as (from, to).
std::set<std::pair<int, int>> directedEdges(const TriMesh& T) {
  std::set<std::pair<int, int>> directed;
  for (int f = 0; f < T.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) directed.insert({T.F(f, k), T.F(f, (k + 1) % 3)});
  return directed;
}

// A flat upload cut out of a triangular lattice of edge h (n x n, rows along x) along a square [-1, 1]^2 turned by
// `degrees`: its sides across the rows zigzag (all four, turned by 20 degrees), its boundary vertices' own edges
// turning by 30-60 degrees.
MeshSurface zigzagSquare(double h, int n, double degrees) {
  const double turn = degrees * 3.14159265358979 / 180;
  const Vec3 side0(std::cos(turn), std::sin(turn), 0), side1(-std::sin(turn), std::cos(turn), 0);
  auto inside = [&](const Vec3& p) {
    const double a = p.dot(side0), b = p.dot(side1);
    return std::abs(a) < 1.0 && std::abs(b) < 1.0;
  };
  TriMesh lattice;
  lattice.V.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      lattice.V.row(j * (n + 1) + i) << (i - n / 2) * h + 0.5 * h * (j % 2) - 0.25 * h, (j - n / 2) * h * std::sqrt(0.75), 0;
  std::vector<Eigen::Vector3i> kept;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      const Eigen::Vector3i t1 = j % 2 ? Eigen::Vector3i(a, d, c) : Eigen::Vector3i(a, b, c);
      const Eigen::Vector3i t2 = j % 2 ? Eigen::Vector3i(a, b, d) : Eigen::Vector3i(b, d, c);
      for (const Eigen::Vector3i& t : {t1, t2}) {
        const Vec3 centroid = (lattice.V.row(t(0)) + lattice.V.row(t(1)) + lattice.V.row(t(2))).transpose() / 3;
        if (inside(centroid)) kept.push_back(t);
      }
    }
  lattice.F.resize(static_cast<int>(kept.size()), 3);
  for (std::size_t f = 0; f < kept.size(); ++f) lattice.F.row(static_cast<int>(f)) = kept[f].transpose();
  return MeshSurface(cleanTriMesh(lattice, "zigzag.obj"), "zigzag square");
}

}  // namespace

// The field is held to the sides' direction, not the teeth's (taken from each vertex's two edges, up to 80 degrees
// off; over the window, 6).
TEST_CASE("global field: a boundary that zigzags at the scale of its triangles has the direction of its sides") {
  const double h = 0.1, turn = 20.0 * 3.14159265358979 / 180;
  const Vec3 side0(std::cos(turn), std::sin(turn), 0), side1(-std::sin(turn), std::cos(turn), 0);
  const MeshSurface surface = zigzagSquare(h, 40, 20);
  const global::FieldMesh m = global::fieldMesh(surface, h / 2.6, 1.5, 0.25, nullptr);
  REQUIRE(m.loops.size() == 1);
  int judged = 0;
  double worst = 0;
  for (int v : m.loops[0]) {
    const Vec3 p = m.point(v);
    const double a = p.dot(side0), b = p.dot(side1);
    // Half a side's length from the corners, where the window stops.
    if (std::min(std::abs(std::abs(a) - 1), std::abs(std::abs(b) - 1)) > 0.3 || std::min(std::abs(a), std::abs(b)) > 0.5)
      continue;
    const Vec3 side = std::abs(std::abs(a) - 1) < std::abs(std::abs(b) - 1) ? side1 : side0;
    worst = std::max(worst, std::acos(std::min(1.0, std::abs(m.boundaryTangent[v].dot(side)))) * 180 / 3.14159265358979);
    ++judged;
  }
  INFO(judged << " boundary vertices judged, the worst " << worst << " degrees off its side");
  CHECK(judged > 40);
  CHECK(worst < 8);
}

// The same kind of upload, not turned, its rows half a cell of the global lattice apart (0.54): each tooth of its sides
// across the rows turns 60 degrees within a third of a cell and was taken for a corner of the boundary, where a
// boundary site goes, so the sites stood half a cell apart (kBoundaryMin) and vertices next to the boundary had
// valence 7 (the bumps upload, whose rows end in such teeth, at 3000 faces: 62 of them, every other row along two
// sides). A corner turns over a cell on either side too. Here boundary edges 0.91 -> 0.98 of the cell on average,
// 16 -> 7 of 95 vertices next to the boundary not of valence 6.
TEST_CASE("global triangulation: a boundary that zigzags at the scale of its triangles has no corner at every tooth") {
  const MeshSurface surface = zigzagSquare(0.05, 80, 0);
  GlobalOptions options;
  options.cell = 0.08;
  const Triangulation t = globalTriangulation(surface, options);
  const VertexRings rings = vertexRings(t.mesh);
  double boundaryLength = 0;
  int boundaryEdges = 0;
  std::vector<char> boundary(t.mesh.V.rows(), 0);
  const std::set<std::pair<int, int>> directed = directedEdges(t.mesh);
  for (const auto& [a, b] : directed)
    if (!directed.count({b, a})) {
      boundaryLength += (t.mesh.V.row(a) - t.mesh.V.row(b)).norm();
      ++boundaryEdges;
      boundary[a] = boundary[b] = 1;
    }
  REQUIRE(boundaryEdges > 0);
  // The interior vertices next to the boundary, and how many of them are not of valence 6.
  int nextTo = 0, irregular = 0;
  for (int v = 0; v < t.mesh.V.rows(); ++v) {
    if (boundary[v] || !rings.closed[v]) continue;
    bool near = false;
    for (int f : rings.triangles[v])
      for (int k = 0; k < 3; ++k) near = near || boundary[t.mesh.F(f, k)];
    if (!near) continue;
    ++nextTo;
    irregular += rings.triangles[v].size() != 6;
  }
  INFO(boundaryEdges << " boundary edges of mean length " << boundaryLength / boundaryEdges << "; " << irregular << " of "
                     << nextTo << " vertices next to the boundary not of valence 6");
  CHECK(boundaryLength / boundaryEdges > 0.95 * options.cell);
  CHECK(irregular < 0.12 * nextTo);
}

// An upload refined k x k for a fine lay (MeshSurface::refined, setRefinement): the field mesh's coarse mesh, on
// which the cell's scale is solved, is the upload itself, and every field-mesh vertex's place is carried into
// the upload's triangle holding it.
TEST_CASE("global field: on an upload refined k x k the coarse mesh is the upload, places carried into its triangles") {
  const auto torus = makeSurface("torus");
  const TriMesh upload = latticeTriangulation(*torus, 0.25).mesh;
  MeshSurface plain(upload, "torus");
  MeshSurface refined(plain.refined(3), "torus refined");
  CHECK_THROWS_AS(refined.setRefinement(upload, 2), Error);  // not that refinement
  refined.setRefinement(upload, 3);
  const global::FieldMesh m = global::fieldMesh(refined, 0.03, 1.5, 0.25, nullptr);
  REQUIRE(m.coarse.V.rows() == upload.V.rows());
  REQUIRE(m.coarse.F.rows() == upload.F.rows());
  CHECK(m.vertexCount() > 9 * upload.V.rows());
  double size = 0;  // the upload's longest edge
  for (int f = 0; f < upload.F.rows(); ++f)
    for (int c = 0; c < 3; ++c) size = std::max(size, (upload.V.row(upload.F(f, c)) - upload.V.row(upload.F(f, (c + 1) % 3))).norm());
  int checked = 0;
  double worst = 0, outside = 0;
  for (int v = static_cast<int>(upload.V.rows()); v < m.vertexCount(); ++v) {
    const auto& [f, b] = m.where[v];
    REQUIRE(f >= 0);
    REQUIRE(f < upload.F.rows());
    outside = std::max({outside, -b.minCoeff(), std::abs(b.sum() - 1)});
    Vec3 flat = Vec3::Zero();
    for (int c = 0; c < 3; ++c) flat += b(c) * upload.V.row(upload.F(f, c)).transpose();
    worst = std::max(worst, (flat - m.point(v)).norm());
    ++checked;
  }
  CHECK(checked > 0);
  CHECK(outside < 1e-9);
  // The refined points lie on the jets' blend over the flat triangle: off it by a fraction of its size, where a
  // wrong triangle would be a triangle or more away.
  CHECK(worst < 0.2 * size);
}

namespace {

// The pipeline run without and with the edge flips against folds (PipelineParams::foldFlips).
std::pair<PipelineResult, PipelineResult> withoutAndWithFlips(PipelineParams p) {
  p.foldFlips = false;
  PipelineResult off = runPipeline(p);
  p.foldFlips = true;
  return {std::move(off), runPipeline(p)};
}

// Whether the triangulation's notes say that vertices were merged or edges flipped against folds.
bool flippedAgainstFolds(const PipelineResult& r) {
  for (const std::string& note : r.triangulation.notes)
    if (note.find("had faces crossing themselves (each such face would otherwise be cut") != std::string::npos) return true;
  return false;
}

// How many vertices the note says were merged along the flatter principal direction (0: no such note).
int mergedAgainstFolds(const PipelineResult& r) {
  for (const std::string& note : r.triangulation.notes)
    if (const std::size_t at = note.find(" merged with their neighbour along it"); at != std::string::npos) {
      std::size_t from = at;
      while (from > 0 && std::isdigit(static_cast<unsigned char>(note[from - 1]))) --from;
      return std::stoi(note.substr(from, at - from));
    }
  return 0;
}

// How many vertices the note says were moved in line with a neighbour along the flatter principal direction.
int alignedAgainstFolds(const PipelineResult& r) {
  for (const std::string& note : r.triangulation.notes)
    if (const std::size_t at = note.find(" vertices were moved in line with a neighbour"); at != std::string::npos) {
      std::size_t from = at;
      while (from > 0 && std::isdigit(static_cast<unsigned char>(note[from - 1]))) --from;
      return std::stoi(note.substr(from, at - from));
    }
  return 0;
}

}  // namespace

// Edge collapses and flips against the folds (on by default): on the torus at 3000 faces, whose global lattice
// folds faces only next to its parabolic circles, fewer faces are cut and fewer nodes join four faces (86 -> 24
// and 152 -> 41 when measured); the triangulation's notes say how many vertices were aligned, merged and edges flipped
// (once), the face count stays within 10 % of the one asked for, and every face stays planar and simple.
TEST_CASE("pipeline: the global method's edge flips against folds cut fewer faces on the torus") {
  CHECK(PipelineParams().foldFlips);
  PipelineParams p;
  p.surface = "torus";
  p.method = TriangulationMethod::Global;
  p.faces = 3000;
  p.anisotropy = 1.5;  // the case was chosen at the default before stop 28 (at 2 the torus folds fewer faces)
  p.alignment = 1;     // and the alignment's before stop 30
  const auto [off, on] = withoutAndWithFlips(p);
  auto fourOrMore = [](const PipelineResult& r) {
    int n = 0;
    for (const auto& [faces, count] : r.metrics.vertexValence) n += faces >= 4 ? count : 0;
    return n;
  };
  INFO("cut " << off.interiorFacesSplit << " -> " << on.interiorFacesSplit << ", nodes of 4+ " << fourOrMore(off) << " -> "
              << fourOrMore(on));
  CHECK(off.interiorFacesSplit > 20);  // there is something to mend
  CHECK(on.interiorFacesSplit < 0.75 * off.interiorFacesSplit);
  CHECK(fourOrMore(on) < fourOrMore(off));
  CHECK(flippedAgainstFolds(on));
  CHECK_FALSE(flippedAgainstFolds(off));
  CHECK(mergedAgainstFolds(on) > 0);
  // The first round moves vertices in line along the flatter direction before it merges (no valence changes).
  CHECK(alignedAgainstFolds(on) > 0);
  CHECK(std::abs(on.hex.faceCount() - 3000) <= 300);
  // The repairs after the flips are told in the flips' note, not as repairs of the lay once more per round.
  auto repairNotes = [](const PipelineResult& r) {
    int n = 0;
    for (const std::string& note : r.triangulation.notes) n += note.rfind("repaired ", 0) == 0;
    return n;
  };
  CHECK(repairNotes(on) == repairNotes(off));
  CHECK(repairNotes(on) <= 1);
  CHECK(on.metrics.planarityMax <= 1e-9);
  CHECK(on.metrics.selfIntersectingCount == 0);
}

// A coarse upload folds a fifth or more of its faces: flips there traded hexagons for nothing (the car at 3000
// faces: 94 % -> 54 %), so none are made and the result is the one without them.
TEST_CASE("pipeline: no edge flips against folds on a coarse upload that folds more than a few faces") {
  PipelineParams p;
  p.mesh = upload("phcpf_car_r.off");
  p.method = TriangulationMethod::Global;
  p.faces = 1000;
  p.relay = false;  // one lay (where no lay reaches a P-Hex mesh, the run lays again with the rounds on more folds)
  const auto [off, on] = withoutAndWithFlips(p);
  CHECK_FALSE(flippedAgainstFolds(on));
  CHECK(on.hex.faceCount() == off.hex.faceCount());
  CHECK(on.hex.V.rows() == off.hex.V.rows());
}

// The car folds about a fifth of its faces next to its near-parabolic parts: within the default share of cuts (a
// tenth) no solve of its first lay reaches the tolerance and the mesh is left off planar (1.1e-2 at 1000 faces, laid
// on its refinement, 2 faces cut). With a share of 0.3 the solve with folds allowed, every folded face cut, is kept:
// planar, none crossing itself, at the price of 150 faces cut (two nodes of four each); the default run's notes say
// which share keeps it. Out of [0, 1] the share is an error naming it.
TEST_CASE("pipeline: a larger cut share gives a planar mesh where the default leaves a coarse upload off planar") {
  PipelineParams p;
  p.mesh = upload("phcpf_car_r.off");
  p.faces = 1000;
  p.relay = false;  // its first lay (laid again, the rounds against folds on more folds make it planar: see below)
  const PipelineResult plain = runPipeline(p);
  CHECK_FALSE(plain.solve.converged);
  CHECK(static_cast<double>(plain.interiorFacesSplit) <= 0.1 * plain.hex.faceCount());
  // Its notes name the share that would keep the planar mesh.
  CHECK(std::any_of(plain.triangulation.notes.begin(), plain.triangulation.notes.end(),
                    [](const std::string& n) { return n.find("with cutShare 0.") != std::string::npos; }));
  p.cutShare = 0.3;
  const PipelineResult cut = runPipeline(p);
  INFO("cut " << cut.interiorFacesSplit << " of " << cut.hex.faceCount() << " planarity " << cut.metrics.planarityMax);
  CHECK(cut.solve.converged);
  CHECK(cut.metrics.planarityMax <= 1e-9);
  CHECK(cut.metrics.selfIntersectingCount == 0);
  CHECK(cut.interiorFacesSplit > plain.interiorFacesSplit);
  CHECK(static_cast<double>(cut.interiorFacesSplit) <= 0.3 * (cut.hex.faceCount() - cut.interiorFacesSplit));
  for (double bad : {-0.1, 1.5, std::nan("")}) {
    p.cutShare = bad;
    try {
      runPipeline(p);
      FAIL("no error for cutShare " << bad);
    } catch (const Error& e) {
      CHECK(std::string(e.what()).find("cutShare") != std::string::npos);
    }
  }
}

namespace {
// The botanic-garden bubble laid by the global method at `faces`, the alignment, anisotropy and fairness given.
// (The cases below were chosen, by scans, on the lattice as the position field leaves it: they lay it so,
// `cancelDislocations` off, to test their mechanisms where those act.)
// The anisotropy the bubble's cases below were chosen at (the default before stop 28; at 2 its lay folds elsewhere).
constexpr double kBubbleAnisotropy = 1.5;
// And the alignment (the default before stop 30, 3 since).
constexpr double kBubbleAlignment = 1.0;
PipelineResult bubbleGlobal(int faces, double alignment = kBubbleAlignment,
                            double anisotropy = PipelineParams().anisotropy, double fairness = PipelineParams().fairness,
                            bool cancelDislocations = false) {
  PipelineParams p;
  p.cancelDislocations = cancelDislocations;
  p.mesh = upload("directional_botanic-garden-bubble.off");
  p.method = TriangulationMethod::Global;
  p.faces = faces;
  p.alignment = alignment;
  p.anisotropy = anisotropy;
  p.fairness = fairness;
  p.relay = false;  // one lay: the tests below look at what its solve does (no second lay, no trial lays)
  p.foldAlignRounds = 1;  // the cases below were chosen when the rounds against folds aligned in the first alone
  return runPipeline(p);
}
// Converged, planar to the tolerance, no face crossing itself, and every node within the distance goal.
void checkSolvedNear(const PipelineResult& r) {
  INFO("cut " << r.interiorFacesSplit << ", farthest node " << r.solve.surfaceDistanceAfter);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.solve.surfaceDistanceAfter <= kSurfaceDistanceGoal);
}
}  // namespace

// Where the guarded solve stalls and converges only by cutting every face left off planar, round after round, the
// unguarded solve cuts only the faces that fold: the botanic-garden bubble at 2500 faces (alignment 0.999,
// anisotropy 1.499) cuts 23 interior faces unguarded, its farthest node 0.08 % of the diagonal off (the goal 0.2 %).
// That is without the solver's fairness; with it (the default) none is cut. (The test stood at 5000 faces, alignment
// 0.999, anisotropy 1.497 until the rounds against folds solved only around their changes: there the guarded solve
// now converges with few cuts; then at 2500 faces until those rounds took folded boundary panels too, at 4500 until
// they flipped fans of two, and at 3000 (alignment 1, anisotropy 1.5) until they went on past a round that gained
// too little. Of 28 configurations scanned then, 2000-5000 faces, anisotropy 1.499 and 1.5, alignment 0.999 and 1,
// six keep the unguarded solve, five of them within the distance goal.)
TEST_CASE("pipeline: a global solve that cut far more faces than its dual folds is solved unguarded as well") {
  const PipelineResult r = bubbleGlobal(2500, 0.999, 1.499, 0.0);
  checkSolvedNear(r);
  CHECK(r.foldsAllowed);
  CHECK(r.interiorFacesSplit < 60);
  const PipelineResult fair = bubbleGlobal(2500, 0.999, 1.499);
  checkSolvedNear(fair);
  CHECK(fair.interiorFacesSplit < r.interiorFacesSplit);
}

// The unguarded solve can leave a node far off where three planes pass through nearly one line (the surface fit
// cannot move such a node): put back on the surface and solved again, the bubble at 3500 faces (anisotropy 1.499,
// without the fairness) ends 0.10 % off with 2 faces cut, unguarded (the result does not say how many nodes were put
// back: the test asserts the unguarded solve kept within the goal).
// On the 80 bubbles of 1500-6000 faces at anisotropies 1.497-1.5 (alignment 0.999 and 1) so solved (the rounds
// against folds flipping folded boundary fans of three), 13 of the 15 kept unguarded had far nodes put back. (The test stood at 4000 faces, anisotropy 1.499, until the rounds against
// folds took folded boundary panels too; at 4500 faces, anisotropy 1.498, until they solved only around their
// changes, before that at 4000 faces, until their merges chose among neighbours about as well along the flatter
// direction, and at 3000 faces until their first round aligned before it merged; at anisotropy 1.5 until the bubble
// was refined by the smooth blend of its jets, MeshSurface::Blend: of 60 configurations scanned then, 1500-6000
// faces, anisotropy 1.498-1.5, alignment 0.999 and 1, nine keep the unguarded solve, all within the distance goal.)
TEST_CASE("pipeline: far nodes of the unguarded solve are put back on the surface and solved again") {
  const PipelineResult r = bubbleGlobal(3500, kBubbleAlignment, 1.499, 0.0);
  checkSolvedNear(r);
  CHECK(r.foldsAllowed);
  CHECK(r.interiorFacesSplit < 30);
}

// The solve with folds allowed folds the fan of a boundary vertex here and there (a middle triangle's point past the
// vertex), and such a panel was cut in two after the solve: a node of four faces. The rounds against folds now flip
// an edge of such a fan as they do inside: the bubble laid once at 1000, 2000 and 3000 faces cut 5, 4 and 2 boundary
// panels before, 2, 1 and 1 now, its hexagons within a point.
TEST_CASE("pipeline: the rounds against folds mend folded boundary panels, so fewer are cut") {
  int panels = 0;
  for (int faces : {1000, 2000, 3000}) {
    const PipelineResult r = bubbleGlobal(faces, kBubbleAlignment, kBubbleAnisotropy);
    INFO(faces << " faces: " << r.boundaryPanelsSplit << " boundary panels and " << r.interiorFacesSplit << " interior faces cut");
    checkSolvedNear(r);
    CHECK(r.interiorFacesSplit == 0);
    CHECK(r.boundaryPanelsSplit <= 2);
    CHECK(r.interiorHexagonFraction >= 0.92);
    panels += r.boundaryPanelsSplit;
  }
  CHECK(panels <= 5);
}

// A folded boundary fan of two whose flip would leave a sliver (its vertex nearly on the chord between its two
// boundary neighbours) had its panel cut: the bubble laid once at 2000 faces cut one. Where such panels are left
// when the rounds against folds are done, one round more drops those vertices alone (kDropEven): none cut now, and
// its boundary nodes stay on the curve. On a boundary along asymptotic lines (the helicoid's helices and end
// rulings, whose panels fold all along them) no vertex is dropped.
TEST_CASE("pipeline: the rounds against folds drop a folded boundary vertex nearly on its neighbours' chord") {
  auto dropNote = [](const PipelineResult& r) {
    for (const std::string& n : r.triangulation.notes)
      if (n.find("nearly on the chord between their neighbours dropped") != std::string::npos) return true;
    return false;
  };
  const PipelineResult r = bubbleGlobal(2000, kBubbleAlignment, kBubbleAnisotropy);
  checkSolvedNear(r);
  CHECK(dropNote(r));
  CHECK(r.boundaryPanelsSplit == 0);
  CHECK(r.interiorFacesSplit == 0);
  CHECK(r.boundaryOffset.max <= 0.5);
  PipelineParams p;
  p.surface = "helicoid";
  p.faces = 2000;
  const PipelineResult helicoid = runPipeline(p);
  CHECK(helicoid.method == TriangulationMethod::Global);
  CHECK_FALSE(dropNote(helicoid));
}

// The rounds against folds stopped at the first round that gained too little. On the torus laid globally at 2000 faces
// (laid once) the round after the best folded a few faces again, the rounds ended there and the 4 folds left were
// cut: 7 nodes of four faces or more. Going on from that round once (kFoldPatience), the next one mends them: no face cut, every
// node of three faces.
TEST_CASE("pipeline: the rounds against folds go on once past a round that gains too little") {
  PipelineParams p;
  p.surface = "torus";
  p.method = TriangulationMethod::Global;
  p.faces = 2000;
  p.relay = false;  // that lay (no trial lays)
  const PipelineResult r = runPipeline(p);
  REQUIRE(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.interiorFacesSplit == 0);
  CHECK(r.metrics.vertexValence.rbegin()->first == 3);  // closed: every node of three faces
  CHECK(r.interiorHexagonFraction >= 0.93);
}

// A converged mesh can keep a few nodes far off where three planes pass through nearly one line: the bubble at
// 1000 faces ended 0.42 % of the diagonal off (the goal 0.2 %). Put back on the surface and solved again, 0.10 %.
TEST_CASE("pipeline: a converged global mesh with nodes past the distance goal has them put back and solved again") {
  const PipelineResult r = bubbleGlobal(1000);
  checkSolvedNear(r);
  CHECK(r.metrics.surfaceDistanceMax <= kSurfaceDistanceGoal);
  CHECK(r.interiorFacesSplit <= 10);
}

// The first solve with folds allowed can stand but for a node past the distance goal: the bubble at 2000 faces, 0.29 %
// of the diagonal off (three planes through nearly one line). Put back on the surface and solved again as a repair
// (from a thousandth of the run's lambda, without the fairness) it stands at 0.08 % with no face more cut. Solved
// from there with the run's lambda and fairness it stalled, and the guarded solves after it ended with the mesh
// 0.29 % off.
TEST_CASE("pipeline: the first solve with folds allowed stands once its node past the distance goal is put back") {
  const PipelineResult r = bubbleGlobal(2000);
  checkSolvedNear(r);
  CHECK(r.foldsAllowed);
  CHECK(r.interiorFacesSplit <= 2);
}

// A strip whose boundary runs along asymptotic lines (an uploaded helicoid: its helices and end rulings): no
// planar boundary panel there without folding, and the guarded solve cut 179 of them in two (a node of four faces
// each) with one interior face. Where over a quarter of the boundary panels are cut, the solve runs unguarded as
// well, and the result whose cuts make fewer nodes of four is kept: 103 cut.
TEST_CASE("pipeline: a quarter of the boundary panels cut sends the global solve unguarded as well") {
  const ParametricSurfacePtr helicoid = makeSurface("helicoid");
  Triangulation strip = latticeTriangulation(*helicoid, cellForFaceCount(*helicoid, 6000));
  repairStars(strip, *helicoid);
  const PipelineResult r = runPipeline(globalUpload(strip.mesh, "helicoid.obj", 2000));
  INFO(r.interiorFacesSplit << " interior faces and " << r.boundaryPanelsSplit << " boundary panels cut");
  checkSolvedNear(r);
  CHECK(r.foldsAllowed);
  CHECK(2 * r.interiorFacesSplit + r.boundaryPanelsSplit < 160);
}

// Near a parabolic curve the flatter curvature decides which triangles are valid (Props. 4, 5), and the default
// metric (bounded at 1.5, regularized by a quarter of the median curvature) follows too little of it. The Dupin
// cyclide laid globally at 2000 faces without the solver's fairness: the first lay stalls; laid again following the
// Dupin metric to 2.5 with a floor of 0.05, it converges (26 faces cut when measured). (A shallow dome, radii 1 and
// 30, was this test's case until its boundary was left free where the field holds to the flatter direction: its first
// lay converges now. So does the cyclide's with the field held to the principal directions, PipelineParams::
// principalTrial, 10 faces cut: the case is laid along the field smoothest in the Dupin metric.)
TEST_CASE("pipeline: the global method lays a surface again following the Dupin metric further where the first lay stalls") {
  CHECK(PipelineParams().relay);
  PipelineParams p;
  p.surface = "cyclide";
  p.method = TriangulationMethod::Global;
  p.faces = 2000;
  p.fairness = 0;
  p.principalTrial = false;
  const PipelineResult r = runPipeline(p);
  INFO(r.interiorFacesSplit << " interior faces and " << r.boundaryPanelsSplit << " boundary panels cut");
  CHECK(r.relay.tried);
  CHECK(r.relay.kept);
  CHECK_FALSE(r.relay.firstReached);
  CHECK(r.relay.anisotropy == kRelayAnisotropy);
  CHECK(r.relay.curvatureFloor == kRelayFloor);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.farNodes == 0);
  CHECK(2 * r.interiorFacesSplit + r.boundaryPanelsSplit <= kRelayNodesOfFour * r.metrics.faceCount);
  CHECK(std::any_of(r.triangulation.notes.begin(), r.triangulation.notes.end(), [](const std::string& n) {
    return n.find("laid again following the Dupin metric") != std::string::npos;
  }));
  // The stages' time is both lays', each stage once.
  double sum = 0;
  std::set<std::string> stages;
  for (const StageTiming& t : r.timings) sum += t.milliseconds, stages.insert(t.stage);
  CHECK(stages.size() == r.timings.size());
  CHECK(sum <= r.totalMilliseconds);
  // Without the second lay the first stands, unconverged.
  p.relay = false;
  const PipelineResult once = runPipeline(p);
  CHECK_FALSE(once.relay.tried);
  CHECK_FALSE(once.solve.converged);
}

// The Dupin cyclide laid globally at 1000 faces converges with 10 interior faces cut (20 nodes of four faces, 2 %
// of its faces: no second lay); its lattice for 970 faces falls otherwise next to the parabolic circles and
// converges with none cut.
TEST_CASE("pipeline: where the global lay's cuts leave nodes of four faces, trial lays for other face counts are kept if better") {
  PipelineParams p;
  p.surface = "cyclide";
  p.method = TriangulationMethod::Global;
  p.faces = 1000;
  p.relay = false;
  p.cancelDislocations = false;  // the case was chosen on the lattice as the position field leaves it
  p.anisotropy = 1.5;            // and at the default before stop 28
  const PipelineResult once = runPipeline(p);
  const int onceFour = 2 * once.interiorFacesSplit + once.boundaryPanelsSplit;
  REQUIRE(onceFour > 0);
  CHECK(once.relay.trials == 0);
  p.relay = true;
  const PipelineResult r = runPipeline(p);
  const int four = 2 * r.interiorFacesSplit + r.boundaryPanelsSplit;
  const std::string notes = allNotes(r.triangulation);
  INFO(notes);
  CHECK_FALSE(r.relay.tried);  // not the second lay: its cuts stayed under kRelayNodesOfFour
  CHECK(r.relay.trials >= 1);
  CHECK(r.relay.trials <= static_cast<int>(std::size(kTrialShares)));
  CHECK(r.relay.trialNodesOfFour == onceFour);
  CHECK((r.relay.trialShare == kTrialShares[0] || r.relay.trialShare == kTrialShares[1]));
  CHECK(four < onceFour);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(std::abs(r.metrics.faceCount - p.faces) <= 0.1 * p.faces);
  CHECK(notes.find("laid again as trials") != std::string::npos);
  CHECK(r.totalMilliseconds >= once.totalMilliseconds * 0.5);
  // Over kTrialMostFaces faces none runs where the cuts' nodes of four are few (each lay there costs what the goals'
  // time allows for one), and over kTrialLargeFaces none at all.
  p.faces = kTrialMostFaces + 1000;
  p.relay = true;
  CHECK(runPipeline(p).relay.trials == 0);
  p.faces = kTrialLargeFaces + 1000;
  CHECK(runPipeline(p).relay.trials == 0);
}

// Between kTrialMostFaces and kTrialLargeFaces faces the trial lays run where the cuts' nodes of four are more than
// kTrialLargeShare of the faces: PH-CPF's car (tests/data, CC BY-SA 4.0) at 8000 faces cuts 27 interior faces laid
// once (54 nodes of four), its trial for 7760 faces 8; six_s0 at 6000 faces cuts 1 interior face and 2 boundary panels
// (4 nodes of four, under the share) and is laid once.
TEST_CASE("pipeline: over kTrialMostFaces faces, trial lays run where the cuts' nodes of four are many") {
  PipelineParams p;
  p.mesh = upload("phcpf_car_r.off");
  p.faces = 8000;
  const PipelineResult car = runPipeline(p);
  const std::string notes = allNotes(car.triangulation);
  INFO(notes);
  REQUIRE(car.relay.trialNodesOfFour > kTrialLargeShare * p.faces);
  CHECK(car.relay.trials >= 1);
  CHECK(2 * car.interiorFacesSplit + car.boundaryPanelsSplit < car.relay.trialNodesOfFour);
  CHECK(car.solve.converged);
  CHECK(car.metrics.planarityMax <= 1e-9);
  CHECK(std::abs(car.metrics.faceCount - p.faces) <= 0.1 * p.faces);
  p.mesh = upload("phcpf_six_s0.off");
  p.faces = 6000;
  const PipelineResult six = runPipeline(p);
  const int four = 2 * six.interiorFacesSplit + six.boundaryPanelsSplit;
  CHECK(four > 0);
  CHECK(four <= kTrialLargeShare * p.faces);
  CHECK(six.relay.trials == 0);
}

// A noisy upload's first lay leaves out the repairs that trade hexagons for cuts on such meshes (the fairness, the
// changes at folded boundary panels, the dislocation glides) and is not laid again following the Dupin metric; where
// it falls short it is laid again with them, as a smooth upload is, and the first stands where that falls short
// too: the car at 700 faces stalls either way (issue 31; laid on its facets, which are under a cell: at 1000 faces,
// since noisy uploads are refined from one cell, on its refinement, which reaches a P-Hex mesh). (Without the rounds
// against folds, which it folds too many faces for: they would run only in the lay of the test below, where no lay
// reached a P-Hex mesh.)
TEST_CASE("pipeline: a noisy upload that falls short is laid again with the repairs, the first kept where that falls short too") {
  PipelineParams p;
  p.mesh = upload("phcpf_car_r.off");
  p.method = TriangulationMethod::Global;
  p.faces = 700;
  p.foldFlips = false;
  const PipelineResult r = runPipeline(p);
  REQUIRE_FALSE(r.solve.converged);  // the car stalls (issue 31)
  CHECK(r.relay.noisyRepairs);
  CHECK_FALSE(r.relay.noisyRepairsKept);
  const std::string notes = allNotes(r.triangulation);
  INFO(notes);
  CHECK(notes.find("laid again with them, as a smooth upload is, it did not reach one either: the first is kept") !=
        std::string::npos);
  p.relay = false;
  const PipelineResult once = runPipeline(p);
  CHECK_FALSE(once.relay.noisyRepairs);
  CHECK_FALSE(once.relay.tried);
  REQUIRE(once.hex.V.rows() == r.hex.V.rows());
  CHECK(once.hex.V == r.hex.V);  // the first lay, kept
  CHECK(r.totalMilliseconds > once.totalMilliseconds);  // both lays' time
}

// Where no lay reached a P-Hex mesh (the car at 700 faces, laid on its facets, folds a tenth of its faces in the solve
// with folds allowed, over kFoldFlipShare, so they were cut, over the cut share: its first lay, the relay and the noisy
// repairs' lay stall), all is laid again with the rounds against folds run up to kFoldRescueShare: planar, 2 faces cut
// where it measured (issue 31: the price of planar faces there). (The case was the car at 1000 faces until noisy
// uploads were refined from one cell: its refinement is the case of the test below.)
TEST_CASE("pipeline: where no lay reaches a P-Hex mesh, all is laid again with the rounds against folds on more folds") {
  PipelineParams p;
  p.mesh = upload("phcpf_car_r.off");
  p.method = TriangulationMethod::Global;
  p.faces = 700;
  const PipelineResult r = runPipeline(p);
  const std::string notes = allNotes(r.triangulation);
  INFO(notes);
  CHECK(notes.find("no lay reached a P-Hex mesh") != std::string::npos);
  CHECK(notes.find("it reached one (") != std::string::npos);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.farNodes == 0);
  CHECK(std::abs(r.metrics.faceCount - p.faces) <= 0.1 * p.faces);
  // The same as laying with that share at once (no further lay then).
  p.foldRoundsShare = kFoldRescueShare;
  const PipelineResult direct = runPipeline(p);
  REQUIRE(direct.hex.V.rows() == r.hex.V.rows());
  CHECK(direct.hex.V == r.hex.V);
  CHECK(r.totalMilliseconds > direct.totalMilliseconds);  // the lays that stalled, counted
  // The first lay alone stalls (no lay again without the relay).
  p.foldRoundsShare = kFoldFlipShare;
  p.relay = false;
  CHECK_FALSE(runPipeline(p).solve.converged);
  // The two settings (PipelineParams, not options of the command line or the library) out of range are named.
  for (double bad : {-0.1, 1.5, std::nan("")}) {
    p.foldRoundsShare = bad;
    CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("foldRoundsShare"));
  }
  p.foldRoundsShare = kFoldFlipShare;
  for (int bad : {-1, 101}) {
    p.foldAlignRounds = bad;
    CHECK_THROWS_WITH(runPipeline(p), Catch::Contains("foldAlignRounds"));
  }
  p.foldAlignRounds = kAlignRounds;
  CHECK_NOTHROW(validate(p));
}

// Where the lay kept reached a P-Hex mesh only with nodes of four faces from cuts at over kRelayNodesOfFour of its
// faces, the rescue runs too and is kept where it has fewer: the car at 1000 faces under auto (laid on its
// refinement; its relay reached one with 184 nodes of four where it measured, the rescue with none).
TEST_CASE("pipeline: where the lay kept cut many faces, all is laid again with the rounds against folds on more folds") {
  PipelineParams p;
  p.mesh = upload("phcpf_car_r.off");
  p.faces = 1000;
  const PipelineResult r = runPipeline(p);
  const std::string notes = allNotes(r.triangulation);
  INFO(notes);
  const std::string said = "the lay kept reached a P-Hex mesh only with ";
  const std::size_t at = notes.find(said);
  REQUIRE(at != std::string::npos);
  const int before = std::stoi(notes.substr(at + said.size()));
  CHECK(before > kRelayNodesOfFour * p.faces);
  CHECK(notes.find("nodes of four faces from cuts): kept") != std::string::npos);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(2 * r.interiorFacesSplit + r.boundaryPanelsSplit < before);
  CHECK(std::abs(r.metrics.faceCount - p.faces) <= 0.1 * p.faces);
}

// Where auto chose the global method for an upload, the pipeline's re-lays (relay, trial lays, the noisy repairs' lay)
// lay globally at once and say why as the first lay did (PipelineParams::globalBecause): PH-CPF's intersection shell at
// 1500 faces keeps a re-lay, whose own choice (Method 2's trial lays again, a second and more each lay) had found 2
// systems of rows where the first lay's found 3.
TEST_CASE("pipeline: re-lays of an upload auto tiled globally do not choose the method again") {
  PipelineParams p;
  p.mesh = upload("phcpf_intersection.off");
  p.faces = 1500;
  p.relay = false;
  const PipelineResult first = runPipeline(p);
  REQUIRE(first.method == TriangulationMethod::Global);
  REQUIRE_FALSE(first.globalBecause.empty());
  CHECK(first.triangulation.notes.at(0).find(first.globalBecause) != std::string::npos);
  p.relay = true;
  const PipelineResult r = runPipeline(p);
  REQUIRE((r.relay.noisyRepairsKept || r.relay.kept || r.relay.trialShare > 0));  // a re-lay is kept
  CHECK(r.method == TriangulationMethod::Global);
  CHECK(r.globalBecause == first.globalBecause);
  CHECK(r.triangulation.notes.at(0).find(first.globalBecause) != std::string::npos);
  // A method asked for explicitly has no reason to give.
  p.method = TriangulationMethod::Global;
  p.relay = false;
  CHECK(runPipeline(p).globalBecause.empty());
}

// PH-CPF's intersection shell at 1000 faces (laid on its refinement, which is noisy too): its first lay stalls short
// of the tolerance; laid again with the repairs it reaches a P-Hex mesh with no face cut (measured: 83 % hexagons).
// (The case was the open annulus six_s0 at 1500 faces until noisy uploads were refined from one cell: its refinement
// is smooth, laid with the repairs at once.)
TEST_CASE("pipeline: a noisy shared model reaches a P-Hex mesh laid again with the repairs of a smooth upload") {
  PipelineParams p;
  p.mesh = upload("phcpf_intersection.off");
  p.faces = 1000;
  const PipelineResult r = runPipeline(p);
  CHECK(r.method == TriangulationMethod::Global);
  CHECK(r.relay.noisyRepairs);
  CHECK(r.relay.noisyRepairsKept);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.metrics.selfIntersectingCount == 0);
  CHECK(r.farNodes == 0);
  CHECK(std::abs(r.metrics.faceCount - p.faces) <= 0.1 * p.faces);
  CHECK(2 * r.interiorFacesSplit + r.boundaryPanelsSplit <= r.metrics.faceCount / 50);
  // The same lay with the repairs asked from the start, without the relay: only the first lay, which stalls or
  // cuts faces making nodes of four at over 5 % of its faces.
  p.relay = false;
  const PipelineResult once = runPipeline(p);
  CHECK((!once.solve.converged || 2 * once.interiorFacesSplit + once.boundaryPanelsSplit > once.metrics.faceCount / 20));
  p.noisyRepairs = true;
  const PipelineResult repaired = runPipeline(p);
  CHECK(repaired.solve.converged);
  CHECK_FALSE(repaired.relay.noisyRepairs);  // nothing laid again
}

// A noisy upload's sharpest turns are its faceting's, not a crease: PH-CPF's car (77 edges turning by over 30
// degrees, up to 48, against a median of 5) is refined into a smooth surface where its triangles are over 1.5 cells,
// as a clean coarse upload is; a clean mesh with a crease is not (tests of the crease note in pipeline.cpp).
TEST_CASE("pipeline: a noisy upload whose facets turn sharply is refined, not taken for creased") {
  PipelineParams p;
  p.mesh = upload("phcpf_car_r.off");
  p.method = TriangulationMethod::Global;
  p.faces = 3000;
  p.relay = false;
  const PipelineResult r = runPipeline(p);
  const std::string notes = allNotes(r.triangulation);
  INFO(notes);
  CHECK(notes.find("laid on a smooth surface near its 750 vertices") != std::string::npos);
  CHECK(notes.find("too coarse to be refined") == std::string::npos);
}

TEST_CASE("global triangulation: the curvature floor out of its range is named") {
  const ParametricSurfacePtr torus = makeSurface("torus");
  for (const double floor : {0.0, 0.009, 1.01, std::nan("")}) {
    GlobalOptions o;
    o.faces = 300;
    o.curvatureFloor = floor;
    try {
      globalTriangulation(*torus, o);
      FAIL("no error for " << floor);
    } catch (const Error& e) {
      CHECK(std::string(e.what()).find("curvatureFloor") != std::string::npos);
    }
  }
  PipelineParams p;
  p.method = TriangulationMethod::Global;
  p.faces = 300;
  p.curvatureFloor = 2;
  CHECK_THROWS_AS(runPipeline(p), Error);
  // A smaller floor follows a near-developable surface's indicatrix further: its field mesh's frames are longer.
  const ParametricSurfacePtr dome = makeSurface("elliptic-paraboloid", {{"ra", 1.0}, {"rb", 30.0}});
  const global::FieldMesh loose = global::fieldMesh(*dome, 0.05, 8, 0.25, nullptr);
  const global::FieldMesh tight = global::fieldMesh(*dome, 0.05, 8, 0.05, nullptr);
  REQUIRE(loose.frame.size() == tight.frame.size());
  double looseAspect = 0, tightAspect = 0;
  for (std::size_t v = 0; v < loose.frame.size(); ++v)
    looseAspect += 1 / (loose.frame[v].sigma * loose.frame[v].sigma), tightAspect += 1 / (tight.frame[v].sigma * tight.frame[v].sigma);
  CHECK(tightAspect > 1.3 * looseAspect);
}

// The local solver's fairness (PipelineParams::fairness, on by default for the global method): interior nodes
// pulled towards their neighbours' mean while lambda fades, so the planes follow a smooth mesh instead of folding.
// The bubble at 1000 faces cut 5 interior faces and 26 boundary panels without it (measured), none with it; on a
// noisy upload (the car) it is not applied: the same mesh either way.
TEST_CASE("pipeline: the solver's fairness cuts fewer faces on a clean upload, and leaves a noisy one alone") {
  CHECK(PipelineParams().fairness > 0);
  const PipelineResult plain = bubbleGlobal(1000, kBubbleAlignment, PipelineParams().anisotropy, 0.0);
  const PipelineResult fair = bubbleGlobal(1000);
  INFO("cut without " << plain.interiorFacesSplit << "+" << plain.boundaryPanelsSplit << ", with "
                      << fair.interiorFacesSplit << "+" << fair.boundaryPanelsSplit);
  checkSolvedNear(fair);
  CHECK(2 * fair.interiorFacesSplit + fair.boundaryPanelsSplit < 2 * plain.interiorFacesSplit + plain.boundaryPanelsSplit);
  CHECK(fair.interiorHexagonFraction >= plain.interiorHexagonFraction);
  PipelineParams p;
  p.mesh = upload("phcpf_car_r.off");
  p.method = TriangulationMethod::Global;
  p.faces = 1000;
  p.relay = false;  // its first lay (the lays again with the repairs of a smooth upload apply the fairness)
  const PipelineResult car = runPipeline(p);
  p.fairness = 0;
  const PipelineResult carPlain = runPipeline(p);
  REQUIRE(car.hex.V.rows() == carPlain.hex.V.rows());
  CHECK(car.hex.V == carPlain.hex.V);
  // Out of its range, named.
  p.fairness = 1.5;
  try {
    runPipeline(p);
    FAIL("no error for fairness 1.5");
  } catch (const Error& e) {
    CHECK(std::string(e.what()).find("fairness") != std::string::npos);
  }
}

namespace {

// The sum of squared misses of valence 6 (4 on the boundary), as improveValences counts it.
int valenceExcess(const TriMesh& T) {
  const std::set<std::pair<int, int>> directed = directedEdges(T);
  std::vector<int> valence(T.V.rows(), 0);
  std::vector<char> boundary(T.V.rows(), 0);
  for (const auto& [a, b] : directed) {
    if (!directed.count({b, a})) boundary[a] = boundary[b] = 1, ++valence[a], ++valence[b];
    else if (a < b) ++valence[a], ++valence[b];
  }
  int sum = 0;
  for (std::size_t v = 0; v < valence.size(); ++v) {
    const int d = valence[v] - (boundary[v] ? 4 : 6);
    sum += d * d;
  }
  return sum;
}

// The edge a - b flipped (its triangles (a, b, p) and (b, a, q) become (p, a, q) and (q, b, p)); false if it has
// not two triangles.
bool flipEdge(TriMesh& T, int a, int b) {
  int f = -1, g = -1, p = -1, q = -1;
  for (int t = 0; t < T.F.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      if (T.F(t, k) == a && T.F(t, (k + 1) % 3) == b) f = t, p = T.F(t, (k + 2) % 3);
      if (T.F(t, k) == b && T.F(t, (k + 1) % 3) == a) g = t, q = T.F(t, (k + 2) % 3);
    }
  if (f < 0 || g < 0) return false;
  T.F.row(f) << p, a, q;
  T.F.row(g) << q, b, p;
  return true;
}

// The interior edges of T, each once.
std::vector<std::pair<int, int>> interiorEdges(const TriMesh& T) {
  const std::set<std::pair<int, int>> directed = directedEdges(T);
  std::vector<std::pair<int, int>> edges;
  for (const auto& [a, b] : directed)
    if (a < b && directed.count({b, a})) edges.push_back({a, b});
  return edges;
}

}  // namespace

// A flat patch of the equilateral lattice with a dislocation dipole: one edge flipped (two 5s and two 7s), then one
// of the two dislocations moved a row along its glide line by a flip that keeps the valences' sum of squares. No
// single flip mends that; two (the glide back, then the flip back) do, and improveValences finds them.
TEST_CASE("global triangulation: dislocations of opposite sense glide together and vanish") {
  const int n = 12;
  TriMesh T;
  T.V.resize(n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) T.V.row(j * n + i) << i + 0.5 * j, 0.5 * std::sqrt(3.0) * j, 0;
  T.F.resize(2 * (n - 1) * (n - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i;
      T.F.row(f++) << a, a + 1, a + n;
      T.F.row(f++) << a + 1, a + n + 1, a + n;
    }
  const MeshSurface plane(T, "lattice.obj");
  const int regular = valenceExcess(T);
  const int c = (n / 2) * n + n / 2;
  REQUIRE(flipEdge(T, c + 1, c + n));
  REQUIRE(valenceExcess(T) == regular + 4);
  // A glide: a flip next to the four that keeps the sum of squares, and does not take the first flip back.
  bool glided = false;
  for (const auto& [a, b] : interiorEdges(T)) {
    if ((a == c && b == c + n + 1) || glided) continue;
    TriMesh trial = T;
    if (flipEdge(trial, a, b) && valenceExcess(trial) == regular + 4 && countEdges(trial).bad == 0) {
      // Not a flip that only moves the quadrupole back together: some single flip must not mend it.
      bool mendedByOne = false;
      for (const auto& [x, y] : interiorEdges(trial)) {
        TriMesh again = trial;
        mendedByOne = mendedByOne || (flipEdge(again, x, y) && valenceExcess(again) < regular + 4);
      }
      if (!mendedByOne) T = trial, glided = true;
    }
  }
  REQUIRE(glided);
  const int flips = global::improveValences(T, plane, true, nullptr);
  CHECK(flips >= 2);
  CHECK(valenceExcess(T) == regular);
  CHECK(countEdges(T).bad == 0);

  SECTION("a lattice scrambled by random flips: valences no worse, every triangle kept facing up") {
    TriMesh scrambled;
    scrambled.V = T.V;
    scrambled.F = T.F;
    std::uint32_t seed = 12345;
    auto next = [&]() { return seed = seed * 1664525u + 1013904223u; };
    for (int k = 0; k < 300; ++k) {
      const std::vector<std::pair<int, int>> edges = interiorEdges(scrambled);
      const auto [a, b] = edges[next() % edges.size()];
      TriMesh trial = scrambled;
      if (!flipEdge(trial, a, b)) continue;
      bool up = true;
      for (int f = 0; f < trial.F.rows(); ++f) {
        const Vec3 p = trial.V.row(trial.F(f, 0)), q = trial.V.row(trial.F(f, 1)), r = trial.V.row(trial.F(f, 2));
        up = up && (q - p).cross(r - p).z() > 0;
      }
      if (up && countEdges(trial).bad == 0) scrambled = trial;
    }
    const int before = valenceExcess(scrambled);
    REQUIRE(before > regular + 40);  // well scrambled
    global::improveValences(scrambled, plane, true, nullptr);
    INFO("sum of squared misses " << before << " -> " << valenceExcess(scrambled) << " (regular " << regular << ")");
    CHECK(valenceExcess(scrambled) < before);
    CHECK(countEdges(scrambled).bad == 0);
    for (int f = 0; f < scrambled.F.rows(); ++f) {
      const Vec3 p = scrambled.V.row(scrambled.F(f, 0)), q = scrambled.V.row(scrambled.F(f, 1)),
                 r = scrambled.V.row(scrambled.F(f, 2));
      CHECK((q - p).cross(r - p).z() > 0);
    }
  }
}

// A near-developable surface (the shallow dome, radii of curvature 1 and 30) is held to its flatter principal
// direction nearly everywhere; its boundary, a square across that direction, is left free there, so that the rows
// run to it straight and are clipped (GlobalOptions::freeAlignedBoundary). With the boundary fixed, the rows bent
// along it over the first rows inside and ended every other one at a vertex of 5 or 7 neighbours: measured at
// 3000 faces, 93.9 % interior hexagons against 99.7 %.
TEST_CASE("global triangulation: a near-developable surface's rows run to its boundary, left free there") {
  const ParametricSurfacePtr dome = makeSurface("elliptic-paraboloid", {{"ra", 1.0}, {"rb", 30.0}});
  GlobalOptions o = atFaces(2000);
  const double free = laidValence6(*dome, o);
  o.freeAlignedBoundary = false;
  const double fixed = laidValence6(*dome, o);
  INFO("interior vertices of valence 6: boundary free " << free << ", fixed " << fixed);
  CHECK(free >= 0.97);
  CHECK(free > fixed);
  // The lattice as the position field leaves it (dislocations kept), where the bent rows' ends stay as 5-7 pairs:
  // measured 98.5 % against 95.9 % (with them cancelled 98.9 % against 98.1 %).
  o.cancelDislocations = false;
  const double fixedKept = laidValence6(*dome, o);
  o.freeAlignedBoundary = true;
  const double freeKept = laidValence6(*dome, o);
  INFO("dislocations kept: boundary free " << freeKept << ", fixed " << fixedKept);
  CHECK(freeKept >= fixedKept + 0.02);
  // The pipeline: a planar mesh, nothing cut, covering the dome to its clipped boundary.
  PipelineParams p;
  p.surface = "elliptic-paraboloid";
  p.surfaceParams = {{"ra", 1.0}, {"rb", 30.0}};
  p.method = TriangulationMethod::Global;
  p.faces = 2000;
  p.relay = false;
  const PipelineResult r = runPipeline(p);
  CHECK(r.solve.converged);
  CHECK(r.metrics.planarityMax <= 1e-9);
  CHECK(r.interiorFacesSplit + r.boundaryPanelsSplit == 0);
  CHECK(r.interiorHexagonFraction >= 0.97);
  CHECK(r.coverageGap <= kCoverageGapGoal);
}

// The torus' lattice needs no dislocation (a lattice along the parallels with as many points on each closes up),
// but the position field leaves some: 5-7 pairs where the sweeps settled, rows wandering over them. Cancelled before
// the extraction (GlobalOptions::cancelDislocations), the cores are joined in pairs and the field left has none:
// the same cancellation on it finds nothing to do.
TEST_CASE("global lattice: the position field's dislocations on the torus are cancelled in pairs, none left") {
  const auto torus = makeSurface("torus");
  const double cell = 0.08;
  const global::FieldMesh m = global::fieldMesh(*torus, cell / 2.6, 1.5, 0.25, nullptr);
  std::vector<double> scale(m.vertexCount(), 1.0);
  std::vector<global::Level> levels = global::hierarchy(m, scale);
  std::vector<std::vector<Vec3>> fields = global::orientationField(levels, 1.0, {}, nullptr);
  const std::vector<double> integrable = global::integrableScale(m, fields[0], 1.0);
  for (int v = 0; v < m.vertexCount(); ++v) scale[v] *= integrable[v];
  global::setScale(levels, scale);
  std::vector<Vec3> o = global::positionField(levels, fields, cell, {}, nullptr);
  int left = -1;
  const int cancelled = global::cancelDislocations(m, levels[0], fields[0], o, cell, &left, nullptr);
  INFO(cancelled << " cores cancelled, " << left << " left");
  CHECK(cancelled >= 5);
  CHECK(left == 0);
  int again = -1;
  CHECK(global::cancelDislocations(m, levels[0], fields[0], o, cell, &again, nullptr) == 0);
  CHECK(again == 0);
}

// The triangulation extracted from it: on the torus at 3000 faces every vertex of valence 6, where the field as the
// sweeps left it has dislocations along the tube (measured: 100 % against 98.0 % of valence 6, 0 against 60
// irregular vertices).
TEST_CASE("global triangulation: with the dislocations cancelled the torus' lattice is nearly all of valence 6") {
  const auto torus = makeSurface("torus");
  GlobalOptions o = atFaces(3000);
  const double cancelled = laidValence6(*torus, o);
  o.cancelDislocations = false;
  const double kept = laidValence6(*torus, o);
  INFO("interior vertices of valence 6: dislocations cancelled " << cancelled << ", kept " << kept);
  CHECK(cancelled >= 0.99);
  CHECK(cancelled >= kept + 0.01);
  CHECK(PipelineParams().cancelDislocations);
  CHECK(GlobalOptions().cancelDislocations);
}

// The principal directions as a cross field: no umbilic on a Dupin cyclide (its curvature lines are circles, a
// network without singularities), several on the bumps (their hill tops).
TEST_CASE("global field: the principal directions turn about no triangle of the cyclide, about the bumps' hill tops") {
  auto umbilics = [](const Surface& s, double edge) {
    const global::FieldMesh m = global::fieldMesh(s, edge, 1.5, 0.25, nullptr);
    int count = 0;
    for (int f = 0; f < m.F.rows(); ++f) count += global::principalTurns(m, m.F(f, 0), m.F(f, 1), m.F(f, 2));
    return count;
  };
  CHECK(umbilics(*makeSurface("cyclide"), 0.03) == 0);
  CHECK(umbilics(*makeSurface("freeform"), 0.025) >= 4);
}

// GlobalOptions::principalTrial: on the cyclide the field smoothest in the Dupin metric turns through pairs of
// singular points the principal directions do not have; held to them it turns through a few, and that field is
// laid (measured at 2000 faces: 20 -> 4 singular points, interior valence 6 from 94 to 97 %). On the bumps, whose
// hill tops are umbilics, the trial is not run: the same field, the same mesh.
TEST_CASE("global triangulation: the field held to the principal directions is laid on the cyclide, not on the bumps") {
  const auto cyclide = makeSurface("cyclide");
  GlobalOptions o = atFaces(2000);
  const Triangulation held = globalTriangulation(*cyclide, o);
  o.principalTrial = false;
  const Triangulation smoothest = globalTriangulation(*cyclide, o);
  INFO("singular points held " << held.singularities.size() << ", smoothest " << smoothest.singularities.size());
  CHECK(held.singularities.size() <= 0.75 * smoothest.singularities.size());
  CHECK(held.notes.front().find("held to the principal directions") != std::string::npos);
  CHECK(smoothest.notes.front().find("held to the principal directions") == std::string::npos);
  const double heldRegular = checkTriangulation(held, *cyclide).regularFraction;
  const double smoothestRegular = checkTriangulation(smoothest, *cyclide).regularFraction;
  INFO("valence 6: held " << heldRegular << ", smoothest " << smoothestRegular);
  CHECK(heldRegular > smoothestRegular);

  const auto bumps = makeSurface("freeform");
  GlobalOptions b = atFaces(1500);
  const Triangulation tried = globalTriangulation(*bumps, b);
  b.principalTrial = false;
  const Triangulation off = globalTriangulation(*bumps, b);
  CHECK(tried.notes.front().find("held to the principal directions") == std::string::npos);
  CHECK(tried.singularities.size() == off.singularities.size());
  CHECK(tried.mesh.V.isApprox(off.mesh.V));
  CHECK(GlobalOptions().principalTrial);
}
