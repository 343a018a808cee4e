#include <catch.hpp>
#include <cmath>
#include <regex>
#include <sstream>

#include "phex/error.hpp"
#include "phex/metrics.hpp"
#include "phex/panels.hpp"
#include "phex/pipeline.hpp"

using namespace phex;

namespace {

// A planar hexagon (an affine image of the regular one, so not equilateral) in a tilted plane, corners CCW seen
// from `normal`.
PolyMesh tiltedHexagon(Vec3& normal) {
  const Vec3 a = Vec3(1, 0.2, 0.3).normalized(), n0 = Vec3(0.1, -0.4, 1).normalized();
  const Vec3 b = n0.cross(a).normalized();
  normal = a.cross(b);
  PolyMesh m;
  m.V.resize(6, 3);
  for (int i = 0; i < 6; ++i) {
    const double t = i * M_PI / 3;
    m.V.row(i) = (Vec3(5, -2, 7) + 2.0 * std::cos(t) * a + 1.0 * std::sin(t) * b).transpose();
  }
  m.addFace({0, 1, 2, 3, 4, 5});
  return m;
}

// The cells of each line of `csv` (no quoting in phex's CSV; an empty last cell kept).
std::vector<std::vector<std::string>> csvRows(const std::string& csv) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream lines(csv);
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<std::string> cells;
    std::stringstream cellStream(line);
    std::string cell;
    while (std::getline(cellStream, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    rows.push_back(cells);
  }
  return rows;
}

}  // namespace

TEST_CASE("panels: a tilted planar hexagon is laid flat true to size, counterclockwise from its normal side") {
  Vec3 normal;
  const PolyMesh m = tiltedHexagon(normal);
  const std::vector<Panel> panels = flattenPanels(m);
  REQUIRE(panels.size() == 1);
  const Panel& p = panels[0];
  CHECK(p.normal.dot(normal) == Approx(1.0));
  REQUIRE(p.outline.size() == 6);
  double angles = 0;
  for (int k = 0; k < 6; ++k) {
    // Every flat edge and every flat diagonal as long as in space.
    for (int j = 0; j < 6; ++j)
      CHECK((p.outline[j] - p.outline[k]).norm() == Approx((m.vertex(j) - m.vertex(k)).norm()).margin(1e-12));
    CHECK(p.edges[k] == Approx((m.vertex((k + 1) % 6) - m.vertex(k)).norm()));
    angles += p.angles[k];
    // The frame maps the outline back onto the corners.
    CHECK((p.origin + p.outline[k].x() * p.xAxis + p.outline[k].y() * p.yAxis - m.vertex(k)).norm() < 1e-12);
  }
  CHECK(angles == Approx(720.0));
  // The longest edge from the origin along +x, the rest above it (the hexagon is convex).
  CHECK(p.outline[p.base].norm() < 1e-12);
  CHECK(std::abs(p.outline[(p.base + 1) % 6].y()) < 1e-12);
  CHECK(p.outline[(p.base + 1) % 6].x() == Approx(*std::max_element(p.edges.begin(), p.edges.end())));
  for (const Vec2& c : p.outline) CHECK(c.y() > -1e-12);
  CHECK(p.area == Approx(measure(m).faceArea[0]));
  CHECK(p.area > 0);
  CHECK(p.planarity < 1e-12);
  // Reversed, the face is seen from the other side: the normal flips, the outline still turns CCW.
  PolyMesh reversed = m;
  reversed.indices = {5, 4, 3, 2, 1, 0};
  const Panel q = flattenPanels(reversed)[0];
  CHECK(q.normal.dot(normal) == Approx(-1.0));
  CHECK(q.area == Approx(p.area));
}

