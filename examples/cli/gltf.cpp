// phex CLI — glTF 2.0 output through tinygltf (Debian's libtinygltf-dev).
#include "gltf.hpp"

#include <phex/error.hpp>
#include <phex/mesh_io.hpp>

#include <cstring>
#include <numeric>
#include <tiny_gltf.h>

namespace phexcli {

namespace {

// Appends `bytes` to the buffer, 4-byte aligned, as a new buffer view; returns its index.
int addView(tinygltf::Model& model, const void* bytes, std::size_t size, int target) {
  std::vector<unsigned char>& data = model.buffers[0].data;
  data.resize((data.size() + 3) & ~std::size_t(3));
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = data.size();
  view.byteLength = size;
  view.target = target;
  data.insert(data.end(), static_cast<const unsigned char*>(bytes), static_cast<const unsigned char*>(bytes) + size);
  model.bufferViews.push_back(view);
  return static_cast<int>(model.bufferViews.size()) - 1;
}

int addAccessor(tinygltf::Model& model, int view, int componentType, std::size_t count, int type) {
  tinygltf::Accessor a;
  a.bufferView = view;
  a.componentType = componentType;
  a.count = count;
  a.type = type;
  model.accessors.push_back(a);
  return static_cast<int>(model.accessors.size()) - 1;
}

}  // namespace

void writeGltf(const std::string& path, const std::vector<GltfPart>& parts, const phex::Vec3& origin,
               const std::vector<std::pair<std::string, int>>& counts) {
  tinygltf::Model model;
  model.asset.generator = "phex 0.1.0";
  model.buffers.resize(1);
  tinygltf::Scene scene;
  tinygltf::Value::Object extras;
  for (const auto& [name, count] : counts) extras[name] = tinygltf::Value(count);
  scene.extras = tinygltf::Value(extras);
  for (const GltfPart& part : parts) {
    if (part.index.empty()) continue;
    std::vector<float> xyz(part.V.data(), part.V.data() + part.V.size());
    const int positions = addAccessor(model, addView(model, xyz.data(), xyz.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER),
                                      TINYGLTF_COMPONENT_TYPE_FLOAT, static_cast<std::size_t>(part.V.rows()), TINYGLTF_TYPE_VEC3);
    tinygltf::Accessor& p = model.accessors[positions];  // glTF asks for the bounds of positions
    for (int c = 0; c < 3; ++c) {
      p.minValues.push_back(part.V.rows() ? static_cast<float>(part.V.col(c).minCoeff()) : 0.0);
      p.maxValues.push_back(part.V.rows() ? static_cast<float>(part.V.col(c).maxCoeff()) : 0.0);
    }
    const int indices = addAccessor(model, addView(model, part.index.data(), part.index.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                                    TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, part.index.size(), TINYGLTF_TYPE_SCALAR);
    tinygltf::Material material;
    material.name = part.name;
    material.pbrMetallicRoughness.baseColorFactor = {part.color.begin(), part.color.end()};
    material.pbrMetallicRoughness.metallicFactor = 0.1;
    material.pbrMetallicRoughness.roughnessFactor = 0.6;
    material.doubleSided = part.lines;
    if (part.color[3] < 1) material.alphaMode = "BLEND";
    model.materials.push_back(material);
    tinygltf::Primitive primitive;
    primitive.attributes["POSITION"] = positions;
    primitive.indices = indices;
    primitive.material = static_cast<int>(model.materials.size()) - 1;
    primitive.mode = part.lines ? TINYGLTF_MODE_LINE : TINYGLTF_MODE_TRIANGLES;
    tinygltf::Mesh mesh;
    mesh.name = part.name;
    mesh.primitives.push_back(primitive);
    model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.name = part.name;
    node.mesh = static_cast<int>(model.meshes.size()) - 1;
    if (origin.norm() > 0) node.translation = {origin.x(), origin.y(), origin.z()};
    model.nodes.push_back(node);
    scene.nodes.push_back(static_cast<int>(model.nodes.size()) - 1);
  }
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  const bool binary = !(path.size() >= 5 && path.compare(path.size() - 5, 5, ".gltf") == 0);
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToFile(&model, path, false, true, !binary, binary))
    throw phex::Error(phex::ErrorCode::Io, "failed writing '" + path + "'");
}

GltfPart polygonPart(const std::string& name, const phex::PolyMesh& mesh, const phex::Vec3& origin) {
  GltfPart part;
  part.name = name;
  part.V = mesh.V.rowwise() - origin.transpose();
  std::vector<int> ids, tri;
  for (int f = 0; f < mesh.faceCount(); ++f) {
    ids.assign(mesh.face(f), mesh.face(f) + mesh.faceSize(f));
    phex::triangulatePolygon(ids, part.V.data(), tri);
  }
  part.index.assign(tri.begin(), tri.end());
  return part;
}

}  // namespace phexcli
