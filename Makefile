# The two commands of the README: `make reproduce` and `make test`.
# Both install missing Debian packages, configure a Release build in build/, build with all cores, run.
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
OUT ?= out
# The MPI build (docs/cluster.md) is on here, so that `make test` checks it against one process.
# Both builds compile in batches (IMPLICIT_UNITY_BUILD): about 40 % less compile time from scratch.
CMAKE_FLAGS ?= -DIMPLICIT_WITH_MPI=ON -DIMPLICIT_UNITY_BUILD=ON
# Ninja when it is installed (scripts/install-deps.sh installs it): it starts a target's compiles
# while the libraries it links are still being built, where Make waits for them, so both cores stay
# busy (docs/design.md, "Build time"). A build folder keeps the generator it was made with.
GENERATOR = $(if $(wildcard $(1)/CMakeCache.txt),,$(if $(shell command -v ninja),-G Ninja))
# The sanitizer and fuzzing build (clang++ 14, ASan + UBSan, libFuzzer): docs/design.md, "Reliability".
SANITIZE_DIR ?= build-sanitize
SANITIZE_CXX ?= clang++-14
# What the clang build compiles, the examples and benchmarks among it (`make test` leaves them
# out; the slow test programs do not exist there: IMPLICIT_SLOW_TESTS is
# off), and the ctest labels it leaves out. A narrower list, e.g. SANITIZE_TARGETS="implicit_cli
# test_core", checks a part: ctest registers the other test programs as <program>_NOT_BUILT
# placeholders, which test-sanitize leaves out by name.
FUZZ_TARGETS = robot_log carpark slam_data results_json occupancy_map carmen_log resume_record \
  trajectory bag nav2_params
SANITIZE_TARGETS ?= implicit_cli implicit_toy test_core test_filter test_control test_robot test_slam test_da test_apps \
	$(addprefix fuzz_,$(FUZZ_TARGETS)) examples benchmarks
SANITIZE_EXCLUDE ?= slow|packaging|docs
# Each fuzz target runs this many seconds in `make fuzz-smoke` (a smoke test: tens of thousands
# of inputs per target; `make fuzz-smoke FUZZ_SECONDS=600` for a real session).
FUZZ_SECONDS ?= 6

.PHONY: all deps configure build build-tested test test-slow reproduce reproduce-quick crosscheck bench docs \
	install format clean configure-sanitize test-sanitize fuzz-smoke docs-check

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD_DIR) $(call GENERATOR,$(BUILD_DIR)) -DCMAKE_BUILD_TYPE=Release \
	  $(CMAKE_FLAGS) > /dev/null

# Everything: the library, the tool, the Python module, the tests, the examples and the benchmarks.
build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target all examples benchmarks

# What the tests run (all but the examples and the benchmarks, which CI compiles in test-sanitize).
build-tested: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

# The slow test programs exist only in a build configured with IMPLICIT_SLOW_TESTS=ON, which
# test-slow turns on (the build folder keeps it: its later builds compile them too, and `make test`
# still leaves their tests out by label).
test: build-tested
	@ctest --test-dir $(BUILD_DIR) -LE slow --output-on-failure -j $(JOBS)

test-slow: build-tested
	@cmake -S . -B $(BUILD_DIR) -DIMPLICIT_SLOW_TESTS=ON > /dev/null
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target tests_slow
	@ctest --test-dir $(BUILD_DIR) -L slow --output-on-failure -j $(JOBS)

# -O1 keeps the instrumented tests fast enough; assertions stay on (no NDEBUG). The packaging test
# is left out: its consumer is built with the default compiler, which cannot link an instrumented
# library, and `make test` runs it; so are the documentation checks (label docs), whose example
# programs `make test` builds and runs.
configure-sanitize: deps
	@CXX=$(SANITIZE_CXX) cmake -S . -B $(SANITIZE_DIR) $(call GENERATOR,$(SANITIZE_DIR)) \
	  -DCMAKE_BUILD_TYPE=Sanitize -DCMAKE_CXX_FLAGS_SANITIZE="-O1 -gline-tables-only" \
	  -DIMPLICIT_SANITIZE=ON -DIMPLICIT_BUILD_FUZZERS=ON -DIMPLICIT_BUILD_BENCHMARKS=ON \
	  -DIMPLICIT_BUILD_PYTHON=OFF -DIMPLICIT_BUILD_EXAMPLES=ON $(CMAKE_FLAGS) \
	  -DIMPLICIT_WITH_MPI=OFF > /dev/null

