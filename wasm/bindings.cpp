// phex — embind bindings. This file only converts between JS values and the core's plain data;
// it computes nothing. Every C++ exception is caught here and returned as {ok: false, code, message},
// which the ES-module wrapper (js/phex.js) throws as a PHexError.
#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <phex/error.hpp>
#include <phex/panels.hpp>
#include <phex/pipeline.hpp>
#include <phex/structure.hpp>

#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

using emscripten::val;

namespace {

// Copies a contiguous array into a new JS typed array (the wasm heap may move, so never hand out views).
template <typename T>
val copyArray(const char* type, const T* data, std::size_t n) {
  return val::global(type).new_(emscripten::typed_memory_view(n, data)).template call<val>("slice");
}

val meshToJs(const phex::PolyMesh& m) {
  val out = val::object();
  out.set("positions", copyArray("Float64Array", m.V.data(), static_cast<std::size_t>(m.V.size())));
  std::vector<std::uint32_t> offsets(m.offsets.begin(), m.offsets.end()), indices(m.indices.begin(), m.indices.end());
  out.set("faceOffsets", copyArray("Uint32Array", offsets.data(), offsets.size()));
  out.set("faceIndices", copyArray("Uint32Array", indices.data(), indices.size()));
  return out;
}

bool has(const val& o, const char* key) { return o.hasOwnProperty(key) && !o[key].isUndefined() && !o[key].isNull(); }

double number(const val& o, const char* key) {
  const val v = o[key];
  if (v.typeOf().as<std::string>() != "number")
    throw phex::Error(phex::ErrorCode::InvalidParameter, std::string(key) + " must be a number");
  return v.as<double>();
}

int integer(const val& o, const char* key) {
  const double d = number(o, key);
  if (!std::isfinite(d) || d != std::floor(d) || std::abs(d) > 2e9)
    throw phex::Error(phex::ErrorCode::InvalidParameter, std::string(key) + " must be an integer (got " + std::to_string(d) + ")");
  return static_cast<int>(d);
}

phex::Vec3 vector3(const val& o, const char* key) {
  const val v = o[key];
  if (!val::global("Array").call<bool>("isArray", v) || v["length"].as<unsigned>() != 3)
    throw phex::Error(phex::ErrorCode::InvalidParameter, std::string(key) + " must be an array [x, y, z]");
  phex::Vec3 x;
  for (unsigned i = 0; i < 3; ++i) {
    if (v[i].typeOf().as<std::string>() != "number")
      throw phex::Error(phex::ErrorCode::InvalidParameter, std::string(key) + " must be an array of three numbers");
    x[i] = v[i].as<double>();
  }
  return x;
}

std::string text(const val& o, const char* key) {
  if (o[key].typeOf().as<std::string>() != "string")
    throw phex::Error(phex::ErrorCode::InvalidParameter, std::string(key) + " must be a string");
  return o[key].as<std::string>();
}

// A two-way switch given as a string: true for `yes`, false for `no`, else Error(InvalidParameter) naming it.
bool switchValue(const val& o, const char* key, const char* yes, const char* no) {
  const std::string v = text(o, key);
  if (v != yes && v != no)
    throw phex::Error(phex::ErrorCode::InvalidParameter,
                      std::string(key) + " must be '" + yes + "' or '" + no + "' (got '" + v + "')");
  return v == yes;
}

phex::PipelineParams paramsFromJs(const val& o) {
  if (o.typeOf().as<std::string>() != "object" || o.isNull())
    throw phex::Error(phex::ErrorCode::InvalidParameter, "params must be an object");
  phex::PipelineParams p;
  if (has(o, "surface")) {
    p.surface = text(o, "surface");
  }
  if (has(o, "surfaceParams")) {
    const val sp = o["surfaceParams"];
    const val keys = val::global("Object").call<val>("keys", sp);
    for (unsigned i = 0; i < keys["length"].as<unsigned>(); ++i) {
      const std::string k = keys[i].as<std::string>();
      p.surfaceParams[k] = number(sp, k.c_str());
    }
  }
  if (has(o, "faces")) p.faces = integer(o, "faces");
  if (has(o, "cell")) p.cell = number(o, "cell");
  if (has(o, "tolerance")) p.tolerance = number(o, "tolerance");
  if (has(o, "lambda")) p.lambda = number(o, "lambda");
  if (has(o, "mu")) p.mu = number(o, "mu");
  if (has(o, "maxIterations")) p.maxIterations = integer(o, "maxIterations");
  if (has(o, "duality")) p.duality = phex::parseDuality(text(o, "duality"));
  if (has(o, "method")) p.method = phex::parseTriangulationMethod(text(o, "method"));
  if (has(o, "field")) p.field = text(o, "field");
  if (has(o, "lowerBound")) p.lowerBound = number(o, "lowerBound");
  if (has(o, "start")) p.start = vector3(o, "start");
  if (has(o, "direction")) p.direction = vector3(o, "direction");
  if (has(o, "mesh")) {
    const val bytes = o["mesh"];
    if (!bytes.instanceof(val::global("Uint8Array")))
      throw phex::Error(phex::ErrorCode::InvalidParameter, "mesh must be a Uint8Array of the file's bytes");
    phex::MeshInput mesh;
    mesh.bytes = emscripten::convertJSArrayToNumberVector<std::uint8_t>(bytes);
    if (has(o, "meshFormat")) mesh.format = text(o, "meshFormat");
    mesh.name = has(o, "meshName") ? text(o, "meshName") : "mesh";
    p.mesh = std::move(mesh);
  }
  if (has(o, "solver")) p.solver = phex::parseMethod(text(o, "solver"));
  if (has(o, "folds")) p.preventFolds = switchValue(o, "folds", "prevent", "allow");
  if (has(o, "surfaceFit")) p.fitSurface = switchValue(o, "surfaceFit", "on", "off");
  if (has(o, "splitBoundary")) p.splitBoundaryPanels = switchValue(o, "splitBoundary", "on", "off");
  if (has(o, "clipBoundary")) p.clipBoundary = switchValue(o, "clipBoundary", "on", "off");
  if (has(o, "anisotropy")) p.anisotropy = number(o, "anisotropy");
  if (has(o, "foldFlips")) p.foldFlips = switchValue(o, "foldFlips", "on", "off");
  if (has(o, "dislocations")) p.cancelDislocations = switchValue(o, "dislocations", "cancel", "keep");
  if (has(o, "principalField")) p.principalTrial = switchValue(o, "principalField", "try", "off");
  if (has(o, "alignment")) p.alignment = number(o, "alignment");
  if (has(o, "curvatureSizing")) p.curvatureSizing = number(o, "curvatureSizing");
  if (has(o, "curvatureFloor")) p.curvatureFloor = number(o, "curvatureFloor");
  if (has(o, "relay")) p.relay = switchValue(o, "relay", "on", "off");
  if (has(o, "fairness")) p.fairness = number(o, "fairness");
  if (has(o, "cutShare")) p.cutShare = number(o, "cutShare");
  return p;
}

val resultToJs(const phex::PipelineResult& r) {
  val out = val::object();
  out.set("ok", true);
  out.set("hex", meshToJs(r.hex));
  out.set("initial", meshToJs(r.initial));
  val tri = val::object();
  const phex::TriMesh& T = r.triangulation.mesh;
  tri.set("positions", copyArray("Float64Array", T.V.data(), static_cast<std::size_t>(T.V.size())));
  std::vector<std::uint32_t> tris(T.F.data(), T.F.data() + T.F.size());
  tri.set("triangles", copyArray("Uint32Array", tris.data(), tris.size()));
  // Traced direction-field curves as polylines: positions (x, y, z per point) and offsets (#lines + 1).
  std::vector<double> linePoints;
  std::vector<std::uint32_t> lineOffsets{0};
  for (const auto& line : r.triangulation.fieldLines) {
    for (const phex::Vec3& q : line) linePoints.insert(linePoints.end(), {q.x(), q.y(), q.z()});
    lineOffsets.push_back(static_cast<std::uint32_t>(linePoints.size() / 3));
  }
  val lines = val::object();
  lines.set("positions", copyArray("Float64Array", linePoints.data(), linePoints.size()));
  lines.set("offsets", copyArray("Uint32Array", lineOffsets.data(), lineOffsets.size()));
  tri.set("fieldLines", lines);
  // The global method's singular points: positions (x, y, z each) and their indices in sixths of a turn.
  const std::vector<phex::FieldSingularity>& singular = r.triangulation.singularities;
  std::vector<double> singularAt;
  std::vector<std::int32_t> singularIndex;
  for (const phex::FieldSingularity& s : singular) {
    singularAt.insert(singularAt.end(), {s.position.x(), s.position.y(), s.position.z()});
    singularIndex.push_back(s.index);
  }
  val singularities = val::object();
  singularities.set("positions", copyArray("Float64Array", singularAt.data(), singularAt.size()));
  singularities.set("index", copyArray("Int32Array", singularIndex.data(), singularIndex.size()));
  tri.set("singularities", singularities);
  val notes = val::array();
  for (const std::string& n : r.triangulation.notes) notes.call<void>("push", n);
  tri.set("notes", notes);
  tri.set("systems", r.triangulation.systems);
  const phex::TriangulationCheck& c = r.check;
  val check = val::object();
  check.set("interiorVertices", c.interiorVertices);
  check.set("regularFraction", c.regularFraction);
  std::vector<std::uint32_t> invalid(c.invalidStars.begin(), c.invalidStars.end());
  check.set("invalidStars", copyArray("Uint32Array", invalid.data(), invalid.size()));
  check.set("parabolicStars", static_cast<int>(c.parabolicStars.size()));
  check.set("edgeMin", c.edgeMin);
  check.set("edgeMax", c.edgeMax);
  check.set("edgeMean", c.edgeMean);
  check.set("coverage", c.coverage);
  tri.set("check", check);
  out.set("triangulation", tri);

  val metrics = val::object();
  const phex::MeshMetrics& m = r.metrics;
  metrics.set("planarity", copyArray("Float64Array", m.planarity.data(), m.planarity.size()));
  metrics.set("selfIntersecting", copyArray("Uint8Array", m.selfIntersecting.data(), m.selfIntersecting.size()));
  metrics.set("vertexCount", m.vertexCount);
  metrics.set("faceCount", m.faceCount);
  val bySize = val::object();
  for (const auto& [size, count] : m.facesBySize) bySize.set(std::to_string(size), count);
  metrics.set("facesBySize", bySize);
  metrics.set("planarityMax", m.planarityMax);
  metrics.set("planarityMean", m.planarityMean);
  metrics.set("selfIntersectingCount", m.selfIntersectingCount);
  metrics.set("planarityDiagonals", copyArray("Float64Array", m.planarityDiagonals.data(), m.planarityDiagonals.size()));
  metrics.set("convex", copyArray("Uint8Array", m.convex.data(), m.convex.size()));
  metrics.set("faceArea", copyArray("Float64Array", m.faceArea.data(), m.faceArea.size()));
  metrics.set("convexityMismatch", copyArray("Uint8Array", m.convexityMismatch.data(), m.convexityMismatch.size()));
  metrics.set("convexityMismatchCount", m.convexityMismatchCount);
  metrics.set("parabolicFaceCount", m.parabolicFaceCount);
  metrics.set("interiorHexagonFraction", r.interiorHexagonFraction);
  metrics.set("regularity", copyArray("Float64Array", m.regularity.data(), m.regularity.size()));
  metrics.set("regularityMean", m.regularityMean);
  metrics.set("boundaryFace", copyArray("Uint8Array", r.dual.boundaryFace.data(), r.dual.boundaryFace.size()));
  metrics.set("edgeLengthMin", m.edgeLengthMin);
  metrics.set("edgeLengthMax", m.edgeLengthMax);
  metrics.set("edgeLengthMean", m.edgeLengthMean);
  metrics.set("shortEdgeCount", m.shortEdgeCount);
  metrics.set("faceAreaMin", m.faceAreaMin);
  metrics.set("faceAreaMax", m.faceAreaMax);
  metrics.set("faceAreaMean", m.faceAreaMean);
  val valence = val::object();
  for (const auto& [k, count] : m.vertexValence) valence.set(std::to_string(k), count);
  metrics.set("vertexValence", valence);
  metrics.set("surfaceDistance", copyArray("Float64Array", m.surfaceDistance.data(), m.surfaceDistance.size()));
  metrics.set("surfaceDistanceMax", m.surfaceDistanceMax);
  metrics.set("surfaceDistanceMean", m.surfaceDistanceMean);
  out.set("metrics", metrics);

  val solve = val::object();
  solve.set("iterations", r.solve.iterations);
  solve.set("rounds", r.solve.rounds);
  solve.set("converged", r.solve.converged);
  solve.set("initialPlanarityMax", r.solve.initialPlanarityMax);
  solve.set("planarityMax", r.solve.planarityMax);
  solve.set("displacementMax", r.solve.displacementMax);
  solve.set("surfaceFitted", r.solve.surfaceFitted);
  solve.set("boundaryPanelsSplit", r.boundaryPanelsSplit);
  solve.set("interiorFacesSplit", r.interiorFacesSplit);
  solve.set("foldsAllowed", r.foldsAllowed);
  solve.set("method", std::string(phex::methodName(r.solverUsed)));
  solve.set("surfaceDistanceBefore", r.solve.surfaceDistanceBefore);
  solve.set("surfaceDistanceAfter", r.solve.surfaceDistanceAfter);
  solve.set("freeNodesSettled", r.solve.freeNodesSettled);
  solve.set("boundaryNodesPlaced", r.solve.boundaryNodesPlaced);
  val log = val::array();
  for (const phex::IterationLog& it : r.solve.log) {
    val e = val::object();
    e.set("round", it.round);
    e.set("iteration", it.iteration);
    e.set("lambda", it.lambda);
    e.set("objective", it.objective);
    e.set("planarityMax", it.planarityMax);
    e.set("milliseconds", it.milliseconds);
    log.call<void>("push", e);
  }
  solve.set("log", log);
  out.set("solve", solve);

  val timings = val::object();
  for (const phex::StageTiming& t : r.timings) timings.set(t.stage, t.milliseconds);
  timings.set("total", r.totalMilliseconds);
  out.set("timings", timings);
  out.set("dualFallbacks", r.dual.fallbackCount);
  out.set("dualUntangled", r.dual.untangled);
  out.set("duality", std::string(phex::dualityName(r.duality)));
  out.set("method", std::string(phex::triangulationMethodName(r.method)));
  out.set("field", r.field);
  out.set("surfaceReused", r.surfaceReused);
  out.set("farNodes", r.farNodes);
  out.set("coverageGap", r.coverageGap);
  val boundary = val::object();
  boundary.set("max", r.boundaryOffset.max);
  boundary.set("median", r.boundaryOffset.median);
  boundary.set("nodes", r.boundaryOffset.nodes);
  out.set("boundaryOffset", boundary);
  val clip = val::object();
  clip.set("panels", r.boundaryClip.panels);
  clip.set("skipped", r.boundaryClip.skipped);
  clip.set("nodesMoved", r.boundaryClip.nodesMoved);
  clip.set("nodesAdded", r.boundaryClip.nodesAdded);
  clip.set("nodesRemoved", r.boundaryClip.nodesRemoved);
  clip.set("fillers", r.boundaryClip.fillers);
  clip.set("cutDropped", r.boundaryClip.cutDropped);
  clip.set("removed", r.boundaryClip.removed);
  clip.set("gapMax", r.boundaryClip.gapMax);
  out.set("boundaryClip", clip);
  val relay = val::object();
  relay.set("tried", r.relay.tried);
  relay.set("kept", r.relay.kept);
  relay.set("anisotropy", r.relay.anisotropy);
  relay.set("curvatureFloor", r.relay.curvatureFloor);
  relay.set("firstReached", r.relay.firstReached);
  relay.set("firstNodesOfFour", r.relay.firstNodesOfFour);
  relay.set("globally", r.relay.globally);
  relay.set("firstCoverageGap", r.relay.firstCoverageGap);
  relay.set("trials", r.relay.trials);
  relay.set("trialNodesOfFour", r.relay.trialNodesOfFour);
  relay.set("trialShare", r.relay.trialShare);
  relay.set("noisyRepairs", r.relay.noisyRepairs);
  relay.set("noisyRepairsKept", r.relay.noisyRepairsKept);
  out.set("relay", relay);
  val origin = val::array();
  for (int k = 0; k < 3; ++k) origin.call<void>("push", r.origin(k));
  out.set("origin", origin);
  return out;
}

val errorToJs(const char* code, const std::string& message) {
  val out = val::object();
  out.set("ok", false);
  out.set("code", std::string(code));
  out.set("message", message);
  return out;
}

// Runs `body`, turning any C++ exception into the {ok: false, code, message} answer.
template <typename Body>
val guarded(Body body) {
  try {
    return body();
  } catch (const phex::Error& e) {
    return errorToJs(phex::errorCodeName(e.code()), e.what());
  } catch (const std::bad_alloc&) {
    // Not a bug: the run asked for more than the module's heap can grow to (phex.js restarts the core after it).
    return errorToJs("out_of_memory",
                     "out of memory: this run needs more than the 2 GB the WebAssembly core can hold; ask for fewer "
                     "faces or a larger cell (the core is restarted for the next call, and its memory given back)");
  } catch (const std::exception& e) {
    return errorToJs("internal", e.what());
  }
}

val run(val params, val onProgress) {
  return guarded([&] {
    const phex::PipelineParams p = paramsFromJs(params);
    phex::ProgressFn progress;
    if (onProgress.typeOf().as<std::string>() == "function")
      progress = [&onProgress](const phex::Progress& pr) { onProgress(pr.stage, pr.fraction, pr.message); };
    return resultToJs(phex::runPipeline(p, progress));
  });
}

val surfaces() {
  val list = val::array();
  for (const phex::SurfaceSpec& s : phex::analyticSurfaces()) {
    val e = val::object();
    e.set("name", s.name);
    e.set("description", s.description);
    e.set("method", s.method);
    e.set("field", s.field);
    val ps = val::array();
    for (const phex::ParameterSpec& p : s.parameters) {
      val q = val::object();
      q.set("name", p.name);
      q.set("default", p.defaultValue);
      q.set("min", p.min);
      q.set("max", p.max);
      q.set("description", p.description);
      ps.call<void>("push", q);
    }
    e.set("parameters", ps);
    list.call<void>("push", e);
  }
  return list;
}

std::string version() { return "0.1.0"; }

val capabilities() {
  val c = val::object();
  c.set("meshInput", true);
  val formats = val::array();
  for (const char* f : {"obj", "off", "ply", "stl"}) formats.call<void>("push", std::string(f));
  c.set("meshFormats", formats);
  val methods = val::array();
  for (const char* m : {"auto", "progressive", "prespecified", "subdivision", "lattice", "global"}) methods.call<void>("push", std::string(m));
  c.set("methods", methods);
  val fields = val::array();
  for (const char* f : {"principal", "angle:DEG", "param", "radial", "diverging", "spiral", "section"}) fields.call<void>("push", std::string(f));
  c.set("fields", fields);
  c.set("lowerBound", true);
  c.set("globalOptions", true);  // anisotropy, alignment, curvatureSizing, curvatureFloor, foldFlips, dislocations, relay, fairness
  val controls = val::array();
  for (const std::string& n : phex::subdivisionControls()) controls.call<void>("push", n);
  c.set("subdivisionControls", controls);
  val solvers = val::array();
  for (const char* s : {"local", "planes", "volumes"}) solvers.call<void>("push", std::string(s));
  c.set("solvers", solvers);
  return c;
}

// The surface of `params` (analytic by name, or an uploaded mesh) as a triangle mesh with the principal
// curvatures at its vertices, for display.
val surfacePreview(val params) {
  return guarded([&] {
    const phex::PipelineParams p = paramsFromJs(params);
    const phex::SurfacePreview s = phex::surfacePreview(p);
    val out = val::object();
    out.set("ok", true);
    out.set("positions", copyArray("Float64Array", s.mesh.V.data(), static_cast<std::size_t>(s.mesh.V.size())));
    std::vector<std::uint32_t> tris(s.mesh.F.data(), s.mesh.F.data() + s.mesh.F.size());
    out.set("triangles", copyArray("Uint32Array", tris.data(), tris.size()));
    out.set("k1", copyArray("Float64Array", s.k1.data(), s.k1.size()));
    out.set("k2", copyArray("Float64Array", s.k2.data(), s.k2.size()));
    return out;
  });
}

// A polygon mesh from {positions, faceOffsets, faceIndices} (typed arrays or arrays of numbers), as run()
// returns them. Shapes are checked here; ids and offsets by the core, which names the face.
phex::PolyMesh polyMeshFromJs(const val& o) {
  if (o.typeOf().as<std::string>() != "object" || o.isNull())
    throw phex::Error(phex::ErrorCode::InvalidInput, "mesh must be an object {positions, faceOffsets, faceIndices}");
  for (const char* key : {"positions", "faceOffsets", "faceIndices"})
    if (!has(o, key) || !o[key]["length"].isNumber())
      throw phex::Error(phex::ErrorCode::InvalidInput, std::string("mesh.") + key + " must be an array or typed array");
  const std::vector<double> positions = emscripten::convertJSArrayToNumberVector<double>(o["positions"]);
  if (positions.size() % 3 != 0)
    throw phex::Error(phex::ErrorCode::InvalidInput, "mesh.positions has " + std::to_string(positions.size()) +
                                                         " numbers, not a multiple of 3");
  const std::vector<double> offsets = emscripten::convertJSArrayToNumberVector<double>(o["faceOffsets"]);
  const std::vector<double> indices = emscripten::convertJSArrayToNumberVector<double>(o["faceIndices"]);
  auto id = [](double x, const char* what) {
    if (!(x >= 0 && x <= 2e9) || x != std::floor(x))
      throw phex::Error(phex::ErrorCode::InvalidInput, std::string("mesh.") + what + " holds " + std::to_string(x) +
                                                           ", not an index");
    return static_cast<int>(x);
  };
  phex::PolyMesh m;
  m.V.resize(static_cast<Eigen::Index>(positions.size() / 3), 3);
  for (std::size_t i = 0; i < positions.size(); ++i) m.V(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3)) = positions[i];
  m.offsets.clear();
  for (double x : offsets) m.offsets.push_back(id(x, "faceOffsets"));
  if (m.offsets.empty()) m.offsets.push_back(0);
  for (double x : indices) m.indices.push_back(id(x, "faceIndices"));
  return m;
}

