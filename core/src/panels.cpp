// phex — fabrication output: faces laid flat, a cut sheet (SVG) and a panel schedule (CSV).
#include "phex/panels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "phex/error.hpp"
#include "phex/metrics.hpp"

namespace phex {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string label(int face) { return panelLabel(face); }
std::string num(double x) { return formatNumber(x); }

// The area centroid of a simple polygon (the mean corner where the area vanishes).
Vec2 areaCentroid(const std::vector<Vec2>& p) {
  const double a = signedArea(p);
  Vec2 c = Vec2::Zero();
  if (!(std::abs(a) > 0)) {
    for (const Vec2& q : p) c += q / static_cast<double>(p.size());
    return c;
  }
  for (std::size_t k = 0; k < p.size(); ++k) {
    const Vec2& q = p[k];
    const Vec2& r = p[(k + 1) % p.size()];
    c += (q + r) * (q.x() * r.y() - r.x() * q.y());
  }
  return c / (6 * a);
}

struct Box2 {
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
};
Box2 boxOf(const std::vector<Vec2>& p) {
  Box2 b{p[0].x(), p[0].x(), p[0].y(), p[0].y()};
  for (const Vec2& q : p) {
    b.x0 = std::min(b.x0, q.x()), b.x1 = std::max(b.x1, q.x());
    b.y0 = std::min(b.y0, q.y()), b.y1 = std::max(b.y1, q.y());
  }
  return b;
}

double meanEdge(const std::vector<Panel>& panels) {
  double sum = 0;
  int n = 0;
  for (const Panel& p : panels) sum += p.perimeter, n += static_cast<int>(p.edges.size());
  return n > 0 ? sum / n : 0.0;
}

}  // namespace

std::string panelLabel(int face) { return "P" + std::to_string(face + 1); }

std::string formatNumber(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", x == 0 ? 0.0 : x);  // no "-0"
  return buf;
}

void checkPolyMesh(const PolyMesh& mesh, const std::string& who) {
  const int nf = mesh.faceCount(), nv = static_cast<int>(mesh.V.rows());
  if (nf <= 0) throw Error(ErrorCode::InvalidInput, who + ": the mesh has no faces");
  if (mesh.offsets.front() != 0 || static_cast<std::size_t>(mesh.offsets.back()) != mesh.indices.size())
    throw Error(ErrorCode::InvalidInput, who + ": the face offsets do not span the face indices");
  if (!mesh.V.allFinite()) {
    for (int v = 0; v < nv; ++v)
      if (!mesh.V.row(v).allFinite())
        throw Error(ErrorCode::InvalidInput, who + ": vertex " + std::to_string(v) + " has a coordinate that is not finite");
  }
  for (int f = 0; f < nf; ++f) {
    auto name = [&] { return who + ": face " + std::to_string(f) + " (" + label(f) + ")"; };  // on error only
    if (mesh.offsets[f + 1] < mesh.offsets[f] || static_cast<std::size_t>(mesh.offsets[f + 1]) > mesh.indices.size())
      throw Error(ErrorCode::InvalidInput, name() + ": its offsets " + std::to_string(mesh.offsets[f]) + ".." +
                                               std::to_string(mesh.offsets[f + 1]) + " do not lie within the face indices");
    const int n = mesh.offsets[f + 1] - mesh.offsets[f];
    if (n < 3) throw Error(ErrorCode::InvalidInput, name() + " has " + std::to_string(std::max(n, 0)) + " corners; a panel needs 3 or more");
    const int* ids = mesh.face(f);
    for (int k = 0; k < n; ++k)
      if (ids[k] < 0 || ids[k] >= nv)
        throw Error(ErrorCode::InvalidInput, name() + " names vertex " + std::to_string(ids[k]) + ", outside 0.." + std::to_string(nv - 1));
  }
}