TEST_CASE("panels: a P-Hex mesh's panels keep their true size, and the sheet places them apart") {
  PipelineParams params;
  params.surface = "torus";
  params.faces = 400;
  const PipelineResult r = runPipeline(params);
  REQUIRE(r.solve.converged);
  const std::vector<Panel> panels = flattenPanels(r.hex);
  REQUIRE(static_cast<int>(panels.size()) == r.hex.faceCount());
  int reflex = 0;
  for (const Panel& p : panels) {
    const int n = static_cast<int>(p.outline.size());
    double angles = 0;
    for (int k = 0; k < n; ++k) {
      const double flat = (p.outline[(k + 1) % n] - p.outline[k]).norm();
      CHECK(std::abs(flat - p.edges[k]) <= 1e-8 * p.edges[k]);  // planar to 1e-9 of the edge: lengths kept
      angles += p.angles[k];
      reflex += p.angles[k] > 180;
    }
    CHECK(angles == Approx(180.0 * (n - 2)));
    CHECK(p.area == Approx(r.metrics.faceArea[p.face]).epsilon(1e-9));
    CHECK(p.planarity == Approx(r.metrics.planarity[p.face]).margin(1e-15));
  }
  CHECK(reflex > 0);  // the torus' inner half has non-convex faces (K < 0, §3)
  // Bounding boxes on the sheet: inside it and apart by the gap.
  PanelSheetOptions o;
  o.gap = 0.01;
  const PanelSheet sheet = layoutPanels(panels, o);
  std::vector<std::array<double, 4>> boxes;
  for (std::size_t i = 0; i < panels.size(); ++i) {
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (const Vec2& c : panels[i].outline) x0 = std::min(x0, c.x()), x1 = std::max(x1, c.x()), y0 = std::min(y0, c.y()), y1 = std::max(y1, c.y());
    const double X = sheet.offset[i].x(), Y = sheet.offset[i].y();
    boxes.push_back({X, X + x1 - x0, Y, Y + y1 - y0});
    CHECK(X >= o.gap - 1e-12);
    CHECK(Y >= o.gap - 1e-12);
    CHECK(X + x1 - x0 <= sheet.width - o.gap + 1e-12);
    CHECK(Y + y1 - y0 <= sheet.height - o.gap + 1e-12);
  }
  int overlaps = 0;
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t j = i + 1; j < boxes.size(); ++j)
      overlaps += boxes[i][0] < boxes[j][1] + o.gap - 1e-12 && boxes[j][0] < boxes[i][1] + o.gap - 1e-12 &&
                  boxes[i][2] < boxes[j][3] + o.gap - 1e-12 && boxes[j][2] < boxes[i][3] + o.gap - 1e-12;
  CHECK(overlaps == 0);
  CHECK(sheet.width < 3 * sheet.height);  // about square by default
  CHECK(sheet.height < 3 * sheet.width);
  // The SVG: one polygon and one label per panel, labelled P1..Pn in face order.
  const std::string svg = panelsSvg(panels);
  const std::regex polygon("<polygon id=\"P([0-9]+)\" points=\"([^\"]*)\"/>");
  int count = 0;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), polygon); it != std::sregex_iterator(); ++it, ++count) {
    CHECK(std::stoi((*it)[1]) == count + 1);
    std::istringstream points((*it)[2]);
    std::string pair;
    int corners = 0;
    while (points >> pair) ++corners;
    CHECK(corners == static_cast<int>(panels[count].outline.size()));
  }
  CHECK(count == static_cast<int>(panels.size()));
  const std::regex text("<text [^>]*>P[0-9]+</text>");
  CHECK(std::distance(std::sregex_iterator(svg.begin(), svg.end(), text), std::sregex_iterator()) == count);
  PanelSheetOptions bare;
  bare.labels = false;
  CHECK(panelsSvg(panels, bare).find("<text") == std::string::npos);
  // Without a unit no size (viewers fit the sheet); with one, the true size in millimetres.
  CHECK(svg.find(" width=") == std::string::npos);
  PanelSheetOptions metres;
  metres.unit = "m";
  const std::string sized = panelsSvg(panels, metres);
  std::smatch size;
  REQUIRE(std::regex_search(sized, size, std::regex("<svg [^>]*width=\"([0-9.e+-]+)mm\"")));
  CHECK(std::stod(size[1]) == Approx(1000 * layoutPanels(panels).width).epsilon(1e-9));
  metres.unit = "ft";
  CHECK_THROWS_AS(panelsSvg(panels, metres), Error);
  // The CSV: a header and one row per panel, 14 columns, the lists as long as the panel has corners.
  const std::vector<std::vector<std::string>> rows = csvRows(panelsCsv(panels));
  REQUIRE(!rows.empty());
  CHECK(rows[0][0] == "panel");
  CHECK(rows[0][1] == "corners");
  CHECK(rows[0][2] == "area");
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const std::vector<std::string>& cells = rows[i];
    REQUIRE(cells.size() == 14);
    CHECK(cells[0] == "P" + std::to_string(i));
    const int n = std::stoi(cells[1]);
    for (int c : {11, 12, 13}) CHECK(std::count(cells[c].begin(), cells[c].end(), ';') == n - 1);
  }
  CHECK(static_cast<int>(rows.size()) - 1 == count);
}

