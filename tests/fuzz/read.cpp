// phex — fuzz target: one reader (PHEX_FUZZ_FORMAT: obj, off, ply or stl) on any bytes. A file is read into a
// clean mesh or refused as invalid input; the mesh read holds what cleanTriMesh promises.
#include <phex/mesh_io.hpp>

#include "fuzz.hpp"

using namespace phex_fuzz;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  expectRefusalOnly({phex::ErrorCode::InvalidInput}, [&] {
    phex::MeshReadReport report;
    const phex::TriMesh m = phex::readMeshBytes(data, size, PHEX_FUZZ_FORMAT, "fuzz." PHEX_FUZZ_FORMAT, &report);
    check(m.F.rows() > 0 && m.V.rows() >= 3, "a mesh read has triangles");
    check(m.F.minCoeff() >= 0 && m.F.maxCoeff() < m.V.rows(), "indices in range");
    check(m.V.allFinite() && m.V.cwiseAbs().maxCoeff() <= phex::kMaxMeshCoordinate, "coordinates finite, within the limit");
    check(static_cast<Eigen::Index>(report.fileVertex.size()) == m.V.rows(), "a file vertex per vertex");
  });
  return 0;
}