std::vector<MeshEdge> meshEdges(const PolyMesh& mesh, const std::string& who) {
  std::vector<MeshEdge> edges;
  edges.reserve(mesh.indices.size() / 2 + 8);
  // The edges at each node as a linked list under its smaller end: a node has few, so a lookup is a short walk.
  std::vector<int> head(mesh.V.rows(), -1), next;
  next.reserve(edges.capacity());
  for (int f = 0; f < mesh.faceCount(); ++f) {
    const int n = mesh.faceSize(f);
    const int* ids = mesh.face(f);
    for (int k = 0; k < n; ++k) {
      const int a = ids[k], b = ids[(k + 1) % n];
      int e = head[std::min(a, b)];
      while (e >= 0 && std::max(edges[e].a, edges[e].b) != std::max(a, b)) e = next[e];
      if (e < 0) {
        next.push_back(head[std::min(a, b)]);
        head[std::min(a, b)] = static_cast<int>(edges.size());
        edges.push_back({a, b, f, -1});
        continue;
      }
      MeshEdge& edge = edges[e];
      auto name = [&] { return who + ": the edge between vertices " + std::to_string(a) + " and " + std::to_string(b); };
      if (edge.right >= 0)
        throw Error(ErrorCode::InvalidInput, name() + " is shared by more than two faces (" + label(edge.left) + ", " +
                                                 label(edge.right) + ", " + label(f) + ")");
      if (edge.a == a)
        throw Error(ErrorCode::InvalidInput, name() + " runs the same way in " + label(edge.left) + " and " + label(f) +
                                                 " (faces not consistently oriented)");
      edge.right = f;
    }
  }
  return edges;
}

std::vector<Panel> flattenPanels(const PolyMesh& mesh) {
  checkPolyMesh(mesh, "panels");
  const int nf = mesh.faceCount();
  std::vector<Panel> panels(nf);
  for (int f = 0; f < nf; ++f) {
    const std::string name = "panels: face " + std::to_string(f) + " (" + label(f) + ")";
    const int n = mesh.faceSize(f);
    const int* ids = mesh.face(f);
    Panel& p = panels[f];
    p.face = f;
    const FacePlane plane = leastSquaresPlane(mesh, f);
    p.centroid = plane.centroid;
    p.normal = normalLikeFace(mesh, f, plane.normal);  // on the side the corners turn counterclockwise
    auto onPlane = [&](int k) {
      const Vec3 q = mesh.vertex(ids[k]);
      return Vec3(q - (q - p.centroid).dot(p.normal) * p.normal);
    };
    double scale = 0, longest = -1;
    for (int k = 0; k < n; ++k) {
      const double e = (mesh.vertex(ids[(k + 1) % n]) - mesh.vertex(ids[k])).norm();
      p.edges.push_back(e);
      p.perimeter += e;
      scale = std::max(scale, (mesh.vertex(ids[k]) - p.centroid).norm());
      const double flat = (onPlane((k + 1) % n) - onPlane(k)).norm();
      if (flat > longest) longest = flat, p.base = k;
    }
    if (!(longest > 1e-12 * std::max(scale, 1e-300)))
      throw Error(ErrorCode::InvalidInput, name + " is degenerate: its corners coincide");
    p.origin = onPlane(p.base);
    p.xAxis = (onPlane((p.base + 1) % n) - p.origin).normalized();
    p.yAxis = p.normal.cross(p.xAxis);
    for (int k = 0; k < n; ++k) {
      const Vec3 d = onPlane(k) - p.origin;
      p.outline.emplace_back(d.dot(p.xAxis), d.dot(p.yAxis));
    }
    for (Vec2& c : p.outline)  // round-off off the axes (1e-16 for 0) to 0
      for (int a = 0; a < 2; ++a)
        if (std::abs(c[a]) < 1e-14 * longest) c[a] = 0;
    p.area = signedArea(p.outline);
    if (!(p.area > 1e-12 * longest * longest))
      throw Error(ErrorCode::InvalidInput, name + " is degenerate: its corners lie on one line");
    for (int k = 0; k < n; ++k) {
      const Vec2 in = p.outline[k] - p.outline[(k + n - 1) % n], out = p.outline[(k + 1) % n] - p.outline[k];
      const double turn = std::atan2(in.x() * out.y() - in.y() * out.x(), in.dot(out));
      p.angles.push_back(180.0 - turn * 180.0 / kPi);
    }
    p.planarity = facePlanarity(mesh, f, plane);
  }
  return panels;
}