// The structure options of `options` ({offset, beamHeight, beamWidth, panelThickness}; missing: the defaults).
phex::StructureOptions structureOptionsFromJs(const val& options) {
  phex::StructureOptions o;
  if (options.isUndefined() || options.isNull()) return o;
  if (options.typeOf().as<std::string>() != "object")
    throw phex::Error(phex::ErrorCode::InvalidParameter, "structure options must be an object");
  if (has(options, "offset")) o.offset = number(options, "offset");
  if (has(options, "beamHeight")) o.beamHeight = number(options, "beamHeight");
  if (has(options, "beamWidth")) o.beamWidth = number(options, "beamWidth");
  if (has(options, "panelThickness")) o.panelThickness = number(options, "panelThickness");
  return o;
}

// Fabrication output of `mesh`: {ok, text} with options.format 'svg' (the faces laid flat on a cut sheet), 'csv'
// (the panel schedule), 'beams' (the beam schedule; with options.beamHeight, extended by the structure's beams),
// 'nodes' (the node schedule) or 'structure-obj' (the structure's solid model as OBJ, with the structure options);
// options.gap, width, unit and labels shape the sheet (phex::PanelSheetOptions).
val fabrication(val mesh, val options) {
  return guarded([&] {
    phex::PanelSheetOptions sheet;
    std::string format = "svg";
    if (!options.isUndefined() && !options.isNull()) {
      if (options.typeOf().as<std::string>() != "object")
        throw phex::Error(phex::ErrorCode::InvalidParameter, "panel options must be an object");
      if (has(options, "format")) format = text(options, "format");
      if (has(options, "gap")) sheet.gap = number(options, "gap");
      if (has(options, "width")) sheet.width = number(options, "width");
      if (has(options, "unit")) sheet.unit = text(options, "unit");
      if (has(options, "labels")) {
        if (options["labels"].typeOf().as<std::string>() != "boolean")
          throw phex::Error(phex::ErrorCode::InvalidParameter, "labels must be true or false");
        sheet.labels = options["labels"].as<bool>();
      }
    }
    if (format != "svg" && format != "csv" && format != "beams" && format != "nodes" && format != "structure-obj")
      throw phex::Error(phex::ErrorCode::InvalidParameter,
                        "format must be 'svg', 'csv', 'beams', 'nodes' or 'structure-obj' (got '" + format + "')");
    // The structure's schedules and solid model take its options too (offset, beamHeight, beamWidth, panelThickness).
    const phex::StructureOptions o = structureOptionsFromJs(format == "svg" || format == "csv" ? val::undefined() : options);
    phex::validate(o);
    const phex::PolyMesh m = polyMeshFromJs(mesh);
    val out = val::object();
    out.set("ok", true);
    if (format == "beams" && o.beamHeight) {
      const phex::Structure s = phex::buildStructure(m, o);
      out.set("text", phex::beamsCsv(m, s.axes, s.beams));
    } else if (format == "beams") {
      out.set("text", phex::beamsCsv(m));
    } else if (format == "nodes") {
      out.set("text", phex::nodesCsv(m, phex::nodeAxes(m)));
    } else if (format == "structure-obj") {
      out.set("text", phex::toObj(phex::buildStructure(m, o).model));
    } else {
      const std::vector<phex::Panel> flat = phex::flattenPanels(m);
      out.set("text", format == "svg" ? phex::panelsSvg(flat, sheet) : phex::panelsCsv(flat));
    }
    return out;
  });
}

