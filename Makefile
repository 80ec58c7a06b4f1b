# SPDX-License-Identifier: MIT
# The README's two commands live here: `make demo` and `make test`. Both install what is missing first.
BUILD      ?= build
ASAN_BUILD ?= build-asan
JOBS       ?= $(shell nproc)
CMAKE_GEN  := $(shell command -v ninja >/dev/null 2>&1 && echo "-G Ninja")
WERROR     ?= $(if $(CI),ON,OFF)# ON: the project's warnings are errors (on by default where CI is set, as in .ci/run)

.PHONY: deps build demo test test-sanitize bench fuzz clean

deps:
	@bash scripts/install-deps.sh

build: deps
	cmake -S . -B $(BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=Release -DIMPS_WERROR=$(WERROR)
	cmake --build $(BUILD) -j $(JOBS)

# The main job on a bundled example: mesh the simple biped and write a glTF you can open anywhere.
demo: build
	@mkdir -p out
	$(BUILD)/puppeteer/puppeteer check examples/simple_biped.wrl
	$(BUILD)/puppeteer/puppeteer mesh examples/simple_biped.wrl --cell 0.02 -o out/simple_biped.glb
	@echo "demo: wrote out/simple_biped.glb (open it in Blender or any glTF viewer)"

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 600

# The same tests under AddressSanitizer + UndefinedBehaviorSanitizer (Debug build, slow tests skipped). Leaks inside
# system libraries are suppressed by tests/lsan.supp; the GL tests do not check leaks (tests/CMakeLists.txt).
test-sanitize: deps
	cmake -S . -B $(ASAN_BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=Debug -DIMPS_SANITIZE=ON -DIMPS_BUILD_BENCH=OFF
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp ctest --output-on-failure -j $(JOBS) \
	    -LE slow --timeout 900

# Every libFuzzer target, FUZZ_SECONDS each, starting from its seeds (clang 16, ASan + UBSan, UB fatal). Readers of
# whole files, where size matters (limits, quadratic checks), get inputs up to FUZZ_LARGE_LEN bytes; wire codecs
# keep libFuzzer's default.
FUZZ_BUILD     ?= build-fuzz
FUZZ_SECONDS   ?= 60
FUZZ_LARGE_LEN ?= 262144
FUZZ_LARGE     := vrml_file bvh_reader bvh_session check_pose rig_map scene_polygonize scene_reader session_reader
FUZZ_TARGETS   := $(patsubst tests/fuzz/%.cpp,%,$(wildcard tests/fuzz/*_fuzz.cpp))
fuzz:
	@bash scripts/install-deps.sh fuzz
	cmake -S . -B $(FUZZ_BUILD) $(CMAKE_GEN) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIMPS_FUZZ=ON \
	  -DCMAKE_C_COMPILER=clang-16 -DCMAKE_CXX_COMPILER=clang++-16 -DIMPS_BUILD_BENCH=OFF
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target $(FUZZ_TARGETS)
	@for f in $(FUZZ_BUILD)/tests/fuzz/*_fuzz; do \
	  name=$$(basename $$f _fuzz); mkdir -p $(FUZZ_BUILD)/corpus/$$name; \
	  len=""; case " $(FUZZ_LARGE) " in *" $$name "*) len="-max_len=$(FUZZ_LARGE_LEN)";; esac; \
	  echo "== $$name"; $$f -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 $$len \
	    $(FUZZ_BUILD)/corpus/$$name tests/fuzz/seeds/$$name || exit 1; \
	done

bench: build
	$(BUILD)/bench/imps_bench

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) out