PanelSheet layoutPanels(const std::vector<Panel>& panels, const PanelSheetOptions& options) {
  if (!(options.gap >= 0) || !std::isfinite(options.gap))
    throw Error(ErrorCode::InvalidParameter, "panels: gap must be 0 or more (got " + num(options.gap) + ")");
  if (!(options.width >= 0) || !std::isfinite(options.width))
    throw Error(ErrorCode::InvalidParameter, "panels: width must be 0 or more (got " + num(options.width) + ")");
  PanelSheet sheet;
  if (panels.empty()) return sheet;
  const double gap = options.gap > 0 ? options.gap : 0.25 * meanEdge(panels);
  double widest = 0, area = 0;
  std::vector<Box2> boxes;
  for (const Panel& p : panels) {
    boxes.push_back(boxOf(p.outline));
    const double w = boxes.back().x1 - boxes.back().x0, h = boxes.back().y1 - boxes.back().y0;
    widest = std::max(widest, w);
    area += (w + gap) * (h + gap);
  }
  sheet.width = std::max(options.width > 0 ? options.width : std::sqrt(area) + gap, widest + 2 * gap);
  double x = gap, y = gap, row = 0;
  for (const Box2& b : boxes) {
    const double w = b.x1 - b.x0, h = b.y1 - b.y0;
    if (x > gap && x + w + gap > sheet.width) x = gap, y += row + gap, row = 0;
    sheet.offset.emplace_back(x, y);
    x += w + gap;
    row = std::max(row, h);
  }
  sheet.height = y + row + gap;
  return sheet;
}

std::string panelsSvg(const std::vector<Panel>& panels, const PanelSheetOptions& options) {
  double millimetres = 0;  // per unit of the mesh
  if (options.unit == "mm") millimetres = 1;
  else if (options.unit == "cm") millimetres = 10;
  else if (options.unit == "m") millimetres = 1000;
  else if (options.unit == "in") millimetres = 25.4;
  else if (!options.unit.empty())
    throw Error(ErrorCode::InvalidParameter, "panels: unit must be mm, cm, m or in (got '" + options.unit + "')");
  const PanelSheet sheet = layoutPanels(panels, options);
  const double edge = meanEdge(panels);
  double worst = 0;
  for (const Panel& p : panels) worst = std::max(worst, p.planarity);
  std::string s = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  s += "<svg xmlns=\"http://www.w3.org/2000/svg\"";
  if (millimetres > 0)
    s += " width=\"" + num(sheet.width * millimetres) + "mm\" height=\"" + num(sheet.height * millimetres) + "mm\"";
  s += " viewBox=\"0 0 " + num(sheet.width) + " " + num(sheet.height) + "\">\n";
  s += "<!-- phex panels: " + std::to_string(panels.size()) + " faces true to size (1 unit = 1 " +
       (options.unit.empty() ? std::string("unit of the mesh") : options.unit) +
       "), each seen from its normal side; largest planarity " + num(worst) +
       " of the mean edge. Labels P<n> are face n of the mesh (1-based, as in OBJ). -->\n";
  s += "<g fill=\"none\" stroke=\"#000\" stroke-width=\"" + num(0.01 * edge) + "\">\n";
  std::vector<std::vector<Vec2>> placed;
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const Panel& p = panels[i];
    const Box2 b = boxOf(p.outline);
    std::vector<Vec2> q;
    // y mirrored: the sheet's y runs down, so the panel keeps its turn as seen from the normal side.
    for (const Vec2& c : p.outline) q.emplace_back(sheet.offset[i].x() + c.x() - b.x0, sheet.offset[i].y() + b.y1 - c.y());
    s += "<polygon id=\"" + label(p.face) + "\" points=\"";
    for (std::size_t k = 0; k < q.size(); ++k) s += (k ? " " : "") + num(q[k].x()) + "," + num(q[k].y());
    s += "\"/>\n";
    placed.push_back(std::move(q));
  }
  s += "</g>\n";
  if (options.labels) {
    s += "<g font-family=\"sans-serif\" font-size=\"" + num(0.3 * edge) + "\" text-anchor=\"middle\" dominant-baseline=\"central\" fill=\"#c00\">\n";
    for (std::size_t i = 0; i < panels.size(); ++i) {
      const Vec2 c = areaCentroid(placed[i]);
      s += "<text x=\"" + num(c.x()) + "\" y=\"" + num(c.y()) + "\">" + label(panels[i].face) + "</text>\n";
    }
    s += "</g>\n";
  }
  s += "</svg>\n";
  return s;
}