TEST_CASE("panels: bad meshes and options are named") {
  Vec3 normal;
  const PolyMesh good = tiltedHexagon(normal);
  auto fails = [](const PolyMesh& m, const std::string& part) {
    try {
      flattenPanels(m);
    } catch (const Error& e) {
      CHECK(e.code() == ErrorCode::InvalidInput);
      CHECK_THAT(e.what(), Catch::Contains(part));
      return;
    }
    FAIL("no error for " << part);
  };
  fails(PolyMesh{}, "no faces");
  PolyMesh m = good;
  m.V(3, 1) = std::nan("");
  fails(m, "vertex 3");
  m = good;
  m.indices[2] = 17;
  fails(m, "vertex 17");
  m = good;
  m.addFace({0, 1});
  fails(m, "face 1 (P2) has 2 corners");
  m = good;
  m.offsets = {0, 9};
  fails(m, "offsets");
  m = good;
  m.V.row(5) = m.V.row(0);
  m.V.row(1) = m.V.row(0);
  m.V.row(2) = m.V.row(0);
  m.V.row(3) = m.V.row(0);
  m.V.row(4) = m.V.row(0);
  fails(m, "corners coincide");
  m = good;
  for (int i = 0; i < 6; ++i) m.V.row(i) << i, 2 * i, 0;
  fails(m, "one line");
  const std::vector<Panel> panels = flattenPanels(good);
  for (double bad : {-1.0, std::nan(""), HUGE_VAL}) {
    PanelSheetOptions o;
    o.gap = bad;
    CHECK_THROWS_AS(panelsSvg(panels, o), Error);
    o.gap = 0;
    o.width = bad;
    CHECK_THROWS_AS(layoutPanels(panels, o), Error);
  }
  // A sheet narrower than the widest panel is widened to fit it.
  PanelSheetOptions narrow;
  narrow.width = 1e-6;
  const PanelSheet sheet = layoutPanels(panels, narrow);
  CHECK(sheet.width > 3.9);  // the hexagon spans 4 across
}

TEST_CASE("beams: one row per edge with its panels, and the fold between them signed ridge or valley") {
  // Two unit squares meeting at a ridge along x (z = 1 there), both CCW seen from above.
  PolyMesh roof;
  roof.V.resize(6, 3);
  roof.V << 0, -1, 0, 1, -1, 0, 1, 0, 1, 0, 0, 1, 0, 1, 0, 1, 1, 0;
  roof.addFace({0, 1, 2, 3});
  roof.addFace({3, 2, 5, 4});
  std::vector<std::vector<std::string>> rows = csvRows(beamsCsv(roof));
  REQUIRE(rows.size() == 1 + 7);  // 4 + 4 edges, one shared
  CHECK(rows[0][0] == "beam");
  int shared = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    REQUIRE(rows[i].size() == 13);
    CHECK(rows[i][0] == "B" + std::to_string(i));
    if (rows[i][5].empty()) {
      CHECK(rows[i][6].empty());  // a boundary beam: no fold
      continue;
    }
    ++shared;
    CHECK(rows[i][4] == "P1");
    CHECK(rows[i][5] == "P2");
    CHECK(std::stod(rows[i][3]) == Approx(1.0));
    CHECK(std::stod(rows[i][6]) == Approx(90.0));  // normals (0,-1,1)/√2 and (0,1,1)/√2: a ridge
  }
  CHECK(shared == 1);
  // Upside down (the same faces, z mirrored and turned to stay CCW seen from above): a valley.
  PolyMesh valley = roof;
  valley.V.col(2) = -valley.V.col(2);
  rows = csvRows(beamsCsv(valley));
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (!rows[i][5].empty()) CHECK(std::stod(rows[i][6]) == Approx(-90.0));

  // A closed convex P-Hex mesh (§7, 12 pentagons): every beam has two panels and is a ridge seen from outside,
  // and there are V + F - 2 of them (Euler).
  PipelineParams p;
  p.method = TriangulationMethod::Subdivision;
  p.surface = "icosahedron";
  p.faces = 500;
  const PipelineResult r = runPipeline(p);
  REQUIRE(r.solve.converged);
  rows = csvRows(beamsCsv(r.hex));
  CHECK(static_cast<int>(rows.size()) - 1 == r.hex.V.rows() + r.hex.faceCount() - 2);
  for (std::size_t i = 1; i < rows.size(); ++i) {
    REQUIRE(rows[i].size() == 13);
    CHECK(!rows[i][5].empty());
    CHECK(std::stod(rows[i][6]) > 0);
    const int a = std::stoi(rows[i][1]) - 1, b = std::stoi(rows[i][2]) - 1;
    CHECK(std::stod(rows[i][3]) == Approx((r.hex.vertex(a) - r.hex.vertex(b)).norm()));
  }

  // Bad meshes: an edge of three faces, and two faces running an edge the same way.
  PolyMesh three = roof;
  three.V.conservativeResize(7, 3);
  three.V.row(6) << 0.5, 0.5, 2;
  three.addFace({2, 3, 6});
  CHECK_THROWS_WITH(beamsCsv(three), Catch::Contains("shared by more than two faces (P1, P2, P3)"));
  PolyMesh flipped = roof;
  flipped.indices = {0, 1, 2, 3, 2, 3, 4, 5};
  CHECK_THROWS_WITH(beamsCsv(flipped), Catch::Contains("runs the same way in P1 and P2"));
}
