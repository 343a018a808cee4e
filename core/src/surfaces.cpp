#include "phex/surfaces.hpp"

#include <cmath>
#include <functional>
#include <sstream>

#include "phex/error.hpp"

namespace phex {
namespace {

constexpr double kPi = 3.14159265358979323846;
double radians(double degrees) { return degrees * kPi / 180.0; }

// Sphere of radius R, trimmed to latitudes |v| <= latitude (the lattice cannot cover the poles).
class Sphere final : public ParametricSurface {
 public:
  Sphere(double R, double latitudeDeg) : R_(R), vmax_(radians(latitudeDeg)) {}
  std::string name() const override { return "sphere"; }
  Domain domain() const override { return {0, 2 * kPi, -vmax_, vmax_, true, false}; }
  Jet jet(double u, double v) const override {
    const double cu = std::cos(u), su = std::sin(u), cv = std::cos(v), sv = std::sin(v);
    Jet j;
    j.P = R_ * Vec3(cv * cu, cv * su, sv);
    j.Pu = R_ * Vec3(-cv * su, cv * cu, 0);
    j.Pv = R_ * Vec3(-sv * cu, -sv * su, cv);
    j.Puu = R_ * Vec3(-cv * cu, -cv * su, 0);
    j.Puv = R_ * Vec3(sv * su, -sv * cu, 0);
    j.Pvv = R_ * Vec3(-cv * cu, -cv * su, -sv);
    return j;
  }

 private:
  double R_, vmax_;
};

// Torus with major radius R and minor radius r; parabolic circles at the top and bottom.
class Torus final : public ParametricSurface {
 public:
  Torus(double R, double r) : R_(R), r_(r) {}
  std::string name() const override { return "torus"; }
  Domain domain() const override { return {0, 2 * kPi, -kPi, kPi, true, true}; }
  Jet jet(double u, double v) const override {
    const double cu = std::cos(u), su = std::sin(u), cv = std::cos(v), sv = std::sin(v);
    const double w = R_ + r_ * cv;
    Jet j;
    j.P = Vec3(w * cu, w * su, r_ * sv);
    j.Pu = Vec3(-w * su, w * cu, 0);
    j.Pv = r_ * Vec3(-sv * cu, -sv * su, cv);
    j.Puu = Vec3(-w * cu, -w * su, 0);
    j.Puv = r_ * Vec3(sv * su, -sv * cu, 0);
    j.Pvv = r_ * Vec3(-cv * cu, -cv * su, -sv);
    return j;
  }

 private:
  double R_, r_;
};

struct Entry {
  SurfaceSpec spec;
  std::function<SurfacePtr(const SurfaceParams&)> make;
};

const std::vector<Entry>& registry() {
  static const std::vector<Entry> entries = {
      {{"torus",
        "Torus of revolution around z; elliptic outside, hyperbolic inside, parabolic circles on top and bottom.",
        {{"R", 1.0, 1e-6, 1e6, "major radius (centre to tube axis)"},
         {"r", 0.4, 1e-6, 1e6, "minor radius (tube), must be less than R"}}},
       [](const SurfaceParams& p) {
         if (!(p.at("r") < p.at("R")))
           throw Error(ErrorCode::InvalidParameter, "torus: r must be less than R (got r=" + std::to_string(p.at("r")) +
                                                        ", R=" + std::to_string(p.at("R")) + ")");
         return std::make_shared<Torus>(p.at("R"), p.at("r"));
       }},
      {{"sphere", "Sphere of radius R around the origin, trimmed to a band of latitudes.",
        {{"R", 1.0, 1e-6, 1e6, "radius"},
         {"latitude", 60.0, 5.0, 85.0, "the band covers latitudes -latitude..latitude, in degrees"}}},
       [](const SurfaceParams& p) { return std::make_shared<Sphere>(p.at("R"), p.at("latitude")); }},
  };
  return entries;
}

}  // namespace

const std::vector<SurfaceSpec>& analyticSurfaces() {
  static const std::vector<SurfaceSpec> specs = [] {
    std::vector<SurfaceSpec> s;
    for (const Entry& e : registry()) s.push_back(e.spec);
    return s;
  }();
  return specs;
}

SurfacePtr makeSurface(const std::string& name, const SurfaceParams& params) {
  for (const Entry& e : registry()) {
    if (e.spec.name != name) continue;
    SurfaceParams full;
    for (const ParameterSpec& ps : e.spec.parameters) full[ps.name] = ps.defaultValue;
    for (const auto& [key, value] : params) {
      auto it = full.find(key);
      if (it == full.end()) throw Error(ErrorCode::InvalidParameter, name + ": unknown parameter '" + key + "'");
      it->second = value;
    }
    for (const ParameterSpec& ps : e.spec.parameters) {
      const double v = full[ps.name];
      if (!std::isfinite(v) || v < ps.min || v > ps.max) {
        std::ostringstream msg;
        msg << name << ": parameter '" << ps.name << "' = " << v << " is outside [" << ps.min << ", " << ps.max << "]";
        throw Error(ErrorCode::InvalidParameter, msg.str());
      }
    }
    return e.make(full);
  }
  std::string known;
  for (const Entry& e : registry()) known += (known.empty() ? "" : ", ") + e.spec.name;
  throw Error(ErrorCode::InvalidParameter, "unknown surface '" + name + "' (known: " + known + ")");
}

}  // namespace phex
