// phex — command-line tool: computes P-Hex meshes from the analytic surfaces.
#include <phex/error.hpp>
#include <phex/mesh_io.hpp>
#include <phex/mesh_surface.hpp>
#include <phex/pipeline.hpp>
#include <phex/panels.hpp>
#include <phex/parallel.hpp>
#include <phex/structure.hpp>

#include "gltf.hpp"

#include <algorithm>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <new>
#include <numeric>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

using nlohmann::json;

namespace {

const char* kHelp = R"(phex — hexagonal meshes with planar faces (P-Hex meshes)

Usage:
  phex run [options]        compute a P-Hex mesh of a surface
  phex triangulate [opts]   only lay and check the triangulation (the options of run; --out writes it)
  phex curvature [options]  principal curvatures and directions per vertex, as CSV
  phex surfaces             list the analytic surfaces and their parameters
  phex --help | --version

Options of `phex run`:
  --surface NAME            analytic surface (default torus; see `phex surfaces`), or for
                            --method subdivision a built-in control mesh (icosahedron, egg,
                            flattened-icosahedron)
  --mesh FILE               an uploaded triangle mesh (OBJ, OFF, PLY, STL) instead of --surface; for
                            --method subdivision, the convex control mesh
  --param NAME=VALUE        a surface parameter, e.g. --param R=2 (repeatable)
  --method NAME             triangulation: auto (default: the surface's recommended method, see
                            `phex surfaces`; for an uploaded mesh prespecified where trial lays find
                            one system of rows covering it and its lay leaves no part bare, else
                            global; §7's geodesic route for a
                            closed convex one, subdivision for a closed convex polyhedron of
                            fewer vertices than the faces asked for), progressive (§5.2 Method 1), prespecified
                            (Method 2, along --field), subdivision (§7, closed convex surfaces) or
                            lattice (parameter rows; analytic surfaces only), or global (a 6-fold
                            field in the Dupin metric with singular vertices, its lattice extracted:
                            any surface, any genus, pentagons and heptagons at the singularities)
  --anisotropy A            global: largest ratio of the Dupin metric's axes followed, 1..8 (default 2;
                            1 gives triangles equilateral in space)
  --alignment W             global: weight of the alignment with the flatter principal direction, 0..10
                            (default 3; 0 leaves the field free but for the boundary; on smooth surfaces
                            a stronger pull often cuts fewer faces next to parabolic curves)
  --curvature-sizing S      global: how far the cell follows the curvature, 0..1 (default 0: uniform)
  --curvature-floor F       global: where |curvature| is small the metric tends to the isotropic one: each
                            principal |curvature| gets F times the surface's median largest one added
                            before their ratio is taken, 0.01..1 (default 0.25; smaller follows a
                            near-developable surface's elongated indicatrix further, up to --anisotropy)
  --relay on|off            global: where the lay does not reach a P-Hex mesh, or its cuts make nodes of
                            four faces at over 5 % of its faces, lay it again following the Dupin metric
                            further (anisotropy 2.5, curvature floor 0.05) and keep the better (a noisy
                            upload's first lay leaves out the repairs that trade hexagons for cuts there;
                            where it reaches no P-Hex mesh it is laid again with them, kept where that one
                            does); an upload under auto whose Method 2 rows leave a point of it over a
                            mean panel edge from any panel, cut faces, or reach no P-Hex mesh: tile it by
                            the global method and keep that where it reaches one covering the upload more
                            closely or, both within a panel edge, with fewer nodes of four faces from cuts;
                            then, at up to 5000 faces (10000 where they are over 0.25 % of the faces), where
                            the global lay kept still has nodes of four from cuts, lay it again for 3 % fewer
                            and more faces and keep the best (report: relay)
                            (default on)
  --fold-flips on|off       global: where the dual solved with folds allowed has faces crossing themselves
                            (at most 8 % of them), merge each one's vertex with its neighbour along the
                            flatter principal direction (else flip an edge of its star) and solve again:
                            fewer faces cut later, each cut making two nodes of four faces (default on)
  --dislocations cancel|keep
                            global: the lattice's dislocations (a vertex of five next to one of seven)
                            joined in pairs of opposite sense or moved into a singular point of the
                            field before the triangle mesh is extracted: more hexagons, rows unbroken
                            (default cancel); keep: as the position field leaves them
  --principal-field try|off global: also solve the field held to the principal directions wherever the
                            curvature is anisotropic, and lay it where it has at most three quarters of the
                            singular points (a cyclide, a torus: surfaces without umbilics; default try)
  --field SPEC              direction field: principal (default; under --method auto the surface's
                            recommended field; on a dome whose curvature lines turn around an umbilic,
                            section), angle:DEG, param, radial, diverging[:DEG], spiral[:DEG],
                            section[:DEG] (sections by parallel planes standing on the mean plane)
  --lower-bound B           §5.3 lower bound on the step ratio |CM|/|AB|, 0..2 (default 0.3; 0 off)
  --start X,Y,Z             where the base curve L0 starts (a point near the surface; default: the
                            middle of its bounds, projected)
  --direction X,Y,Z         which way L0 runs at the start (default: along the smaller normal curvature)
  --faces N                 wanted number of hexagons, 12..1000000 (default 2000)
  --cell H                  wanted edge length of the triangulation instead of --faces
  --tolerance T             planarity goal relative to edge length (default 1e-9)
  --lambda L                initial closeness weight, divided by 10 every round (default 1)
  --mu M                    surface-distance weight (default 0)
  --fairness F              global: the local solver pulls each interior node towards its neighbours'
                            mean with F times the square root of lambda, gone with lambda: the faces'
                            planes follow a smooth mesh instead of folding, 0..1 (default 0.03; not on
                            a noisy upload's first lay, see --relay)
  --max-iterations N        Gauss-Newton iteration cap (default 100)
  --duality auto|dupin|tangent
                            initial hexagonal mesh: Dupin duality (§6), tangent duality (§4.1), or
                            auto (default): Dupin, and tangent as well where that solve stalls or
                            leaves faces crossing themselves; the better is kept (dualityUsed)
  --solver local|planes|volumes
                            planarity solver: per-face planes by block coordinate descent (default,
                            fastest), per-face planes by Gauss-Newton with Schur elimination (Ceres),
                            or the paper's tetrahedron volumes by Gauss-Newton (Ceres, reference)
  --folds prevent|allow     the local solver keeps simple faces simple (default; where only folding
                            reaches planarity it stops short and says so) or lets them fold
  --surface-fit on|off      once planar, shift every face plane along its normal (the faces stay
                            exactly planar) to bring the vertices closer to the surface, and put
                            nodes on fewer than three face planes nearest to it along the directions
                            those planes leave free, the boundary nodes onto the boundary curve
                            (report: boundaryOffset) (default on)
  --split-boundary on|off   a boundary panel left off planar (every face away from it planar), or one
                            that crosses itself, is cut in two along its best diagonal and the solve
                            goes on; so are up to 8 interior faces left off planar, or all of
                            them on a surface laid in several systems of rows or where the solve
                            stalled (at most 1 in 20 faces) (default on)
  --cut-share S             the largest share of the interior faces, 0-1, that may be cut in two so
                            that the mesh comes out planar (each cut makes two nodes of four faces;
                            default 0.1): on an upload that folds more (the noisy shared models fold
                            11-28 % of their faces) a larger share gives a planar mesh with more such
                            nodes where the default leaves it off planar (exit 2)
  --clip-boundary on|off    once solved, clip the boundary panels to the surface's boundary curve:
                            their boundary edges follow the curve projected onto each panel's plane,
                            so the edge panels can be cut as drawn (report: boundaryClip) (default on)
  --out FILE                write the P-Hex mesh (for triangulate: the triangulation, OBJ)
  --format obj|ply|json     output format (default from the extension, else obj); json carries
                            the per-face metrics
  --panels FILE.svg|.csv    write the faces laid flat, true to size, for cutting: an SVG sheet of
                            outlines labelled P1..Pn (face n of the mesh, seen from its normal side)
                            or the panel schedule as CSV (corners, area, perimeter, planarity, plane,
                            edge lengths, corner angles, flat outline)
  --panel-gap G             space between panels on the SVG sheet, in the mesh's units (default a
                            quarter of the mean edge length)
  --panel-width W           width of the SVG sheet (default: about square)
  --panel-unit mm|cm|m|in   the mesh's length unit: the SVG sheet gets its true size for CAD and print
                            (default none: viewers fit it to the window)
  --beams FILE.csv          write the beam schedule: one row per edge with its nodes, length, the
                            panels either side and the fold between them (degrees, + ridge, - valley)
  --offset D                the offset of the P-Hex mesh at face distance D (either side, not 0; > 0
                            towards the normals): every face plane moved by D, each node along its axis
  --offset-mesh FILE        write that offset: .obj or .ply (its vertices and faces in the P-Hex mesh's
                            order, so the two files pair up line by line) or .glb / .gltf
  --beam-height H           height of the beams behind the panels (face distance; > 0, default a fifth
                            of the mean edge): one planar quad per edge, between the mesh and its offset
                            at -H; with --beams the schedule gains each beam's heights, plane, planarity,
                            twist and quad corners
  --beam-width W            width of the beams in the solid model (> 0, default a quarter of H)
  --panel-thickness T       thickness of the panels in the solid model (> 0, default a fiftieth of the
                            mean edge)
  --structure FILE          write the structure as a solid model: panels with their thickness and beams
                            with their height and width, .glb / .gltf (meshes panels, beams, axes) or
                            .obj (an object per panel P<n> and per beam B<k>)
  --nodes FILE.csv          write the node schedule: position, axis, the panels at the node and the
                            angles between axis and panels; nodes of four or more panels and folded ones
                            named (see the report's structure notes)
  --triangulation FILE.obj  write the triangulation as OBJ
  --initial FILE.obj        write the mesh before optimization as OBJ
  --report FILE.json        write counts, planarity, iterations and timings as JSON
  --threads N               threads for the parts that split into independent work (trial lays, flow
                            lines, curvature fits, closest points, plane fits, measures); 0 (default):
                            the PHEX_THREADS environment variable, else the machine's threads, at most
                            8. The meshes are the same bits whatever the count
  --quiet                   no progress on stderr

Options of `phex curvature`:
  --mesh FILE               a triangle mesh (OBJ, OFF, PLY or STL, ASCII or binary); curvature is
                            estimated by jet fitting; rows follow the file's vertex order (STL: distinct
                            corners in order of first appearance; unused vertices are left out)
  --surface NAME            or an analytic surface (exact curvature), sampled on a regular lattice
  --param NAME=VALUE        surface parameter (repeatable)
  --faces N                 lattice size for --surface (default 2000 vertices)
  --out FILE.csv            output, header x,y,z,k1,k2,d1x,d1y,d1z,d2x,d2y,d2z (k1 >= k2, unit d1, d2;
                            curvature > 0 where the surface bends away from its outward/upward normal)

Exit status: 0 on success, 1 when the input or a parameter is wrong (the message says which),
2 when the result misses the planarity goal, has self-intersecting faces or a node off the surface by
over 1 % of the bounding-box diagonal and a mean edge, 3 on internal errors.
)";