std::string panelsCsv(const std::vector<Panel>& panels) {
  std::string s =
      "panel,corners,area,perimeter,planarity,centroid_x,centroid_y,centroid_z,normal_x,normal_y,normal_z,"
      "edge_lengths,corner_angles_deg,outline_xy\n";
  for (const Panel& p : panels) {
    s += label(p.face) + "," + std::to_string(p.outline.size()) + "," + num(p.area) + "," + num(p.perimeter) + "," +
         num(p.planarity);
    for (const Vec3* v : {&p.centroid, &p.normal})
      for (int a = 0; a < 3; ++a) s += "," + num((*v)[a]);
    s += ",";
    for (std::size_t k = 0; k < p.edges.size(); ++k) s += (k ? ";" : "") + num(p.edges[k]);
    s += ",";
    for (std::size_t k = 0; k < p.angles.size(); ++k) s += (k ? ";" : "") + num(p.angles[k]);
    s += ",";
    for (std::size_t k = 0; k < p.outline.size(); ++k) s += (k ? ";" : "") + num(p.outline[k].x()) + " " + num(p.outline[k].y());
    s += "\n";
  }
  return s;
}

std::string beamsCsv(const PolyMesh& mesh) {
  const std::vector<Panel> panels = flattenPanels(mesh);  // checks the mesh; gives each face's plane
  const std::vector<MeshEdge> beams = meshEdges(mesh);
  std::string s = "beam,node_a,node_b,length,panel_left,panel_right,fold_deg,ax,ay,az,bx,by,bz\n";
  for (std::size_t i = 0; i < beams.size(); ++i) {
    const MeshEdge& beam = beams[i];
    const Vec3 a = mesh.vertex(beam.a), b = mesh.vertex(beam.b);
    std::string fold;
    if (beam.right >= 0) {
      const Panel& l = panels[beam.left];
      const Panel& r = panels[beam.right];
      const double angle = std::atan2(l.normal.cross(r.normal).norm(), l.normal.dot(r.normal)) * 180.0 / kPi;
      // A ridge where the right panel's centre lies below the left panel's plane (against its normal).
      fold = num((r.centroid - l.centroid).dot(l.normal) <= 0 ? angle : -angle);
    }
    s += "B" + std::to_string(i + 1) + "," + std::to_string(beam.a + 1) + "," + std::to_string(beam.b + 1) + "," +
         num((b - a).norm()) + "," + label(beam.left) + "," + (beam.right >= 0 ? label(beam.right) : "") + "," + fold;
    for (const Vec3* p : {&a, &b})
      for (int k = 0; k < 3; ++k) s += "," + num((*p)[k]);
    s += "\n";
  }
  return s;
}

}  // namespace phex
