# tomograin: the two commands a new machine needs (see README.md)
#   make demo   install what is missing, build (Release), run the main job
#   make test   install what is missing, build, run every test (ctest), incl. the sanitizer build
#   make bench  benchmarks (bench/); long, not part of the tests
JOBS ?= $(shell nproc)
BUILD ?= build/release
ASAN_BUILD ?= build/asan
CMAKE_FLAGS ?=

.PHONY: all deps build demo test test-release test-asan test-fuzz fuzz fuzz-build bench clean

all: build

deps:
	@scripts/install_deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DTOMOGRAIN_BENCH=OFF $(CMAKE_FLAGS)

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	$(BUILD)/apps/tomograin demo

test: test-release test-asan test-fuzz

test-release: build
	ctest --test-dir $(BUILD) -j $(JOBS) --output-on-failure --timeout 600

# Unit tests again under AddressSanitizer + UndefinedBehaviorSanitizer (-O1 -g),
# with the command's bad-input tests (ctest label `sanitize`: every error path
# of the apps, exit 2 and nothing written). The long numerical checks (ctest
# label `slow`: accuracy against synthetic truth, packing and settling
# statistics, the full crush; 10-30 s each under ASan, see the SLOW lists in
# tests/*/CMakeLists.txt) run in the Release stage only; their code is
# exercised here by the shorter tests of the same modules (a short crush:
# Crush.ShortCrushSplitsOnce).
# -g1: line tables (file:line in sanitizer reports) without full debug
# info, which tripled the compile time of the largest files (dem/engine.cpp
# 30 s -> 12 s) and kept `make test` over 15 minutes on the 2-core VM.
test-asan: deps
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" \
	  -DTOMOGRAIN_SANITIZE=ON -DTOMOGRAIN_BENCH=OFF $(CMAKE_FLAGS)
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --test-dir $(ASAN_BUILD) -j $(JOBS) -L 'unit|sanitize' -LE slow --output-on-failure --timeout 900

# libFuzzer harnesses for every file reader (clang). make fuzz FUZZ_SECONDS=600 for long runs.
FUZZ_BUILD ?= build/fuzz
FUZZ_SECONDS ?= 300
fuzz-build: deps
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" \
	  -DTOMOGRAIN_FUZZ=ON -DTOMOGRAIN_ONLY=core -DTOMOGRAIN_TESTS=OFF -DTOMOGRAIN_BENCH=OFF -DTOMOGRAIN_APPS=OFF
	cmake --build $(FUZZ_BUILD) -j $(JOBS)

fuzz: fuzz-build
	tests/fuzz/run.sh $(FUZZ_BUILD) $(FUZZ_SECONDS)

# Short fuzz runs inside `make test`, so reader regressions surface in CI.
test-fuzz: fuzz-build
	tests/fuzz/run.sh $(FUZZ_BUILD) ci

# Benchmarks build in their own folder so `make test` never compiles them.
BENCH_BUILD ?= build/bench
bench: deps
	scripts/install_deps.sh --bench
	cmake -S . -B $(BENCH_BUILD) -DCMAKE_BUILD_TYPE=Release -DTOMOGRAIN_BENCH=ON -DTOMOGRAIN_TESTS=OFF $(CMAKE_FLAGS)
	cmake --build $(BENCH_BUILD) -j $(JOBS)
	bench/run_all.sh $(BENCH_BUILD)

clean:
	rm -rf build