[[noreturn]] void usage(const std::string& msg) {
  throw phex::Error(phex::ErrorCode::InvalidParameter, msg + " (see phex --help)");
}

double parseNumber(const std::string& opt, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v)) usage(opt + " expects a number, got '" + text + "'");
  return v;
}

// A two-way switch: true for `yes`, false for `no`, else Error(InvalidParameter) naming the option.
bool parseSwitch(const std::string& opt, const std::string& text, const char* yes, const char* no) {
  if (text != yes && text != no)
    throw phex::Error(phex::ErrorCode::InvalidParameter, opt + " must be " + yes + " or " + no + " (got '" + text + "')");
  return text == yes;
}

int parseInt(const std::string& opt, const std::string& text) {
  const double v = parseNumber(opt, text);
  if (v != std::floor(v) || std::abs(v) > 2e9) usage(opt + " expects an integer, got '" + text + "'");
  return static_cast<int>(v);
}

// High-water mark of this process's resident memory (Linux reports kilobytes).
double peakMemoryMB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

json triangulationJson(const phex::Triangulation& t, const phex::TriangulationCheck& c) {
  json valence = json::object();
  for (const auto& [k, count] : c.interiorValence) valence[std::to_string(k)] = count;
  // The global method's singular points of the field: where and by how many sixths of a turn it turns about them.
  json singular = json::array();
  for (const phex::FieldSingularity& s : t.singularities)
    singular.push_back({{"position", {s.position.x(), s.position.y(), s.position.z()}}, {"index", s.index}});
  return {{"vertices", t.mesh.V.rows()},
          {"triangles", t.mesh.F.rows()},
          {"interiorVertices", c.interiorVertices},
          {"regularFraction", c.regularFraction},
          {"interiorValence", valence},
          {"invalidStars", c.invalidStars},
          {"parabolicStars", c.parabolicStars.size()},
          {"coverage", c.coverage},
          {"systems", t.systems},
          {"singularities", singular},
          {"edgeLength", {{"min", c.edgeMin}, {"max", c.edgeMax}, {"mean", c.edgeMean}}},
          {"notes", t.notes}};
}

