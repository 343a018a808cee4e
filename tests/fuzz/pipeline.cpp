// phex — fuzz target: the whole pipeline on a tiny uploaded mesh (fuzz.hpp: decodeMesh, written as the OBJ
// file a user would upload), at most 60 faces, with the method (the global one with its field options, the
// solver's fairness, the share of cuts and the second lay too),
// field, duality, solver and options a byte picks. It tiles the mesh or refuses it; what it returns is finite.
#include <phex/pipeline.hpp>

#include <string>

#include "fuzz.hpp"

using namespace phex_fuzz;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Input in{data, size};
  phex::PipelineParams p;
  const std::uint8_t choice = in.byte(), more = in.byte();
  const phex::TriangulationMethod methods[] = {phex::TriangulationMethod::Auto, phex::TriangulationMethod::Progressive,
                                               phex::TriangulationMethod::Prespecified, phex::TriangulationMethod::Subdivision,
                                               phex::TriangulationMethod::Global};
  // The first byte's low bits pick the method (global where they are 4-7, with its options from the next byte).
  p.method = methods[(choice & 7) < 4 ? choice & 3 : 4];
  const char* fields[] = {"principal", "angle:30", "section", "param"};
  p.field = fields[(choice >> 2) % 4];
  p.duality = (choice >> 4) % 3 == 0 ? phex::Duality::Auto : (choice >> 4) % 3 == 1 ? phex::Duality::Dupin : phex::Duality::Tangent;
  p.preventFolds = !(choice & 0x40);
  p.splitBoundaryPanels = !(choice & 0x80);
  p.faces = 12 + more % 49;
  p.lowerBound = (more >> 6) * 0.3;
  p.maxIterations = 30;
  if (p.method == phex::TriangulationMethod::Global) {
    const std::uint8_t options = in.byte();
    p.anisotropy = 1 + (options & 7);                // 1 .. 8
    p.alignment = 10.0 * ((options >> 3) & 3) / 3;   // 0 .. 10
    p.curvatureSizing = ((options >> 5) & 3) / 3.0;  // 0 .. 1
    p.relay = !(options & 0x80);
    const std::uint8_t solver = in.byte();
    p.fairness = (solver & 3) / 3.0;                          // 0 .. 1
    p.curvatureFloor = 0.01 + 0.99 * ((solver >> 2) & 7) / 7;  // 0.01 .. 1
    p.cutShare = (solver >> 5) & 3 ? ((solver >> 5) & 3) / 3.0 : 0.1;  // the default, 1/3, 2/3, 1
  }
  const phex::TriMesh m = decodeMesh(in);
  std::string obj;
  char line[128];
  for (Eigen::Index v = 0; v < m.V.rows(); ++v) {
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", m.V(v, 0), m.V(v, 1), m.V(v, 2));
    obj += line;
  }
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) obj += "f " + std::to_string(m.F(f, 0) + 1) + " " + std::to_string(m.F(f, 1) + 1) + " " + std::to_string(m.F(f, 2) + 1) + "\n";
  p.mesh = phex::MeshInput{std::vector<std::uint8_t>(obj.begin(), obj.end()), "obj", "fuzz.obj"};
  expectRefusalOnly({phex::ErrorCode::InvalidInput, phex::ErrorCode::InvalidParameter, phex::ErrorCode::CannotTile}, [&] {
    const phex::PipelineResult r = phex::runPipeline(p);
    check(r.hex.V.allFinite() && r.initial.V.allFinite() && r.triangulation.mesh.V.allFinite(), "meshes finite");
    check(r.hex.V.rows() == 0 || r.hex.offsets.back() == static_cast<int>(r.hex.indices.size()), "faces well formed");
    for (int i : r.hex.indices) check(i >= 0 && i < r.hex.V.rows(), "face corners in range");
  });
  phex::clearUploadCache();  // each input on its own
  return 0;
}
