// phex — the analytic surfaces (exact derivatives), listed by name with documented parameters.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "phex/surface.hpp"

namespace phex {

struct ParameterSpec {
  std::string name;
  double defaultValue;
  double min, max;  // inclusive valid range
  std::string description;
};

struct SurfaceSpec {
  std::string name;
  std::string description;
  std::vector<ParameterSpec> parameters;
  // The triangulation method that tiles it best with its defaults (what method "auto" picks), as measured
  // over the method x surface matrix in tests/core/pipeline.cpp.
  std::string method = "progressive";
  // The direction field "auto" lays a conjugate method along, unless the caller named another than principal.
  std::string field = "principal";
};

using SurfaceParams = std::map<std::string, double>;

// Every analytic surface phex knows, with its parameters and their defaults and ranges.
const std::vector<SurfaceSpec>& analyticSurfaces();
// Builds the named surface; parameters not given take their defaults. Throws
// Error(InvalidParameter) for an unknown name, an unknown parameter or a value out of range.
ParametricSurfacePtr makeSurface(const std::string& name, const SurfaceParams& params = {});

}  // namespace phex