// The P-Hex mesh with its per-face metrics, for `--format json`.
json meshJson(const phex::PipelineResult& r) {
  json vertices = json::array(), faces = json::array();
  for (int v = 0; v < r.hex.V.rows(); ++v) vertices.push_back({r.hex.V(v, 0), r.hex.V(v, 1), r.hex.V(v, 2)});
  for (int f = 0; f < r.hex.faceCount(); ++f) faces.push_back(std::vector<int>(r.hex.face(f), r.hex.face(f) + r.hex.faceSize(f)));
  const phex::MeshMetrics& m = r.metrics;
  return {{"vertices", vertices},
          {"faces", faces},
          {"faceMetrics",
           {{"planarity", m.planarity}, {"planarityDiagonals", m.planarityDiagonals}, {"selfIntersecting", m.selfIntersecting},
            {"convex", m.convex}, {"convexityMismatch", m.convexityMismatch}, {"regularity", m.regularity},
            {"area", m.faceArea}, {"boundary", r.dual.boundaryFace}}},
          {"vertexMetrics", {{"surfaceDistance", m.surfaceDistance}}}};
}

json reportJson(const phex::PipelineParams& p, const phex::PipelineResult& r) {
  json bySize = json::object();
  for (const auto& [size, count] : r.metrics.facesBySize) bySize[std::to_string(size)] = count;
  json valence = json::object();
  for (const auto& [k, count] : r.metrics.vertexValence) valence[std::to_string(k)] = count;
  json timings = json::object();
  for (const auto& t : r.timings) timings[t.stage] = t.milliseconds;
  timings["total"] = r.totalMilliseconds;
  json log = json::array();
  for (const auto& it : r.solve.log)
    log.push_back({{"round", it.round}, {"iteration", it.iteration}, {"lambda", it.lambda},
                   {"objective", it.objective}, {"planarityMax", it.planarityMax}, {"milliseconds", it.milliseconds}});
  json params = {{"surface", p.mesh ? p.mesh->name : p.surface}, {"method", phex::triangulationMethodName(p.method)},
                 {"field", p.field}, {"lowerBound", p.lowerBound}, {"surfaceParams", p.surfaceParams}, {"faces", p.faces}, {"cell", p.cell},
                 {"tolerance", p.tolerance}, {"lambda", p.lambda}, {"mu", p.mu}, {"maxIterations", p.maxIterations},
                 {"duality", phex::dualityName(p.duality)}, {"solver", phex::methodName(p.solver)},
                 {"folds", p.preventFolds ? "prevent" : "allow"}, {"surfaceFit", p.fitSurface ? "on" : "off"},
                 {"splitBoundary", p.splitBoundaryPanels ? "on" : "off"}, {"clipBoundary", p.clipBoundary ? "on" : "off"},
                 {"foldFlips", p.foldFlips ? "on" : "off"},
                 {"dislocations", p.cancelDislocations ? "cancel" : "keep"},
                 {"principalField", p.principalTrial ? "try" : "off"}, {"anisotropy", p.anisotropy}, {"alignment", p.alignment},
                 {"curvatureSizing", p.curvatureSizing}, {"curvatureFloor", p.curvatureFloor}, {"relay", p.relay ? "on" : "off"},
                 {"fairness", p.fairness}, {"cutShare", p.cutShare}};
  if (p.start) params["start"] = {p.start->x(), p.start->y(), p.start->z()};
  if (p.direction) params["direction"] = {p.direction->x(), p.direction->y(), p.direction->z()};
  return {{"phex", "0.1.0"},
          {"params", params},
          {"triangulation", triangulationJson(r.triangulation, r.check)},
          {"methodUsed", phex::triangulationMethodName(r.method)},
          {"fieldUsed", r.field},
          {"farNodes", r.farNodes},
          {"coverageGap", r.coverageGap},
          {"boundaryOffset", {{"max", r.boundaryOffset.max}, {"median", r.boundaryOffset.median},
                              {"nodes", r.boundaryOffset.nodes}}},
          {"boundaryClip", {{"panels", r.boundaryClip.panels}, {"skipped", r.boundaryClip.skipped},
                            {"nodesMoved", r.boundaryClip.nodesMoved}, {"nodesAdded", r.boundaryClip.nodesAdded},
                            {"nodesRemoved", r.boundaryClip.nodesRemoved}, {"fillers", r.boundaryClip.fillers},
                            {"cutDropped", r.boundaryClip.cutDropped},
                            {"removed", r.boundaryClip.removed},
                            {"gapMax", r.boundaryClip.gapMax}}},
          {"mesh", {{"vertices", r.metrics.vertexCount}, {"faces", r.metrics.faceCount}, {"facesBySize", bySize}}},
          {"planarity", {{"max", r.metrics.planarityMax}, {"mean", r.metrics.planarityMean},
                         {"initialMax", r.solve.initialPlanarityMax}}},
          {"invalidFaces", r.metrics.selfIntersectingCount},
          {"boundaryFaces", std::count(r.dual.boundaryFace.begin(), r.dual.boundaryFace.end(), 1)},
          {"interiorHexagonFraction", r.interiorHexagonFraction},
          {"convexityMismatches", r.metrics.convexityMismatchCount},
          {"parabolicFaces", r.metrics.parabolicFaceCount},
          {"regularityMean", r.metrics.regularityMean},
          {"planarityDiagonalsMaxPercent", *std::max_element(r.metrics.planarityDiagonals.begin(), r.metrics.planarityDiagonals.end())},
          {"edgeLength", {{"min", r.metrics.edgeLengthMin}, {"max", r.metrics.edgeLengthMax}, {"mean", r.metrics.edgeLengthMean},
                          {"short", r.metrics.shortEdgeCount}}},
          {"faceArea", {{"min", r.metrics.faceAreaMin}, {"max", r.metrics.faceAreaMax}, {"mean", r.metrics.faceAreaMean}}},
          {"vertexValence", valence},
          {"surfaceDistance", {{"max", r.metrics.surfaceDistanceMax}, {"mean", r.metrics.surfaceDistanceMean}}},
          {"displacementMax", r.solve.displacementMax},
          {"dualFallbacks", r.dual.fallbackCount},
          {"dualUntangled", r.dual.untangled},
          {"dualityUsed", phex::dualityName(r.duality)},
          {"origin", {r.origin.x(), r.origin.y(), r.origin.z()}},
          {"solver", {{"iterations", r.solve.iterations}, {"rounds", r.solve.rounds}, {"converged", r.solve.converged},
                      {"boundaryPanelsSplit", r.boundaryPanelsSplit}, {"interiorFacesSplit", r.interiorFacesSplit},
                      {"foldsAllowed", r.foldsAllowed}, {"method", phex::methodName(r.solverUsed)}, {"log", log}}},
          {"relay", {{"tried", r.relay.tried}, {"kept", r.relay.kept}, {"globally", r.relay.globally},
                     {"anisotropy", r.relay.anisotropy}, {"curvatureFloor", r.relay.curvatureFloor},
                     {"firstReached", r.relay.firstReached}, {"firstNodesOfFour", r.relay.firstNodesOfFour},
                     {"firstCoverageGap", r.relay.firstCoverageGap}, {"trials", r.relay.trials},
                     {"trialNodesOfFour", r.relay.trialNodesOfFour}, {"trialShare", r.relay.trialShare},
                     {"noisyRepairs", r.relay.noisyRepairs}, {"noisyRepairsKept", r.relay.noisyRepairsKept}}},
          {"surfaceFit", {{"applied", r.solve.surfaceFitted}, {"distanceBefore", r.solve.surfaceDistanceBefore},
                          {"distanceAfter", r.solve.surfaceDistanceAfter}, {"freeNodesSettled", r.solve.freeNodesSettled},
                          {"boundaryNodesPlaced", r.solve.boundaryNodesPlaced}}},
          {"milliseconds", timings},
          {"threads", phex::threadCount()},
          {"peakMemoryMB", peakMemoryMB()}};
}

