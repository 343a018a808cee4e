// phex — elementary functions computed with +, -, *, / alone (and exact scalings by powers of two), so that
// every platform rounds them alike: glibc's and musl's sin, cos and exp differ in the last bit here and there,
// and the methods' discrete decisions (which lattice point, which side of a threshold) can grow such a bit into
// another mesh between the native and the WebAssembly build. Accurate to a few units in the last place.
#pragma once
#include <cmath>

namespace phex::portable {

namespace detail {
// pi / 2 in three parts (Cody-Waite), each with trailing zeros so that k * part is exact for |k| < 2^20.
constexpr double kHalfPi1 = 1.5707963267341256e+00, kHalfPi2 = 6.0771005065061922e-11, kHalfPi3 = 2.0222662487959506e-21;
constexpr double kTwoOverPi = 6.3661977236758138e-01;
// Taylor series of sin and cos on [-pi/4, pi/4] (the remainders are below 1e-17 there).
inline double sinKernel(double x) {
  const double x2 = x * x;
  return x + x * x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040 + x2 * (1.0 / 362880 + x2 * (-1.0 / 39916800 +
         x2 * (1.0 / 6227020800 + x2 * (-1.0 / 1307674368000 + x2 * (1.0 / 355687428096000))))))));
}
inline double cosKernel(double x) {
  const double x2 = x * x;
  return 1 + x2 * (-0.5 + x2 * (1.0 / 24 + x2 * (-1.0 / 720 + x2 * (1.0 / 40320 + x2 * (-1.0 / 3628800 +
         x2 * (1.0 / 479001600 + x2 * (-1.0 / 87178291200 + x2 * (1.0 / 20922789888000))))))));
}
// x reduced to [-pi/4, pi/4] and its quadrant.
inline double reduce(double x, int& quadrant) {
  const double k = std::nearbyint(x * kTwoOverPi);
  quadrant = static_cast<int>(static_cast<long long>(k) & 3);
  return ((x - k * kHalfPi1) - k * kHalfPi2) - k * kHalfPi3;
}
// sin of r + quadrant * pi/2.
inline double inQuadrant(double r, int quadrant) {
  switch (quadrant & 3) {
    case 0: return sinKernel(r);
    case 1: return cosKernel(r);
    case 2: return -sinKernel(r);
    default: return -cosKernel(r);
  }
}
}  // namespace detail

// For |x| up to about 1e6 (angles of surfaces: a few turns).
inline double sin(double x) {
  if (!std::isfinite(x)) return std::nan("");
  int q = 0;
  const double r = detail::reduce(x, q);
  return detail::inQuadrant(r, q);
}
// cos x = sin(x + pi/2): the same reduced argument, a quadrant on.
inline double cos(double x) {
  if (!std::isfinite(x)) return std::nan("");
  int q = 0;
  const double r = detail::reduce(x, q);
  return detail::inQuadrant(r, q + 1);
}

// e^x: x = k ln 2 + r with |r| <= ln 2 / 2, e^r by its Taylor series, scaled by 2^k exactly.
inline double exp(double x) {
  if (std::isnan(x)) return x;
  if (x > 709.78) return HUGE_VAL;
  if (x < -745.2) return 0.0;
  constexpr double kLn2Hi = 6.93147180369123816490e-01, kLn2Lo = 1.90821492927058770002e-10;
  const double k = std::nearbyint(x / 0.69314718055994530942);
  const double r = (x - k * kLn2Hi) - k * kLn2Lo;
  double term = 1, sum = 1;
  for (int n = 1; n <= 14; ++n) term *= r / n, sum += term;
  return std::ldexp(sum, static_cast<int>(k));
}

// ln x (x > 0): x = m 2^e with m in [sqrt(1/2), sqrt 2), ln m = 2 atanh((m - 1) / (m + 1)) by its series.
inline double log(double x) {
  if (!(x > 0)) return x == 0 ? -HUGE_VAL : std::nan("");
  if (!std::isfinite(x)) return x;
  int e = 0;
  double m = std::frexp(x, &e);  // m in [0.5, 1)
  if (m < 0.70710678118654752440) m *= 2, --e;
  const double s = (m - 1) / (m + 1), s2 = s * s;
  double term = s, sum = 0;
  for (int n = 1; n <= 41; n += 2) sum += term / n, term *= s2;
  return 2 * sum + e * 0.69314718055994530942;
}

inline double sinh(double x) {
  if (std::abs(x) < 0.5) {  // the series, where e^x - e^-x would cancel
    const double x2 = x * x;
    return x * (1 + x2 / 6 * (1 + x2 / 20 * (1 + x2 / 42 * (1 + x2 / 72 * (1 + x2 / 110 * (1 + x2 / 156 * (1 + x2 / 210)))))));
  }
  const double e = exp(x);
  return 0.5 * (e - 1 / e);
}
inline double cosh(double x) {
  const double e = exp(x);
  return 0.5 * (e + 1 / e);
}
inline double asinh(double x) {
  const double a = std::abs(x);
  double r;
  if (a < 1e-2) {
    const double a2 = a * a;
    r = a * (1 - a2 / 6 * (1 - 9 * a2 / 20 * (1 - 25 * a2 / 42)));
  } else {
    r = log(a + std::sqrt(a * a + 1));
  }
  return x < 0 ? -r : r;
}

}  // namespace phex::portable
