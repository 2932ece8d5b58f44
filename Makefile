# Thin wrapper over CMake. `make demo` and `make test` install missing Debian packages first
# (scripts/setup-deps.sh, silent when all is present), then configure, build and run.
BUILD ?= build
ASAN_BUILD ?= build-asan
CLANG_BUILD ?= build-clang
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 60
# Only definite leaks and memory errors count: OpenMP and TBB keep their thread stacks to the end.
VALGRIND_OPTIONS = --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite --show-possibly-lost=no -q
ASAN_TESTS ?=
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps build clang-build demo tour check test test-asan test-valgrind fuzz fuzz-regress bench accuracy install clean

all: build

deps:
	@sh scripts/setup-deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

# The demo needs the prt program only: the tests and benches are left for `make` and `make test`.
demo: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS) --target prt
	@sh scripts/demo.sh $(BUILD)/prt out/demo

# The README's tour, run as written (scripts/tour.sh), in the time its title states.
tour: build
	@TOUR_STRICT_TIME=1 sh scripts/tour.sh

# Quick feedback while working (under a minute once built): the tests labelled quick, gcc only.
check: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) -L quick

# Every test, then the quick ones (label "quick") again under valgrind, and those and a few more
# (label "asan": resumed bakes, bakes through the table) under ASan+UBSan.
test: build clang-build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)
	$(MAKE) --no-print-directory test-valgrind VALGRIND_TESTS="-L quick"
	$(MAKE) --no-print-directory test-asan ASAN_TESTS="-L 'quick|asan'"

# The same sources with clang and -Werror: prt stays portable C11 + intrinsics (libFuzzer needs clang).
clang-build: deps
	cmake -S . -B $(CLANG_BUILD) -DCMAKE_C_COMPILER=clang -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF $(CMAKE_FLAGS) >/dev/null
	cmake --build $(CLANG_BUILD) -j $(JOBS)

# AddressSanitizer + UndefinedBehaviorSanitizer build running the same tests.
test-asan: deps
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=Debug -DPRT_SANITIZE=ON >/dev/null
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j $(JOBS) $(ASAN_TESTS)

# valgrind memcheck over the tests of the normal build (portable -march=x86-64-v3 code: valgrind
# cannot run AVX-512). VALGRIND_TESTS="-L quick" narrows it, as `make test` does.
test-valgrind: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) -T memcheck $(VALGRIND_TESTS) --overwrite MemoryCheckCommand=$$(command -v valgrind) \
		--overwrite "MemoryCheckCommandOptions=$(VALGRIND_OPTIONS)"

# libFuzzer (clang, ASan + UBSan; no -Werror: instrumented code cannot honour every simd pragma) on
# every harness in fuzz/ for FUZZ_SECONDS each; crashes land in
# fuzz/crashes/NAME/ (copy them into fuzz/regress/NAME/ once fixed).
fuzz: deps
	cmake -S . -B $(FUZZ_BUILD) -DCMAKE_C_COMPILER=clang -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPRT_SANITIZE=ON -DPRT_FUZZ=ON -DPRT_WERROR=OFF -DBUILD_TESTING=OFF >/dev/null
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target fuzz_image fuzz_prt fuzz_scene fuzz_mesh fuzz_ies fuzz_grid
	@sh scripts/fuzz.sh $(FUZZ_BUILD) $(FUZZ_SECONDS)

fuzz-regress: build
	cd $(BUILD) && ctest -R fuzz-regress --output-on-failure

# Every bench (bench/bench_NAME.c, built as prt_bench_NAME) with its defaults, then the runs that
# need more: the spectral method's closed room, the light cloud on Sponza.
bench: build
	@for b in $(BUILD)/prt_bench_*; do echo "== $$b"; $$b || exit 1; done
	$(BUILD)/prt_bench_spectral --room
	@if [ -f ../shared/data/meshes/sponza/sponza_dabrovic.obj ]; then $(BUILD)/prt_bench_lightcloud ../shared/data/meshes/sponza/sponza_dabrovic.obj --grid 12,4,8 --zone-vertices 500; \
	else echo "bench: ../shared/data/meshes/sponza is absent: skipping the Sponza light cloud"; fi

# README's accuracy tables: PRT against the path-traced reference (several minutes).
accuracy: build
	@sh scripts/accuracy.sh $(BUILD)/prt out/accuracy

# make install PREFIX=/usr/local (the default): prt, libprt.{a,so}, headers, prt.pc, the CMake
# package (find_package(prt)), man pages. Then `ldconfig` (or an rpath) for programs using libprt.so.
PREFIX ?= /usr/local
install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(CLANG_BUILD) $(FUZZ_BUILD) out