// The bytes of an input mesh file; its format is taken from the extension (or sniffed).
phex::MeshInput readInput(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw phex::Error(phex::ErrorCode::Io, "cannot open '" + path + "' for reading");
  phex::MeshInput mesh;
  mesh.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  mesh.name = path;
  const auto dot = path.find_last_of('.');
  if (dot != std::string::npos) {
    std::string ext = path.substr(dot + 1);
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == "obj" || ext == "off" || ext == "ply" || ext == "stl") mesh.format = ext;
  }
  return mesh;
}

// `phex run` and `phex triangulate` (which stops after the first stage) share their options.
// "X,Y,Z" -> a vector, for --start and --direction.
phex::Vec3 parseVector(const std::string& opt, const std::string& text) {
  phex::Vec3 v;
  std::size_t from = 0;
  for (int k = 0; k < 3; ++k) {
    const std::size_t comma = text.find(',', from);
    if ((k < 2) != (comma != std::string::npos)) usage(opt + " expects X,Y,Z, got '" + text + "'");
    v[k] = parseNumber(opt, text.substr(from, k < 2 ? comma - from : std::string::npos));
    from = comma + 1;
  }
  return v;
}

// The file type of `path` by its extension, lower case ("" without one).
std::string extensionOf(const std::string& path) {
  const auto dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

json optionalNumber(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }

// The structure's part of the report: nodes by kind, the nodes named, the boundary rule, ranges and measures.
json structureJson(const phex::Structure& s, const phex::StructureOptions& o, double milliseconds) {
  const phex::NodeAxes& ax = s.axes;
  json kinds = json::object();
  for (phex::NodeKind k : {phex::NodeKind::Cone, phex::NodeKind::Boundary, phex::NodeKind::Corner, phex::NodeKind::BestFit,
                           phex::NodeKind::Folded, phex::NodeKind::Free})
    kinds[phex::nodeKindName(k)] = std::count(ax.kind.begin(), ax.kind.end(), k);
  auto ids = [](const std::vector<int>& nodes) {
    json list = json::array();
    for (int v : nodes) list.push_back(v + 1);
    return list;
  };
  json notes = ax.notes;
  for (const std::string& n : s.notes) notes.push_back(n);
  return {{"nodes", kinds}, {"bestFitNodes", ids(ax.bestFit)}, {"foldedNodes", ids(ax.folded)},
          {"boundaryBeams", ax.boundaryBeams}, {"boundaryBeamsPlanar", ax.boundaryBeamsPlanar},
          {"boundaryRuns", ax.boundaryRuns}, {"boundaryRunsPlanar", ax.boundaryRunsPlanar},
          {"boundaryTwistMaxDeg", ax.boundaryTwistMaxDeg}, {"boundaryTurnMaxDeg", ax.boundaryTurnMaxDeg},
          {"offsetRange", {optionalNumber(ax.offsetMin), optionalNumber(ax.offsetMax)}},
          {"offset", o.offset ? json(*o.offset) : json(nullptr)}, {"beamHeight", s.beams.height},
          {"beamWidth", s.beamWidth}, {"panelThickness", s.panelThickness}, {"beams", s.beams.beams.size()},
          {"beamLength", s.beams.length}, {"beamPlanarityMax", s.beams.planarityMax},
          {"interiorBeamPlanarityMax", s.beams.interiorPlanarityMax}, {"nodesMovedOntoPlanesMax", ax.snapMax},
          {"notes", notes}, {"milliseconds", milliseconds}};
}

int run(const std::vector<std::string>& args, bool triangulateOnly) {
  phex::PipelineParams p;
  std::string out, tri, initial, reportPath, format, panels, beams, offsetMesh, structure, nodes;
  phex::StructureOptions structureOptions;
  phex::PanelSheetOptions sheet;
  bool quiet = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) usage(a + " needs a value");
      return args[++i];
    };
    if (a == "--surface") p.surface = value();
    else if (a == "--mesh") p.mesh = readInput(value());
    else if (a == "--method") p.method = phex::parseTriangulationMethod(value());
    else if (a == "--field") p.field = value();
    else if (a == "--lower-bound") p.lowerBound = parseNumber(a, value());
    else if (a == "--anisotropy") p.anisotropy = parseNumber(a, value());
    else if (a == "--fold-flips") p.foldFlips = parseSwitch(a, value(), "on", "off");
    else if (a == "--dislocations") p.cancelDislocations = parseSwitch(a, value(), "cancel", "keep");
    else if (a == "--principal-field") p.principalTrial = parseSwitch(a, value(), "try", "off");
    else if (a == "--relay") p.relay = parseSwitch(a, value(), "on", "off");
    else if (a == "--curvature-floor") p.curvatureFloor = parseNumber(a, value());
    else if (a == "--fairness") p.fairness = parseNumber(a, value());
    else if (a == "--cut-share") p.cutShare = parseNumber(a, value());
    else if (a == "--alignment") p.alignment = parseNumber(a, value());
    else if (a == "--curvature-sizing") p.curvatureSizing = parseNumber(a, value());
    else if (a == "--start") p.start = parseVector(a, value());
    else if (a == "--direction") p.direction = parseVector(a, value());
    else if (a == "--param") {
      const std::string& kv = value();
      const auto eq = kv.find('=');
      if (eq == std::string::npos || eq == 0) usage("--param expects NAME=VALUE, got '" + kv + "'");
      p.surfaceParams[kv.substr(0, eq)] = parseNumber("--param " + kv.substr(0, eq), kv.substr(eq + 1));
    } else if (a == "--faces") p.faces = parseInt(a, value());
    else if (a == "--cell") p.cell = parseNumber(a, value());
    else if (a == "--tolerance") p.tolerance = parseNumber(a, value());
    else if (a == "--lambda") p.lambda = parseNumber(a, value());
    else if (a == "--mu") p.mu = parseNumber(a, value());
    else if (a == "--max-iterations") p.maxIterations = parseInt(a, value());
    else if (a == "--duality") p.duality = phex::parseDuality(value());
    else if (a == "--solver") p.solver = phex::parseMethod(value());
    else if (a == "--folds") p.preventFolds = parseSwitch(a, value(), "prevent", "allow");
    else if (a == "--surface-fit") p.fitSurface = parseSwitch(a, value(), "on", "off");
    else if (a == "--split-boundary") p.splitBoundaryPanels = parseSwitch(a, value(), "on", "off");
    else if (a == "--clip-boundary") p.clipBoundary = parseSwitch(a, value(), "on", "off");
    else if (a == "--out") out = value();
    else if (a == "--triangulation") tri = value();
    else if (a == "--panels") panels = value();
    else if (a == "--beams") beams = value();
    else if (a == "--offset") structureOptions.offset = parseNumber(a, value());
    else if (a == "--offset-mesh") offsetMesh = value();
    else if (a == "--beam-height") structureOptions.beamHeight = parseNumber(a, value());
    else if (a == "--beam-width") structureOptions.beamWidth = parseNumber(a, value());
    else if (a == "--panel-thickness") structureOptions.panelThickness = parseNumber(a, value());
    else if (a == "--structure") structure = value();
    else if (a == "--nodes") nodes = value();
    else if (a == "--panel-gap") sheet.gap = parseNumber(a, value());
    else if (a == "--panel-width") sheet.width = parseNumber(a, value());
    else if (a == "--panel-unit") sheet.unit = value();
    else if (a == "--initial") initial = value();
    else if (a == "--report") reportPath = value();
    else if (a == "--format") format = value();
    else if (a == "--quiet") quiet = true;
    else if (a == "--threads") {
      const int n = parseInt(a, value());
      if (n < 0) usage("--threads must be 0 (the default) or more, got " + std::to_string(n));
      phex::setThreadCount(n);
    } else usage("unknown option '" + a + "'");
  }
  if (p.cell != 0 && !(p.cell > 0)) usage("--cell must be positive");
  if (format.empty()) {
    const auto dot = out.find_last_of('.');
    const std::string ext = dot == std::string::npos ? "" : out.substr(dot + 1);
    format = ext == "ply" || ext == "json" ? ext : "obj";
  }
  if (format != "obj" && format != "ply" && format != "json") usage("--format must be obj, ply or json, got '" + format + "'");
  const auto dot = panels.find_last_of('.');
  const std::string panelFormat = dot == std::string::npos ? "" : panels.substr(dot + 1);
  if (!panels.empty() && panelFormat != "svg" && panelFormat != "csv")
    usage("--panels writes .svg or .csv, got '" + panels + "'");
  if (!panels.empty() && triangulateOnly) usage("--panels needs phex run (a triangulation has no panels)");
  if (!beams.empty() && triangulateOnly) usage("--beams needs phex run");
  const bool structureAsked = structureOptions.offset || structureOptions.beamHeight || structureOptions.beamWidth ||
                              structureOptions.panelThickness || !offsetMesh.empty() || !structure.empty() || !nodes.empty();
  if (structureAsked && triangulateOnly) usage("the structure options (--offset, --beam-height, --structure, --nodes, ...) need phex run");
  if (!offsetMesh.empty() && !structureOptions.offset) usage("--offset-mesh needs --offset D (the face distance)");
  if (structureOptions.offset && offsetMesh.empty()) usage("--offset needs --offset-mesh FILE to write the offset to");
  const std::string offsetFormat = extensionOf(offsetMesh), structureFormat = extensionOf(structure);
  if (!offsetMesh.empty() && offsetFormat != "obj" && offsetFormat != "ply" && offsetFormat != "glb" && offsetFormat != "gltf")
    usage("--offset-mesh writes .obj, .ply, .glb or .gltf, got '" + offsetMesh + "'");
  if (!structure.empty() && structureFormat != "glb" && structureFormat != "gltf" && structureFormat != "obj")
    usage("--structure writes .glb, .gltf or .obj, got '" + structure + "'");
  phex::validate(structureOptions);
  if (!(sheet.gap >= 0)) usage("--panel-gap must be 0 or more");
  if (!(sheet.width >= 0)) usage("--panel-width must be 0 or more");
  if (!sheet.unit.empty() && sheet.unit != "mm" && sheet.unit != "cm" && sheet.unit != "m" && sheet.unit != "in")
    usage("--panel-unit must be mm, cm, m or in, got '" + sheet.unit + "'");
  phex::validate(p);
  phex::threadCount();  // a malformed PHEX_THREADS fails here, before any output is opened
  // Fail on an unwritable output before computing anything.
  for (const std::string* path : {&out, &tri, &initial, &reportPath, &panels, &beams, &offsetMesh, &structure, &nodes})
    if (!path->empty()) phex::writeTextFile(*path, "");

  phex::ProgressFn progress;
  if (!quiet)
    progress = [](const phex::Progress& pr) { std::cerr << "[" << pr.stage << "] " << pr.message << "\n"; };
  if (triangulateOnly) {
    const auto t0 = std::chrono::steady_clock::now();
    const phex::TriangulationStage t = phex::triangulate(p, progress);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!out.empty()) phex::writeTextFile(out, phex::toObj(t.triangulation.mesh));
    json rep = triangulationJson(t.triangulation, t.check);
    rep["methodUsed"] = phex::triangulationMethodName(t.method);
    rep["fieldUsed"] = t.field;
    rep["milliseconds"] = ms;
    if (!reportPath.empty()) phex::writeTextFile(reportPath, rep.dump(2) + "\n");
    std::cout << "triangles " << t.triangulation.mesh.F.rows() << ", interior valence 6 " << t.check.regularFraction * 100
              << " %, invalid stars " << t.check.invalidStars.size() << ", " << ms << " ms\n";
    if (!t.check.invalidStars.empty())
      std::cerr << "phex: " << t.check.invalidStars.size()
                << " stars fail Propositions 4/5 (their dual faces may cross themselves): the triangulation is written "
                   "as it stands (exit 2); the report lists them and its notes say where laying fell short\n";
    return t.check.invalidStars.empty() ? 0 : 2;
  }
  const phex::PipelineResult r = phex::runPipeline(p, progress);
  if (!out.empty())
    phex::writeTextFile(out, format == "ply" ? phex::toPly(r.hex) : format == "json" ? meshJson(r).dump() : phex::toObj(r.hex));
  if (!tri.empty()) phex::writeTextFile(tri, phex::toObj(r.triangulation.mesh));
  if (!initial.empty()) phex::writeTextFile(initial, phex::toObj(r.initial));
  if (!panels.empty()) {
    const std::vector<phex::Panel> flat = phex::flattenPanels(r.hex);
    phex::writeTextFile(panels, panelFormat == "svg" ? phex::panelsSvg(flat, sheet) : phex::panelsCsv(flat));
  }
  json rep = reportJson(p, r);
  if (structureAsked) {
    // The structure on the panels: axes, the offset, beams and the solid model (phex/structure.hpp).
    const auto t0 = std::chrono::steady_clock::now();
    const phex::Structure st = phex::buildStructure(r.hex, structureOptions);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!offsetMesh.empty()) {
      if (offsetFormat == "glb" || offsetFormat == "gltf")
        phexcli::writeGltf(offsetMesh, {phexcli::polygonPart("offset", *st.offset, st.model.origin)}, st.model.origin,
                           {{"faces", st.offset->faceCount()}});
      else
        phex::writeTextFile(offsetMesh, offsetFormat == "ply" ? phex::toPly(*st.offset) : phex::toObj(*st.offset));
    }
    if (!structure.empty()) {
      if (structureFormat == "obj") {
        phex::writeTextFile(structure, phex::toObj(st.model));
      } else {
        auto part = [](const std::string& name, const phex::SolidPart& solid, std::array<double, 4> color) {
          phexcli::GltfPart g;
          g.name = name, g.V = solid.V, g.color = color;
          g.index.assign(solid.F.data(), solid.F.data() + solid.F.size());
          return g;
        };
        phexcli::GltfPart axes;
        axes.name = "axes", axes.V = st.model.axes, axes.lines = true, axes.color = {0.8, 0.1, 0.1, 1};
        axes.index.resize(st.model.axes.rows());
        std::iota(axes.index.begin(), axes.index.end(), 0u);
        phexcli::writeGltf(structure,
                           {part("panels", st.model.panels, {0.55, 0.75, 0.9, 0.6}), part("beams", st.model.beams, {0.35, 0.37, 0.4, 1}), axes},
                           st.model.origin, {{"panels", st.model.panels.elements}, {"beams", st.model.beams.elements}, {"trianglesPerBeam", 12}});
      }
    }
    if (!nodes.empty()) phex::writeTextFile(nodes, phex::nodesCsv(r.hex, st.axes));
    if (!beams.empty())
      phex::writeTextFile(beams, structureOptions.beamHeight ? phex::beamsCsv(r.hex, st.axes, st.beams) : phex::beamsCsv(r.hex));
    rep["structure"] = structureJson(st, structureOptions, ms);
    if (!quiet)
      for (const auto* list : {&st.axes.notes, &st.notes})
        for (const std::string& note : *list) std::cerr << "phex: structure: " << note << "\n";
  } else if (!beams.empty()) {
    phex::writeTextFile(beams, phex::beamsCsv(r.hex));
  }
  if (!reportPath.empty()) phex::writeTextFile(reportPath, rep.dump(2) + "\n");
  std::cout << "faces " << r.metrics.faceCount << ", planarity max " << r.metrics.planarityMax << ", invalid faces "
            << r.metrics.selfIntersectingCount << ", iterations " << r.solve.iterations << ", " << r.totalMilliseconds
            << " ms\n";
  if (!r.solve.converged)
    std::cerr << "phex: not converged: planarity max " << r.metrics.planarityMax << " is above the tolerance "
              << p.tolerance << " after " << r.solve.iterations
              << " iterations; the mesh is written as it stands (exit 2). The report's notes say where the "
                 "triangulation fell short (and, where more faces cut would make it planar, the --cut-share that "
                 "does); another method, field or face count may do\n";
  if (r.metrics.selfIntersectingCount > 0)
    std::cerr << "phex: " << r.metrics.selfIntersectingCount
              << " faces cross themselves: the mesh is written as it stands (exit 2)\n";
  const bool far = r.farNodes > 0;
  if (far)
    std::cerr << "phex: " << r.farNodes << " P-Hex nodes lie over " << 100 * phex::kFarNodeDistance
              << " % of the diagonal and a mean edge off the surface, the farthest " << 100 * r.metrics.surfaceDistanceMax
              << " %: the mesh is written as it stands (exit 2); the report's notes say where\n";
  return (r.solve.converged && r.metrics.selfIntersectingCount == 0 && !far) ? 0 : 2;
}