# The slowest sanitized test starts first instead of running alone at the end: on a fresh build
# ctest knows no costs, so one is seeded (ctest's own cost file, kept if present).
SANITIZE_FIRST ?= Cli.EveryOutputErrorNamesOutAndThePath
# Left out under the sanitizers for CI's time budget, all run by `make test`: the whole quick
# reproduce (5.5 min of one core there, a fifth of the sanitized suite) and the longest statistical
# runs (2.5 min of one core together), whose code the shorter sanitized tests of the same classes
# run as well (the arm experiment also through the `--only arm` quick reproduces).
SANITIZE_SKIP ?= ^(Reproduce\.QuickRunWritesTheReportResultsAndEveryFileOfEachSuccessfulExperiment|ArmExperiment\.GenericAndClosedFormGiveTheSameClosedLoop|DoubleSlitGeneric\.LogPsiAgreesWithTheExactSolution|PathIntegral\.TwoWallsInThePlaneAgreeWithPlainMonteCarlo|PathIntegral\.HardWallMixtureReproducesTheDoubleSlit|GlobalRun\.BothSourcesConvergeOnAnAsymmetricMap|Determinism\.DynamicSizeSameBitsForAnyThreadCount)$$
test-sanitize: configure-sanitize
	@cmake --build $(SANITIZE_DIR) -j $(JOBS) --target $(SANITIZE_TARGETS)
	@mkdir -p $(SANITIZE_DIR)/Testing/Temporary
	@test -f $(SANITIZE_DIR)/Testing/Temporary/CTestCostData.txt || \
	  printf '%s 1 50\n---\n' "$(SANITIZE_FIRST)" > $(SANITIZE_DIR)/Testing/Temporary/CTestCostData.txt
	@ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --test-dir $(SANITIZE_DIR) -LE "$(SANITIZE_EXCLUDE)" -E "_NOT_BUILT$$|$(SANITIZE_SKIP)" \
	  --output-on-failure -j $(JOBS)

# Each target from its seed corpus (fuzz/corpus/NAME, read only; new inputs go to
# $(SANITIZE_DIR)/fuzz-corpus/NAME) for FUZZ_SECONDS; any crash, sanitizer report, leak or
# timeout fails, and the input is saved in $(SANITIZE_DIR)/fuzz-artifacts/.
fuzz-smoke: configure-sanitize
	@cmake --build $(SANITIZE_DIR) -j $(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))
	@mkdir -p $(SANITIZE_DIR)/fuzz-artifacts
	@for t in $(FUZZ_TARGETS); do \
	  mkdir -p $(SANITIZE_DIR)/fuzz-corpus/$$t; \
	  echo "fuzz-smoke: $$t for $(FUZZ_SECONDS) s"; \
	  $(SANITIZE_DIR)/fuzz/fuzz_$$t $(SANITIZE_DIR)/fuzz-corpus/$$t fuzz/corpus/$$t \
	    -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
	    -artifact_prefix=$(SANITIZE_DIR)/fuzz-artifacts/$$t- -print_final_stats=1 \
	    2> $(SANITIZE_DIR)/fuzz-artifacts/$$t.log \
	  || { tail -n 60 $(SANITIZE_DIR)/fuzz-artifacts/$$t.log; exit 1; }; \
	  grep -E "^#[0-9]+ +DONE|stat::number_of_executed_units" $(SANITIZE_DIR)/fuzz-artifacts/$$t.log; \
	done

reproduce: build-tested
	@$(BUILD_DIR)/apps/implicit reproduce --out $(OUT)

reproduce-quick: build-tested
	@$(BUILD_DIR)/apps/implicit reproduce --quick --out $(OUT)

# The independent numpy implementations (python/crosscheck/) against the reference numbers the
# report uses: they read them from a results.json of `implicit reproduce` (here a quick Himmelblau
# run, which also carries Table 4's closed-form expectations; every results.json carries the
# reference numbers, Table 5's among them). Sizes: docs/reproducing.md.
CROSSCHECK_OUT ?= $(BUILD_DIR)/crosscheck
crosscheck: build-tested
	@$(BUILD_DIR)/apps/implicit reproduce --quick --only himmelblau --no-figures \
	  --out $(CROSSCHECK_OUT) > /dev/null
	@echo "== double slit (Table 2), 500 runs per cell =="
	@/usr/bin/python3 python/crosscheck/double_slit_numpy.py --runs 500 --samples 10,50,100 \
	  --seed 1 --compare $(CROSSCHECK_OUT)/results.json
	@echo "== Himmelblau (Table 4), 400 runs =="
	@/usr/bin/python3 python/crosscheck/himmelblau_numpy.py --runs 400 --seed 1 \
	  --compare $(CROSSCHECK_OUT)/results.json
	@echo "== Car Park MCL (Table 5), 10 runs of A:100, A:300, B:100, B:300 =="
	@/usr/bin/python3 python/crosscheck/mcl_numpy.py --runs 10 --cells A:100,A:300,B:100,B:300 \
	  --seed 1 --compare $(CROSSCHECK_OUT)/results.json
	@for m in ekf fastslam2 implicit implicit-rb; do \
	  echo "== SLAM $$m (Table 6), the 10 paper_le1 data sets, M = 100, one run each =="; \
	  /usr/bin/python3 python/crosscheck/slam_numpy.py --method $$m --particles 100 --seed 1 \
	    --compare $(CROSSCHECK_OUT)/results.json || exit 1; \
	done

bench: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target benchmarks

# The API reference: $(BUILD_DIR)/docs/html/index.html (Doxygen, from the public headers).
docs: configure
	@cmake --build $(BUILD_DIR) --target docs

# Every documentation check, the slow ones too: each number a doc states beside a `numbers slow:`
# comment is rerun with its command (some take minutes; docs/design.md, "Numbers in the docs").
docs-check: build-tested
	@ctest --test-dir $(BUILD_DIR) -L docs --output-on-failure -j $(JOBS)

# Installs the library, headers, CMake and pkg-config files, the CLI, the Python module, the data
# and the plot scripts under PREFIX (see README.md, "Install").
PREFIX ?= /usr/local
install: build
	@cmake --install $(BUILD_DIR) --prefix $(PREFIX)

format:
	@find include src apps examples bench tests python -name '*.hpp' -o -name '*.cpp' | xargs clang-format -i

clean:
	@rm -rf $(BUILD_DIR) $(SANITIZE_DIR)
