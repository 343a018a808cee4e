# phex — entry points. `make demo` and `make test` install what is missing, build, then serve or test.
SHELL := /bin/bash
.SHELLFLAGS := -eo pipefail -c
# Debian's emcc needs Node to find acorn; Emscripten 3.1.6 output under Node 20 needs the fetch flag.
export NODE_PATH := /usr/share/nodejs
NODE := node --no-experimental-fetch
PORT ?= 8080

.PHONY: all setup native wasm web test test-native test-wasm test-cli test-js test-browser test-fuzz fuzz demo bench clean

all: native wasm web

setup:
	@bash scripts/setup.sh

native: setup
	@cmake -S . -B build/native -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
	@cmake --build build/native

wasm: setup
	@[ -f build/wasm/build.ninja ] || emcmake cmake -S . -B build/wasm -G Ninja -DCMAKE_BUILD_TYPE=Release \
	  -DPHEX_PKG_DIR=$(CURDIR)/build/pkg >/dev/null
	@cmake --build build/wasm

web: wasm
	@npm run --silent build:web

test: native wasm web
	@$(MAKE) --no-print-directory test-native test-wasm test-cli test-js test-browser test-fuzz

test-native:
	@echo "== Catch2, native (ctest)"
	@ctest --test-dir build/native --output-on-failure

test-wasm:
	@echo "== Catch2, WebAssembly (node)"
	@cd build/wasm/tests && $(NODE) phex_tests.cjs

test-cli:
	@echo "== command line (node)"
	@node --test tests/cli/

test-js:
	@echo "== JS API (node)"
	@$(NODE) --test tests/js/

test-browser:
	@echo "== app in headless Chromium"
	@node --test tests/browser/

# Each fuzz target briefly (about a minute in all), so that a regression shows: from the seeds and regressions
# alone, since replaying a long campaign's corpus would take longer than that.
test-fuzz:
	@rm -rf build/fuzz/smoke
	@$(MAKE) --no-print-directory fuzz FUZZ_SECONDS=10 FUZZ_CORPUS=$(CURDIR)/build/fuzz/smoke

# The libFuzzer targets of tests/fuzz, built by clang with sanitizers in build/fuzz (apart from the release
# builds), each run for FUZZ_SECONDS.
FUZZ_SECONDS ?= 300
fuzz: setup
	@[ -f build/fuzz/build.ninja ] || CXX=clang++ cmake -S tests/fuzz -B build/fuzz -G Ninja >/dev/null
	@cmake --build build/fuzz
	@echo "== fuzzing, $(FUZZ_SECONDS) s per target"
	@FUZZ_SECONDS=$(FUZZ_SECONDS) FUZZ_CORPUS=$(FUZZ_CORPUS) bash tests/fuzz/run.sh

demo: native wasm web
	@node scripts/serve.js build/web $(PORT)

bench: native wasm web
	@echo "== pipeline, native and wasm (node)"
	@node bench/run.mjs
	@echo "== mesh loading and curvature, native then wasm"
	@build/native/bin/phex_bench_mesh_curvature
	@$(NODE) bench/mesh-curvature-wasm.mjs
	@echo "== laying triangulations, native"
	@build/native/bin/phex_bench_laying
	@echo "== the structure (axes, offset, beams, solid model), native then wasm, beside the pipeline"
	@build/native/bin/phex_bench_structure
	@$(NODE) bench/structure-wasm.mjs
	@echo "== web app in headless Chromium"
	@node bench/browser.mjs

clean:
	rm -rf build