// A solid part as {positions (Float32Array, relative to the model's origin), index, element} for a three.js
// BufferGeometry.
val solidToJs(const phex::SolidPart& part) {
  val out = val::object();
  const std::vector<float> xyz(part.V.data(), part.V.data() + part.V.size());
  out.set("positions", copyArray("Float32Array", xyz.data(), xyz.size()));
  const std::vector<std::uint32_t> index(part.F.data(), part.F.data() + part.F.size());
  out.set("index", copyArray("Uint32Array", index.data(), index.size()));
  const std::vector<std::uint32_t> element(part.element.begin(), part.element.end());
  out.set("element", copyArray("Uint32Array", element.data(), element.size()));
  out.set("count", part.elements);
  return out;
}

// The structure on a polygon mesh (phex::buildStructure): node axes, the offset mesh where options.offset is
// given, the beams and the solid model, with what the core reports about them.
val structure(val mesh, val options) {
  return guarded([&] {
    const phex::StructureOptions o = structureOptionsFromJs(options);
    phex::validate(o);  // before the mesh is copied in: a bad option is named at once
    const phex::PolyMesh m = polyMeshFromJs(mesh);
    const phex::Structure s = phex::buildStructure(m, o);
    const phex::NodeAxes& ax = s.axes;
    val out = val::object();
    out.set("ok", true);
    if (s.offset) out.set("offset", meshToJs(*s.offset));
    val nodes = val::object();
    nodes.set("positions", copyArray("Float64Array", ax.position.data(), static_cast<std::size_t>(ax.position.size())));
    nodes.set("axes", copyArray("Float64Array", ax.axis.data(), static_cast<std::size_t>(ax.axis.size())));
    const std::vector<std::uint8_t> kind(reinterpret_cast<const std::uint8_t*>(ax.kind.data()),
                                         reinterpret_cast<const std::uint8_t*>(ax.kind.data()) + ax.kind.size());
    nodes.set("kind", copyArray("Uint8Array", kind.data(), kind.size()));
    const std::vector<std::uint32_t> bestFit(ax.bestFit.begin(), ax.bestFit.end()), folded(ax.folded.begin(), ax.folded.end());
    nodes.set("bestFit", copyArray("Uint32Array", bestFit.data(), bestFit.size()));
    nodes.set("folded", copyArray("Uint32Array", folded.data(), folded.size()));
    nodes.set("residual", copyArray("Float64Array", ax.residual.data(), ax.residual.size()));
    out.set("nodes", nodes);
    const std::size_t nb = s.beams.beams.size();
    std::vector<std::uint32_t> ends(2 * nb);
    std::vector<std::int32_t> faces(2 * nb);
    std::vector<double> quads(12 * nb), planes(4 * nb), heights(2 * nb), planarity(nb), twist(nb);
    for (std::size_t i = 0; i < nb; ++i) {
      const phex::MeshEdge& e = ax.edges[i];
      const phex::Beam& b = s.beams.beams[i];
      ends[2 * i] = e.a, ends[2 * i + 1] = e.b, faces[2 * i] = e.left, faces[2 * i + 1] = e.right;
      for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 3; ++c) quads[12 * i + 3 * k + c] = b.corners[k][c];
      for (int c = 0; c < 3; ++c) planes[4 * i + c] = b.normal[c];
      planes[4 * i + 3] = b.planeOffset;
      heights[2 * i] = b.heightA, heights[2 * i + 1] = b.heightB, planarity[i] = b.planarity, twist[i] = b.twistDeg;
    }
    val beams = val::object();
    beams.set("nodes", copyArray("Uint32Array", ends.data(), ends.size()));
    beams.set("faces", copyArray("Int32Array", faces.data(), faces.size()));
    beams.set("quads", copyArray("Float64Array", quads.data(), quads.size()));
    beams.set("planes", copyArray("Float64Array", planes.data(), planes.size()));
    beams.set("heights", copyArray("Float64Array", heights.data(), heights.size()));
    beams.set("planarity", copyArray("Float64Array", planarity.data(), planarity.size()));
    beams.set("twist", copyArray("Float64Array", twist.data(), twist.size()));
    out.set("beams", beams);
    val solid = val::object();
    val origin = val::array();
    for (int k = 0; k < 3; ++k) origin.call<void>("push", s.model.origin(k));
    solid.set("origin", origin);
    solid.set("panels", solidToJs(s.model.panels));
    solid.set("beams", solidToJs(s.model.beams));
    const std::vector<float> axes(s.model.axes.data(), s.model.axes.data() + s.model.axes.size());
    val axesOut = val::object();
    axesOut.set("positions", copyArray("Float32Array", axes.data(), axes.size()));
    solid.set("axes", axesOut);
    out.set("solid", solid);
    val report = val::object();
    val kinds = val::object();
    int withPanels = 0;
    for (phex::NodeKind k : {phex::NodeKind::Cone, phex::NodeKind::Boundary, phex::NodeKind::Corner, phex::NodeKind::BestFit,
                             phex::NodeKind::Folded, phex::NodeKind::Free}) {
      const int count = static_cast<int>(std::count(ax.kind.begin(), ax.kind.end(), k));
      kinds.set(phex::nodeKindName(k), count);
      if (k != phex::NodeKind::Free) withPanels += count;
    }
    report.set("nodesByKind", kinds);
    report.set("offset", o.offset ? val(*o.offset) : val::null());
    val range = val::array();
    range.call<void>("push", ax.offsetMin);
    range.call<void>("push", ax.offsetMax);
    report.set("offsetRange", range);
    for (const auto& [name, value] : std::initializer_list<std::pair<const char*, double>>{
             {"nodeCount", withPanels}, {"beamCount", static_cast<double>(nb)}, {"beamLength", s.beams.length},
             {"beamHeight", s.beams.height}, {"beamWidth", s.beamWidth}, {"panelThickness", s.panelThickness},
             {"boundaryBeams", ax.boundaryBeams}, {"boundaryBeamsPlanar", ax.boundaryBeamsPlanar},
             {"boundaryRuns", ax.boundaryRuns}, {"boundaryRunsPlanar", ax.boundaryRunsPlanar},
             {"boundaryTwistMaxDeg", ax.boundaryTwistMaxDeg}, {"boundaryTurnMaxDeg", ax.boundaryTurnMaxDeg},
             {"beamPlanarityMax", s.beams.planarityMax}, {"interiorBeamPlanarityMax", s.beams.interiorPlanarityMax},
             {"nodesMovedOntoPlanesMax", ax.snapMax}})
      report.set(name, value);
    val notes = val::array();
    for (const auto* list : {&ax.notes, &s.notes})
      for (const std::string& n : *list) notes.call<void>("push", n);
    report.set("notes", notes);
    out.set("report", report);
    return out;
  });
}

