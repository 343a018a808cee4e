#include "phex/surfaces.hpp"
#include "phex/portable_math.hpp"

#include <cmath>
#include <functional>
#include <sstream>
#include <utility>

#include "phex/error.hpp"

namespace phex {
namespace {

constexpr double kPi = 3.14159265358979323846;
double radians(double degrees) { return degrees * kPi / 180.0; }

// Every analytic surface is one of these: a name, a parameter domain and an exact jet.
class AnalyticSurface final : public ParametricSurface {
 public:
  using JetFunction = std::function<Jet(double u, double v)>;
  AnalyticSurface(std::string name, Domain domain, JetFunction jet)
      : name_(std::move(name)), domain_(domain), jet_(std::move(jet)) {}
  std::string name() const override { return name_; }
  Domain domain() const override { return domain_; }
  Jet jet(double u, double v) const override { return jet_(u, v); }

 private:
  std::string name_;
  Domain domain_;
  JetFunction jet_;
};

ParametricSurfacePtr analytic(std::string name, ParametricSurface::Domain domain, AnalyticSurface::JetFunction jet) {
  return std::make_shared<AnalyticSurface>(std::move(name), domain, std::move(jet));
}

// A function of one variable with its first and second derivatives.
struct Jet1 {
  double f, df, ddf;
};
// The meridian of a surface of revolution: distance rho(v) from the z axis and height z(v).
struct Profile {
  Jet1 rho, z;
};

// Surface of revolution about z, P = (rho(v) cos u, rho(v) sin u, z(v)), u the angle (periodic).
// Pu x Pv = rho (z' cos u, z' sin u, -rho'): the normal lies to the right of the meridian (rho, z), so it
// points outward when the meridian rises (z' > 0) or runs counterclockwise around the enclosed tube.
// A closed meridian (a torus) makes v periodic too.
ParametricSurfacePtr revolution(std::string name, double v0, double v1, std::function<Profile(double)> profile,
                      bool closedMeridian = false) {
  return analytic(std::move(name), {0, 2 * kPi, v0, v1, true, closedMeridian}, [profile](double u, double v) {
    const Profile p = profile(v);
    const double cu = portable::cos(u), su = portable::sin(u);
    const double r = p.rho.f, dr = p.rho.df, ddr = p.rho.ddf;
    ParametricSurface::Jet j;
    j.P = Vec3(r * cu, r * su, p.z.f);
    j.Pu = Vec3(-r * su, r * cu, 0);
    j.Pv = Vec3(dr * cu, dr * su, p.z.df);
    j.Puu = Vec3(-r * cu, -r * su, 0);
    j.Puv = Vec3(-dr * su, dr * cu, 0);
    j.Pvv = Vec3(ddr * cu, ddr * su, p.z.ddf);
    return j;
  });
}

// A height z = f(x, y) and its derivatives.
struct Height {
  double z, zx, zy, zxx, zxy, zyy;
};

// Height field over the square [-size/2, size/2]^2 with (u, v) = (x, y); Pu x Pv = (-zx, -zy, 1) points up.
ParametricSurfacePtr heightField(std::string name, double size, std::function<Height(double, double)> f) {
  const double h = 0.5 * size;
  return analytic(std::move(name), {-h, h, -h, h, false, false}, [f](double x, double y) {
    const Height z = f(x, y);
    ParametricSurface::Jet j;
    j.P = Vec3(x, y, z.z);
    j.Pu = Vec3(1, 0, z.zx);
    j.Pv = Vec3(0, 1, z.zy);
    j.Puu = Vec3(0, 0, z.zxx);
    j.Puv = Vec3(0, 0, z.zxy);
    j.Pvv = Vec3(0, 0, z.zyy);
    return j;
  });
}

// Ellipsoid with semi-axes (a, b, c) (the sphere when equal), P = diag(a, b, c) (cos v cos u, cos v sin u, sin v),
// trimmed to |v| <= latitude: the lattice cannot cover the poles. Outward normals.
ParametricSurfacePtr ellipsoid(std::string name, const Vec3& axes, double latitudeDeg) {
  const double vmax = radians(latitudeDeg);
  return analytic(std::move(name), {0, 2 * kPi, -vmax, vmax, true, false}, [axes](double u, double v) {
    const double cu = portable::cos(u), su = portable::sin(u), cv = portable::cos(v), sv = portable::sin(v);
    ParametricSurface::Jet j;
    j.P = axes.cwiseProduct(Vec3(cv * cu, cv * su, sv));
    j.Pu = axes.cwiseProduct(Vec3(-cv * su, cv * cu, 0));
    j.Pv = axes.cwiseProduct(Vec3(-sv * cu, -sv * su, cv));
    j.Puu = axes.cwiseProduct(Vec3(-cv * cu, -cv * su, 0));
    j.Puv = axes.cwiseProduct(Vec3(sv * su, -sv * cu, 0));
    j.Pvv = axes.cwiseProduct(Vec3(-cv * cu, -cv * su, -sv));
    return j;
  });
}

// Dupin cyclide in the standard form P = N / D with b^2 = a^2 - c^2 (a ring cyclide for c < mu < a;
// c = 0 is the torus with radii a and mu):
//   N = (mu (c - a cos u cos v) + b^2 cos u,  b sin u (a - mu cos v),  b sin v (c cos u - mu)),
//   D = a - c cos u cos v.
// Its curvature lines are the circles u = const and v = const. v = pi is the outer equator; a patch spans
// uSpan around u = 0 and vSpan around v = pi, a span of 360 degrees closes the ring in that direction.
ParametricSurfacePtr cyclide(double a, double c, double mu, double uSpanDeg, double vSpanDeg) {
  const double b = std::sqrt(a * a - c * c);
  const bool closedU = uSpanDeg >= 360, closedV = vSpanDeg >= 360;
  const double hu = 0.5 * radians(uSpanDeg), hv = 0.5 * radians(vSpanDeg);
  const ParametricSurface::Domain domain{-hu, hu, kPi - hv, kPi + hv, closedU, closedV};
  return analytic("cyclide", domain, [a, b, c, mu](double u, double v) {
    const double cu = portable::cos(u), su = portable::sin(u), cv = portable::cos(v), sv = portable::sin(v);
    const double b2 = b * b;
    const Vec3 N(mu * (c - a * cu * cv) + b2 * cu, b * su * (a - mu * cv), b * sv * (c * cu - mu));
    const Vec3 Nu(mu * a * su * cv - b2 * su, b * cu * (a - mu * cv), -b * c * su * sv);
    const Vec3 Nv(mu * a * cu * sv, b * mu * su * sv, b * cv * (c * cu - mu));
    const Vec3 Nuu(mu * a * cu * cv - b2 * cu, -b * su * (a - mu * cv), -b * c * cu * sv);
    const Vec3 Nuv(-mu * a * su * sv, b * mu * cu * sv, -b * c * su * cv);
    const Vec3 Nvv(mu * a * cu * cv, b * mu * su * cv, -b * sv * (c * cu - mu));
    const double D = a - c * cu * cv, Du = c * su * cv, Dv = c * cu * sv;
    const double Duu = c * cu * cv, Duv = -c * su * sv, Dvv = c * cu * cv;
    // Quotient rule from N = P D differentiated twice.
    ParametricSurface::Jet j;
    j.P = N / D;
    j.Pu = (Nu - j.P * Du) / D;
    j.Pv = (Nv - j.P * Dv) / D;
    j.Puu = (Nuu - 2 * j.Pu * Du - j.P * Duu) / D;
    j.Puv = (Nuv - j.Pu * Dv - j.Pv * Du - j.P * Duv) / D;
    j.Pvv = (Nvv - 2 * j.Pv * Dv - j.P * Dvv) / D;
    return j;
  });
}

// Enneper's minimal surface P = (u - u^3/3 + u v^2, v - v^3/3 + v u^2, u^2 - v^2) on the square [-R, R]^2;
// normal +z at the centre.
ParametricSurfacePtr enneper(double R) {
  return analytic("enneper", {-R, R, -R, R, false, false}, [](double u, double v) {
    ParametricSurface::Jet j;
    j.P = Vec3(u - u * u * u / 3 + u * v * v, v - v * v * v / 3 + v * u * u, u * u - v * v);
    j.Pu = Vec3(1 - u * u + v * v, 2 * u * v, 2 * u);
    j.Pv = Vec3(2 * u * v, 1 - v * v + u * u, -2 * v);
    j.Puu = Vec3(-2 * u, 2 * v, 2);
    j.Puv = Vec3(2 * v, 2 * u, 0);
    j.Pvv = Vec3(2 * u, -2 * v, -2);
    return j;
  });
}

// Helicoid P = (s cos t, s sin t, c t) with (u, v) = (s, t), s the signed distance from the axis, so the strip
// crosses the axis without a singularity. Pu x Pv = (c sin t, -c cos t, s): the normal rises where s > 0.
ParametricSurfacePtr helicoid(double radius, double c, double halfAngle) {
  return analytic("helicoid", {-radius, radius, -halfAngle, halfAngle, false, false}, [c](double s, double t) {
    const double ct = portable::cos(t), st = portable::sin(t);
    ParametricSurface::Jet j;
    j.P = Vec3(s * ct, s * st, c * t);
    j.Pu = Vec3(ct, st, 0);
    j.Pv = Vec3(-s * st, s * ct, c);
    j.Puu = Vec3::Zero();
    j.Puv = Vec3(-st, ct, 0);
    j.Pvv = Vec3(-s * ct, -s * st, 0);
    return j;
  });
}

// h exp(-|p - centre|^2 / (2 w^2)) and its derivatives.
Height gaussian(double x, double y, double cx, double cy, double h, double w) {
  const double dx = x - cx, dy = y - cy, w2 = w * w;
  const double g = h * portable::exp(-(dx * dx + dy * dy) / (2 * w2));
  return {g, -dx / w2 * g, -dy / w2 * g, (dx * dx / w2 - 1) / w2 * g, dx * dy / (w2 * w2) * g,
          (dy * dy / w2 - 1) / w2 * g};
}

std::string str(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

struct Entry {
  SurfaceSpec spec;
  std::function<ParametricSurfacePtr(const SurfaceParams&)> make;
};

const std::vector<Entry>& registry() {
  static const std::vector<Entry> entries = {
      {{"torus",
        "Torus of revolution around z; elliptic outside, hyperbolic inside, parabolic circles on top and bottom.",
        {{"R", 1.0, 1e-6, 1e6, "major radius (centre to tube axis)"},
         {"r", 0.4, 1e-6, 1e6, "minor radius (tube), must be less than R"}}},
       [](const SurfaceParams& p) {
         const double R = p.at("R"), r = p.at("r");
         if (!(r < R))
           throw Error(ErrorCode::InvalidParameter, "torus: r must be less than R (got r=" + std::to_string(r) +
                                                        ", R=" + std::to_string(R) + ")");
         return revolution("torus", -kPi, kPi, [R, r](double v) {
           const double c = portable::cos(v), s = portable::sin(v);
           return Profile{{R + r * c, -r * s, -r * c}, {r * s, r * c, -r * s}};
         }, true);
       }},
      {{"sphere", "Sphere of radius R around the origin, trimmed to a band of latitudes.",
        {{"R", 1.0, 1e-6, 1e6, "radius"},
         {"latitude", 60.0, 5.0, 85.0, "the band covers latitudes -latitude..latitude, in degrees"}}},
       [](const SurfaceParams& p) {
         const double R = p.at("R");
         return ellipsoid("sphere", Vec3(R, R, R), p.at("latitude"));
       }},
      {{"ellipsoid",
        "Ellipsoid x^2/a^2 + y^2/b^2 + z^2/c^2 = 1, everywhere elliptic; trimmed to a band of parametric latitudes "
        "(the poles are cut away).",
        {{"a", 1.2, 1e-6, 1e6, "semi-axis along x"},
         {"b", 1.0, 1e-6, 1e6, "semi-axis along y"},
         {"c", 0.8, 1e-6, 1e6, "semi-axis along z"},
         {"latitude", 60.0, 5.0, 85.0, "the band covers parametric latitudes -latitude..latitude, in degrees"}}},
       [](const SurfaceParams& p) {
         return ellipsoid("ellipsoid", Vec3(p.at("a"), p.at("b"), p.at("c")), p.at("latitude"));
       }},
      {{"hyperboloid",
        "Hyperboloid of one sheet (x^2 + y^2)/a^2 - z^2/c^2 = 1 around z, everywhere hyperbolic (Figure 11).",
        {{"a", 0.6, 1e-6, 1e6, "waist radius"},
         {"c", 0.8, 1e-6, 1e6, "the asymptotic cone rises c per a outward; Gaussian curvature -1/c^2 at the waist"},
         {"height", 2.0, 1e-6, 1e6, "total height, centred on the waist"}}},
       [](const SurfaceParams& p) {
         const double a = p.at("a"), c = p.at("c"), t = portable::asinh(0.5 * p.at("height") / c);
         return revolution("hyperboloid", -t, t, [a, c](double v) {
           const double ch = portable::cosh(v), sh = portable::sinh(v);
           return Profile{{a * ch, a * sh, a * ch}, {c * sh, c * ch, c * sh}};
         });
       }},
      {{"cyclide",
        "Ring Dupin cyclide (Figures 1, 15): elliptic outside, hyperbolic inside, with two parabolic circles; "
        "all curvature lines are circles. The whole ring, or a patch around the outer equator.",
        {{"a", 1.0, 1e-6, 1e6, "size: the cyclide spans about 2(a + mu) across"},
         {"c", 0.3, 0.0, 1e6, "eccentricity: 0 gives a torus, larger values thin one side; needs c < mu"},
         {"mu", 0.5, 1e-6, 1e6, "tube size; a ring cyclide needs c < mu < a"},
         {"uSpan", 360.0, 10.0, 360.0, "angle around the ring, in degrees (360: closed)"},
         {"vSpan", 360.0, 10.0, 360.0, "angle around the tube centred on the outer equator, in degrees (360: closed)"}}},
       [](const SurfaceParams& p) {
         const double a = p.at("a"), c = p.at("c"), mu = p.at("mu");
         if (!(c < mu && mu < a))
           throw Error(ErrorCode::InvalidParameter, "cyclide: a ring cyclide needs c < mu < a (got a=" + str(a) +
                                                        ", c=" + str(c) + ", mu=" + str(mu) + ")");
         return cyclide(a, c, mu, p.at("uSpan"), p.at("vSpan"));
       }},
      {{"vase",
        "Vase: surface of revolution with meridian rho(z) = radius + bulge sin(2 pi z / height), z in [0, height]; "
        "elliptic belly, hyperbolic neck, parabolic circle at half height (Figure 18).",
        {{"radius", 1.0, 1e-6, 1e6, "mean radius of the meridian"},
         {"bulge", 0.3, 0.0, 1e6, "amplitude of the meridian wave, must be less than radius"},
         {"height", 3.0, 1e-6, 1e6, "height (one wave of the meridian)"}}},
       [](const SurfaceParams& p) {
         const double R = p.at("radius"), A = p.at("bulge"), H = p.at("height");
         if (!(A < R))
           throw Error(ErrorCode::InvalidParameter,
                       "vase: bulge must be less than radius (got bulge=" + str(A) + ", radius=" + str(R) + ")");
         const double w = 2 * kPi / H;
         return revolution("vase", 0, H, [R, A, w](double v) {
           const double s = portable::sin(w * v), c = portable::cos(w * v);
           return Profile{{R + A * s, A * w * c, -A * w * w * s}, {v, 1, 0}};
         });
       }},
      {{"elliptic-paraboloid",
        "Elliptic paraboloid dome z = -x^2/(2 ra) - y^2/(2 rb) over a square, everywhere elliptic.",
        {{"ra", 1.5, 1e-6, 1e6, "radius of curvature at the apex along x"},
         {"rb", 1.0, 1e-6, 1e6, "radius of curvature at the apex along y"},
         {"size", 2.0, 1e-6, 1e6, "side of the square patch centred on the apex"}}},
       [](const SurfaceParams& p) {
         const double ka = 1 / p.at("ra"), kb = 1 / p.at("rb");
         return heightField("elliptic-paraboloid", p.at("size"), [ka, kb](double x, double y) {
           return Height{-0.5 * (ka * x * x + kb * y * y), -ka * x, -kb * y, -ka, 0, -kb};
         });
       }},
      {{"hyperbolic-paraboloid",
        "Hyperbolic paraboloid z = y^2/(2 rb) - x^2/(2 ra) over a square, everywhere hyperbolic.",
        {{"ra", 1.0, 1e-6, 1e6, "radius of curvature at the saddle point along x (bending down)"},
         {"rb", 1.0, 1e-6, 1e6, "radius of curvature at the saddle point along y (bending up)"},
         {"size", 2.0, 1e-6, 1e6, "side of the square patch centred on the saddle point"}}},
       [](const SurfaceParams& p) {
         const double ka = 1 / p.at("ra"), kb = 1 / p.at("rb");
         return heightField("hyperbolic-paraboloid", p.at("size"), [ka, kb](double x, double y) {
           return Height{0.5 * (kb * y * y - ka * x * x), -ka * x, kb * y, -ka, 0, kb};
         });
       }},
      {{"cylinder", "Circular cylinder around z, a developable: parabolic everywhere, rulings along z.",
        {{"R", 1.0, 1e-6, 1e6, "radius"}, {"height", 2.0, 1e-6, 1e6, "height, centred on z = 0"}}},
       [](const SurfaceParams& p) {
         const double R = p.at("R"), h = 0.5 * p.at("height");
         return revolution("cylinder", -h, h, [R](double v) { return Profile{{R, 0, 0}, {v, 1, 0}}; });
       }},
      {{"cone",
        "Circular cone around z opening upward from its apex at the origin, a developable: parabolic everywhere; "
        "trimmed away from the apex.",
        {{"angle", 30.0, 5.0, 80.0, "half-angle at the apex, in degrees"},
         {"start", 0.5, 1e-3, 1e6, "distance from the apex, along the rulings, where the surface starts"},
         {"length", 2.0, 1e-6, 1e6, "length of the rulings kept"}}},
       [](const SurfaceParams& p) {
         const double sa = portable::sin(radians(p.at("angle"))), ca = portable::cos(radians(p.at("angle")));
         const double s0 = p.at("start");
         return revolution("cone", s0, s0 + p.at("length"),
                           [sa, ca](double v) { return Profile{{v * sa, sa, 0}, {v * ca, ca, 0}}; });
       }},
      {{"plane", "Square patch of the plane z = 0 (planar points: every hexagonal mesh of it is a P-Hex mesh).",
        {{"size", 2.0, 1e-6, 1e6, "side of the square"}}},
       [](const SurfaceParams& p) {
         return heightField("plane", p.at("size"), [](double, double) { return Height{0, 0, 0, 0, 0, 0}; });
       }},
      {{"enneper",
        "Enneper's minimal surface (H = 0, K < 0) over the parameter square [-R, R]^2, inside the disc "
        "u^2 + v^2 < 3 beyond which it intersects itself.",
        {{"R", 1.0, 0.05, 1.2, "half-side of the parameter square (its corners stay inside the disc of radius sqrt(3))"}}},
       [](const SurfaceParams& p) { return enneper(p.at("R")); }},
      {{"catenoid", "Catenoid rho = c cosh(z / c) around z, a minimal surface (H = 0, K < 0).",
        {{"c", 1.0, 1e-6, 1e6, "waist radius"}, {"height", 2.0, 1e-6, 1e6, "height, centred on the waist"}}},
       [](const SurfaceParams& p) {
         const double c = p.at("c"), h = 0.5 * p.at("height");
         return revolution("catenoid", -h, h, [c](double v) {
           const double ch = portable::cosh(v / c), sh = portable::sinh(v / c);
           return Profile{{c * ch, sh, ch / c}, {v, 1, 0}};
         });
       }},
      {{"helicoid", "Helicoid around z, a ruled minimal surface (H = 0, K < 0): a strip crossing the axis.",
        {{"radius", 1.0, 1e-6, 1e6, "half-width of the strip (distance from the axis)"},
         {"pitch", 2.0, 1e-6, 1e6, "rise per full turn"},
         {"turns", 1.0, 0.05, 10.0, "number of turns"}}},
       [](const SurfaceParams& p) {
         return helicoid(p.at("radius"), p.at("pitch") / (2 * kPi), kPi * p.at("turns"));
       }},
      {{"freeform",
        "Free-form height field (Figure 22 kind): two Gaussian bumps on a shallow dome over a square; elliptic "
        "tops, hyperbolic flanks and saddle, parabolic curves between them.",
        {{"size", 3.0, 1e-6, 1e6, "side of the square"},
         {"height", 0.6, 0.0, 1e6, "height of the larger bump (the smaller one is 0.7 of it)"},
         {"width", 0.45, 1e-6, 1e6, "width (standard deviation) of the larger bump (the smaller one is 0.8 of it)"}}},
       [](const SurfaceParams& p) {
         const double L = p.at("size"), h = p.at("height"), w = p.at("width");
         const double kd = 1 / (2 * L);  // the dome's curvature keeps the far field curved, not planar
         return heightField("freeform", L, [L, h, w, kd](double x, double y) {
           const Height b1 = gaussian(x, y, -0.18 * L, -0.12 * L, h, w);
           const Height b2 = gaussian(x, y, 0.2 * L, 0.16 * L, 0.7 * h, 0.8 * w);
           return Height{b1.z + b2.z - 0.5 * kd * (x * x + y * y),
                         b1.zx + b2.zx - kd * x,
                         b1.zy + b2.zy - kd * y,
                         b1.zxx + b2.zxx - kd,
                         b1.zxy + b2.zxy,
                         b1.zyy + b2.zyy - kd};
         });
       }},
      {{"wave-roof",
        "Free-form roof (Figure 22 kind): a barrel vault across y carrying a wave along x whose crests bend with y; "
        "elliptic on one side of a curved parabolic curve, hyperbolic on the other, and free of umbilics, so its "
        "curvature lines form one regular net (the premise of the paper's Section 5.2).",
        {{"size", 3.0, 1e-6, 1e6, "side of the square"},
         {"radius", 2.0, 1e-6, 1e6, "radius of the barrel vault across y, more than half the side"},
         {"amplitude", 0.15, 0.0, 1e6, "amplitude of the wave along x"},
         {"wavenumber", 1.5, 0.0, 1e6, "wavenumber of the wave along x (radians per unit length)"},
         {"bend", 0.3, -1e6, 1e6, "bending of the wave crests: phase added per squared unit of y"}}},
       [](const SurfaceParams& p) {
         const double L = p.at("size"), R = p.at("radius"), A = p.at("amplitude"), w = p.at("wavenumber"),
                      b = p.at("bend");
         if (!(R > 0.5 * L))
           throw Error(ErrorCode::InvalidParameter, "wave-roof: radius must be more than half the side (got radius=" +
                                                        str(R) + ", size=" + str(L) + ")");
         return heightField("wave-roof", L, [R, A, w, b](double x, double y) {
           const double q = R * R - y * y, sq = std::sqrt(q);
           const double u = w * x + b * y * y, su = portable::sin(u), cu = portable::cos(u);
           const double uy = 2 * b * y;
           return Height{R - sq + A * su,
                         A * w * cu,
                         y / sq + A * cu * uy,
                         -A * w * w * su,
                         -A * su * w * uy,
                         R * R / (q * sq) + A * (-su * uy * uy + cu * 2 * b)};
         });
       }},
  };
  return entries;
}

}  // namespace

const std::vector<SurfaceSpec>& analyticSurfaces() {
  // The method that suits each surface: Method 2 along principal lines where the curvature lines form a
  // regular net (§7; on the helicoid it covers 86 % of the strip where Method 1 covers 67 %), the ruling-aligned lattice on developables (§3) and the
  // plane, the parameter lattice where the parameter lines are the curvature lines (torus, ring cyclide,
  // ellipsoid, Enneper: all hexagons, no seam). The bumps' umbilics inside parabolic rings leave no regular
  // conjugate network at all (§7): the global method's singular vertices cover them with fewer faces cut than
  // Method 2's systems of rows, and no strip left bare. The elliptic paraboloid's principal field has two umbilics
  // inside the patch, where Method 2 breaks down; its parameter lines are conjugate (z_xy = 0) and umbilic-free,
  // but they meet the square's sides at every angle between the patch's, and the rows along them ended up to 2
  // mean edges off the boundary curve (the corner left bare at 500 faces, 1.8 edges from any panel): the global
  // method's lattice follows the sides, 95-98 % hexagons with a clean edge, no face cut and no short edge
  // (METHOD.md, "Every analytic surface"). `--method prespecified --field param` lays the rows. The hyperboloid's
  // and the catenoid's parameter lines are their curvature lines too, the boundary circles among them: the lattice
  // rings them with the same count of panels in every row, no zip seam, the edge on the circles, where Method 2's
  // fronts met in a seam whose ends stood 1.7-5.3 mean edges off the boundary (the catenoid at 300, 500, 3000 and
  // 10000 faces, the hyperboloid at 500) and left panels 25-100 times smaller than the largest. The vase, whose
  // parabolic circles the parameter lattice crosses unconverged, and the wave roof (its lattice's hexagons far from
  // affinely regular) keep the rows. The helicoid's rows (along its curvature lines, 45 degrees to its helices and
  // rulings, which are asymptotic) stop short of its edges and leave strips up to 2.9 / 5.8 / 11 mean panel edges
  // wide bare at 1000 / 3000 / 10000 faces: the global method covers it (every point within 0.33 of a panel edge),
  // at 92-97 % hexagons and with a fifth to a third of its boundary panels cut in two (no planar panel along an
  // asymptotic boundary without folding, Prop. 5).
  struct Choice {
    const char* method;
    const char* field;
  };
  static const std::map<std::string, Choice> recommended = {
      {"torus", {"lattice", "principal"}},
      {"sphere", {"prespecified", "principal"}},
      {"ellipsoid", {"lattice", "principal"}},
      {"cyclide", {"lattice", "principal"}},
      {"vase", {"prespecified", "principal"}},
      {"hyperboloid", {"lattice", "principal"}},
      {"elliptic-paraboloid", {"global", "principal"}},
      {"hyperbolic-paraboloid", {"prespecified", "principal"}},
      {"freeform", {"global", "principal"}},
      {"wave-roof", {"prespecified", "principal"}},
      {"enneper", {"lattice", "principal"}},
      {"catenoid", {"lattice", "principal"}},
      {"helicoid", {"global", "principal"}},
      {"cylinder", {"lattice", "principal"}},
      {"cone", {"lattice", "principal"}},
      {"plane", {"lattice", "principal"}}};
  static const std::vector<SurfaceSpec> specs = [] {
    std::vector<SurfaceSpec> s;
    for (const Entry& e : registry()) {
      s.push_back(e.spec);
      const auto it = recommended.find(e.spec.name);
      if (it != recommended.end()) {
        s.back().method = it->second.method;
        s.back().field = it->second.field;
      }
    }
    return s;
  }();
  return specs;
}

ParametricSurfacePtr makeSurface(const std::string& name, const SurfaceParams& params) {
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
