// phex — fuzz target: a MeshSurface of a small mesh (fuzz.hpp: decodeMesh, cleaned as every reader cleans),
// then closest points, curvature and refinement. Whatever it is built from, its answers are finite and on it.
#include <phex/mesh_io.hpp>
#include <phex/mesh_surface.hpp>

#include "fuzz.hpp"

using namespace phex_fuzz;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Input in{data, size};
  const phex::TriMesh raw = decodeMesh(in);
  expectRefusalOnly({phex::ErrorCode::InvalidInput}, [&] {
    const phex::MeshSurface s(phex::cleanTriMesh(raw, "fuzz"), "fuzz");
    const phex::Box3 box = s.bounds();
    const double slack = 1e-9 * (box.diagonal().norm() + box.min().cwiseAbs().maxCoeff() + box.max().cwiseAbs().maxCoeff());
    auto sane = [&](const phex::LocalGeometry& g, const char* what) {
      check(g.point.allFinite() && g.normal.allFinite() && std::isfinite(g.k1) && std::isfinite(g.k2), what);
      check(box.exteriorDistance(g.point) <= slack, "a closest point lies in the mesh's box");
      check(std::abs(g.normal.norm() - 1) < 1e-6, "a unit normal");
    };
    for (int v = 0; v < s.vertexCount(); ++v) sane(s.vertexGeometry(v), "vertex geometry finite");
    // Queries about the mesh, in its box and out to twice its size on every side.
    const phex::Vec3 centre = box.center(), half = box.sizes();
    while (in.size > 0) {
      const phex::Vec3 t(static_cast<std::int8_t>(in.byte()), static_cast<std::int8_t>(in.byte()), static_cast<std::int8_t>(in.byte()));
      sane(s.closestPoint(centre + half.cwiseProduct(t) / 64), "closest point finite");
    }
    for (const phex::LocalGeometry& g : s.samples(8)) sane(g, "sample finite");
    const phex::TriMesh fine = s.refined(2);
    check(fine.V.allFinite(), "a refined mesh is finite");
  });
  return 0;
}