void clearUploadCache() { phex::clearUploadCache(); }

// Test-only: the core fails as a bug in it would, beyond any C++ handler, so that tests can check that a page
// survives one: 'unreachable' (a trap), 'abort' (abort()), 'memory' (a read past the end of the heap).
void debugTrap(std::string kind) {
  if (kind == "abort") std::abort();
  if (kind == "memory") {
    const auto end = static_cast<std::uintptr_t>(emscripten::val::module_property("HEAPU8")["byteLength"].as<double>());
    std::printf("%d\n", *reinterpret_cast<volatile const char*>(end + 16));
  }
  __builtin_trap();
}

double heapBytes() { return static_cast<double>(emscripten::val::module_property("HEAPU8")["byteLength"].as<double>()); }

// Bytes malloc has handed out and not taken back: flat across runs when nothing leaks.
double mallocedBytes() { return static_cast<double>(mallinfo().uordblks); }

}  // namespace

EMSCRIPTEN_BINDINGS(phex) {
  emscripten::function("run", &run);
  emscripten::function("surfaces", &surfaces);
  emscripten::function("version", &version);
  emscripten::function("heapBytes", &heapBytes);
  emscripten::function("capabilities", &capabilities);
  emscripten::function("surfacePreview", &surfacePreview);
  emscripten::function("fabrication", &fabrication);
  emscripten::function("structure", &structure);
  emscripten::function("mallocedBytes", &mallocedBytes);
  emscripten::function("clearUploadCache", &clearUploadCache);
  emscripten::function("debugTrap", &debugTrap);
}
