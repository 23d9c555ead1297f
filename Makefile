# The two commands of the README: `make reproduce` and `make test`.
# Both install missing Debian packages, configure a Release build in build/, build with all cores, run.
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
OUT ?= out
CMAKE_FLAGS ?=

.PHONY: all deps configure build test test-slow reproduce reproduce-quick bench format clean

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) > /dev/null

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	@ctest --test-dir $(BUILD_DIR) -LE slow --output-on-failure -j $(JOBS)

test-slow: build
	@ctest --test-dir $(BUILD_DIR) -L slow --output-on-failure -j $(JOBS)

reproduce: build
	@$(BUILD_DIR)/apps/implicit reproduce --out $(OUT)

reproduce-quick: build
	@$(BUILD_DIR)/apps/implicit reproduce --quick --out $(OUT)

bench: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target benchmarks

format:
	@find include src apps examples bench tests python -name '*.hpp' -o -name '*.cpp' | xargs clang-format -i

clean:
	@rm -rf $(BUILD_DIR)
