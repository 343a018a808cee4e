#!/usr/bin/env bash
# phex: install what the build needs, from Debian's packages and the npm registry only.
# Idempotent: each step checks first and does nothing when its result is already there.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cache="${PHEX_CACHE:-$HOME/.cache/phex}"
ceres_wasm="$cache/ceres-wasm"
sudo=""; [ "$(id -u)" = 0 ] || sudo="sudo"

need_pkgs=()
# clang and libclang-rt-dev (libFuzzer's and the sanitizers' runtimes) build the fuzz targets (make fuzz).
for p in g++ cmake ninja-build make libeigen3-dev libceres-dev catch2 nlohmann-json3-dev libfast-float-dev libtinygltf-dev emscripten chromium nodejs dpkg-dev clang libclang-rt-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need_pkgs+=("$p")
done
if [ ${#need_pkgs[@]} -gt 0 ]; then
  echo "phex setup: installing Debian packages: ${need_pkgs[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${need_pkgs[@]}" >/dev/null
fi
command -v npm >/dev/null || { DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq npm >/dev/null; }

# Ceres for WebAssembly: a minimal build from Debian's own source package, cached outside the repo.
ceres_flags="-DMINIGLOG=ON -DMINIGLOG_MAX_LOG_LEVEL=-2 -DGFLAGS=OFF -DSUITESPARSE=OFF -DCXSPARSE=OFF -DLAPACK=OFF
  -DEIGENSPARSE=ON -DSCHUR_SPECIALIZATIONS=OFF -DCERES_THREADING_MODEL=NO_THREADS -DBUILD_TESTING=OFF
  -DBUILD_EXAMPLES=OFF -DBUILD_BENCHMARKS=OFF -DBUILD_SHARED_LIBS=OFF"
# Rebuilt when missing or when the flags above change (the stamp records them).
if [ ! -f "$ceres_wasm/lib/libceres.a" ] || [ "$(cat "$ceres_wasm/phex-flags" 2>/dev/null)" != "$ceres_flags" ]; then
  rm -rf "$ceres_wasm"
  echo "phex setup: building Ceres for WebAssembly into $ceres_wasm (a few minutes, once)"
  src_list=/etc/apt/sources.list.d/phex-deb-src.sources
  if ! grep -rqs '^Types:.*deb-src' /etc/apt/sources.list.d/ && ! grep -qs '^deb-src' /etc/apt/sources.list 2>/dev/null; then
    if [ -f /etc/apt/sources.list.d/debian.sources ]; then
      sed 's/^Types: deb$/Types: deb-src/' /etc/apt/sources.list.d/debian.sources | $sudo tee "$src_list" >/dev/null
    else
      grep '^deb ' /etc/apt/sources.list | sed 's/^deb /deb-src /' | $sudo tee /etc/apt/sources.list.d/phex-deb-src.list >/dev/null
    fi
    $sudo apt-get update -qq
  fi
  work="$cache/ceres-src"
  rm -rf "$work"; mkdir -p "$work"
  (cd "$work" && apt-get source -qq --download-only ceres-solver >/dev/null 2>&1 || true
   cd "$work" && dpkg-source -x --no-check ceres-solver_*.dsc src >/dev/null)
  export NODE_PATH=/usr/share/nodejs
  emcmake cmake -S "$work/src" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_INSTALL_PREFIX="$ceres_wasm" $ceres_flags \
    -DEigen3_DIR=/usr/share/eigen3/cmake -DCMAKE_CXX_FLAGS="-ffp-contract=off" >"$work/configure.log" 2>&1 \
    || { tail -30 "$work/configure.log"; exit 1; }
  cmake --build "$work/build" -j"$(nproc)" >"$work/build.log" 2>&1 || { tail -40 "$work/build.log"; exit 1; }
  cmake --install "$work/build" >/dev/null
  printf '%s' "$ceres_flags" > "$ceres_wasm/phex-flags"
  rm -rf "$work"
fi

# npm packages from the committed lock file.
if [ -f "$here/package-lock.json" ]; then
  if [ ! -d "$here/node_modules" ] || [ "$here/package-lock.json" -nt "$here/node_modules/.package-lock.json" ]; then
    (cd "$here" && npm ci --no-audit --no-fund --loglevel=error)
  fi
fi
echo "phex setup: ok"
