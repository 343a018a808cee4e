// phex CLI — glTF 2.0 output (binary .glb, or .gltf with its buffer embedded) through tinygltf.
#pragma once
#include <phex/mesh.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace phexcli {

// One mesh of the file: triangles (or line segments) over positions relative to the file's origin.
struct GltfPart {
  std::string name;
  phex::Points V;                      // #V by 3, relative to the origin (written as 32-bit floats)
  std::vector<std::uint32_t> index;    // 3 per triangle, or 2 per segment with lines
  bool lines = false;
  std::array<double, 4> color{0.8, 0.8, 0.8, 1.0};  // linear RGBA; alpha < 1 is blended
};

// Writes the parts as one scene, each a node placed at `origin` (kept in double precision in the node's
// translation, so site coordinates keep their digits while the vertices stay 32-bit floats), with `counts` as the
// scene's extras (e.g. {"beams", 1500}). The format follows the extension: .gltf is JSON with the buffer embedded,
// anything else binary. Throws phex::Error(Io) naming the path when it cannot be written.
void writeGltf(const std::string& path, const std::vector<GltfPart>& parts, const phex::Vec3& origin,
               const std::vector<std::pair<std::string, int>>& counts);

// A polygon mesh's faces as one triangle part (ear clipping, so non-convex faces stay inside their outline), its
// positions relative to `origin`.
GltfPart polygonPart(const std::string& name, const phex::PolyMesh& mesh, const phex::Vec3& origin);

}  // namespace phexcli
