// phex — what the fuzz targets share: bad input is refused with a phex::Error of an expected code; anything
// else (another exception, a wrong answer, a sanitizer report, a hang) is a finding and aborts the run.
#pragma once
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <initializer_list>

#include <phex/error.hpp>
#include <phex/mesh.hpp>
#include <phex/parallel.hpp>

namespace phex_fuzz {

[[noreturn]] inline void finding(const char* what, const char* detail = "") {
  std::fprintf(stderr, "phex fuzz finding: %s %s\n", what, detail);
  std::abort();
}

inline void check(bool ok, const char* what) {
  if (!ok) finding("wrong answer:", what);
}

// Runs body; an Error whose code is in `refusals` is a refusal of the input, as it should be.
template <class Body>
void expectRefusalOnly(std::initializer_list<phex::ErrorCode> refusals, Body body) {
  try {
    body();
  } catch (const phex::Error& e) {
    for (phex::ErrorCode code : refusals)
      if (e.code() == code) return;
    finding(phex::errorCodeName(e.code()), e.what());
  } catch (const std::exception& e) {
    finding("exception:", e.what());
  }
}

// Bytes read front to back; zeros once they run out.
struct Input {
  const std::uint8_t* data;
  std::size_t size;
  std::uint8_t byte() { return size > 0 ? (--size, *data++) : 0; }
  double raw() {
    std::uint8_t b[8] = {0};
    for (std::uint8_t& x : b) x = byte();
    double d;
    std::memcpy(&d, b, 8);
    return d;
  }
};

// A small triangle mesh: a byte each for the vertex count (3..34), the triangle count (1..48), a power-of-two
// scale (2^-256 .. 2^254: beyond phex's coordinate limit both ways) and flags; then per vertex three
// coordinates (bytes as signed steps times the scale, or raw doubles where flags & 1: NaN, infinities,
// subnormals), then three vertex ids per triangle.
inline phex::TriMesh decodeMesh(Input& in) {
  const int nv = 3 + in.byte() % 32, nf = 1 + in.byte() % 48;
  const double scale = std::ldexp(1.0, 2 * static_cast<std::int8_t>(in.byte()));
  const bool raw = in.byte() & 1;
  phex::TriMesh m;
  m.V.resize(nv, 3);
  for (int v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) m.V(v, k) = raw ? in.raw() : static_cast<std::int8_t>(in.byte()) * scale;
  m.F.resize(nf, 3);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) m.F(f, k) = in.byte() % nv;
  return m;
}

}  // namespace phex_fuzz

// Each target is its own program, including this once. One thread: a run is the same whatever the count, and
// pool threads would only slow the sanitizers down.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  phex::setThreadCount(1);
  return 0;
}