int curvature(const std::vector<std::string>& args) {
  std::string mesh, surface, out;
  phex::SurfaceParams params;
  int faces = 2000;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) usage(a + " needs a value");
      return args[++i];
    };
    if (a == "--mesh") mesh = value();
    else if (a == "--surface") surface = value();
    else if (a == "--param") {
      const std::string& kv = value();
      const auto eq = kv.find('=');
      if (eq == std::string::npos || eq == 0) usage("--param expects NAME=VALUE, got '" + kv + "'");
      params[kv.substr(0, eq)] = parseNumber("--param " + kv.substr(0, eq), kv.substr(eq + 1));
    } else if (a == "--faces") faces = parseInt(a, value());
    else if (a == "--out") out = value();
    else usage("unknown option '" + a + "'");
  }
  if (mesh.empty() == surface.empty()) usage("phex curvature needs exactly one of --mesh FILE or --surface NAME");
  if (out.empty()) usage("phex curvature needs --out FILE.csv");
  if (faces < 12 || faces > phex::kMaxFaces) usage("--faces must be between 12 and " + std::to_string(phex::kMaxFaces));
  phex::writeTextFile(out, "");  // fail on an unwritable output before the work
  std::vector<phex::LocalGeometry> rows;
  if (!mesh.empty()) {
    const phex::MeshSurface s(phex::readMesh(mesh), mesh);
    rows = s.vertexGeometries();
  } else {
    const phex::ParametricSurfacePtr s = phex::makeSurface(surface, params);
    const phex::Triangulation t = phex::latticeTriangulation(*s, phex::cellForFaceCount(*s, faces));
    for (const phex::Vec2& uv : t.uv) rows.push_back(s->geometryAt(uv.x(), uv.y()));
  }
  phex::writeTextFile(out, phex::curvatureCsv(rows));
  std::cout << rows.size() << " vertices\n";
  return 0;
}

int surfaces() {
  for (const auto& s : phex::analyticSurfaces()) {
    std::cout << s.name << " — " << s.description << " (method auto: " << s.method
              << (s.method == "prespecified" || s.method == "progressive" ? ", field " + s.field : std::string()) << ")\n";
    for (const auto& prm : s.parameters)
      std::cout << "    " << prm.name << " = " << prm.defaultValue << "  [" << prm.min << ", " << prm.max << "]  "
                << prm.description << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
      std::cout << kHelp;
      return args.empty() ? 1 : 0;
    }
    if (args[0] == "--version") return std::cout << "phex 0.1.0\n", 0;
    const std::string cmd = args[0];
    args.erase(args.begin());
    if (cmd == "run") return run(args, false);
    if (cmd == "triangulate") return run(args, true);
    if (cmd == "surfaces") return surfaces();
    if (cmd == "curvature") return curvature(args);
    usage("unknown command '" + cmd + "'");
  } catch (const phex::Error& e) {
    std::cerr << "phex: error: " << e.what() << "\n";
    return e.code() == phex::ErrorCode::Internal ? 3 : 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "phex: error: out of memory: ask for fewer faces or a larger cell\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "phex: internal error: " << e.what() << "\n";
    return 3;
  }
}
