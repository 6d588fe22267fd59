# Entry points. `make demo` and `make test` are the two README commands.
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

.PHONY: deps configure build test demo package check-package bench fuzz test-sanitize test-tsan check-integrity clean

deps:
	./scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD_DIR) -G Ninja $(CMAKE_FLAGS) -DVIOSFM_BUILD_TESTS=ON \
	  -DVIOSFM_BUILD_BENCHMARKS=ON

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

# Builds and runs every test (tests needing ../shared/data skip without it).
test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

# Installs what the program needs, builds the `viosfm` program alone and runs
# the main job on the built-in simulated default, each step timed.
demo:
	JOBS=$(JOBS) CMAKE_FLAGS="$(CMAKE_FLAGS)" ./scripts/demo.sh --setup $(BUILD_DIR)

# The Debian package build/viosfm_VERSION_ARCH.deb (the `viosfm` program; its
# dependencies are the libraries it links and libjs-three): install it with
# `apt-get install ./build/viosfm_*.deb`.
package:
	./scripts/install-deps.sh --demo
	cmake -S . -B $(BUILD_DIR) -G Ninja $(CMAKE_FLAGS) -DVIOSFM_BUILD_TESTS=OFF \
	  -DVIOSFM_BUILD_BENCHMARKS=OFF
	cmake --build $(BUILD_DIR) -j $(JOBS) --target viosfm
	cd $(BUILD_DIR) && cpack -G DEB

# Installs the package of `make package` into a clean Debian 12 root
# (debootstrap, chroot; needs root) and runs `viosfm --help` and a short run
# there: scripts/check-package.sh.
check-package: package
	./scripts/check-package.sh $$(ls $(BUILD_DIR)/viosfm_*.deb | head -n 1) build-check-package

# Builds the benchmarks and runs them; see docs/benchmarks.md.
bench: configure
	cmake --build $(BUILD_DIR) -j $(JOBS) --target viosfm_benchmarks viosfm
	./scripts/run-benchmarks.sh $(BUILD_DIR)

# Fuzzes every parser of io/ with libFuzzer (clang, ASan + UBSan, build-fuzz/),
# FUZZ_SECONDS (default 60) each; see docs/robustness.md. Not part of `make test`.
fuzz: deps
	./scripts/fuzz.sh build-fuzz

# Builds and runs the whole test suite with AddressSanitizer and
# UndefinedBehaviorSanitizer (build-sanitize/); see docs/robustness.md.
# Not part of `make test`.
test-sanitize: deps
	JOBS=$(JOBS) ./scripts/test-sanitize.sh build-sanitize

# Builds and runs the tests that start threads with ThreadSanitizer
# (build-tsan/); see docs/robustness.md. Not part of `make test`.
test-tsan: deps
	JOBS=$(JOBS) ./scripts/test-tsan.sh build-tsan

# Runs of `viosfm run` on a small simulated sequence: identical re-runs, a
# second dataset into the same folder, SIGKILL and re-run, thread counts,
# hostile inputs (build/integrity/); see docs/robustness.md. Not part of
# `make test`.
check-integrity: configure
	cmake --build $(BUILD_DIR) -j $(JOBS) --target viosfm
	./scripts/check-integrity.sh $(BUILD_DIR)

clean:
	rm -rf $(BUILD_DIR)
