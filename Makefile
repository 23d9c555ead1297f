# The two commands of the README: `make reproduce` and `make test`.
# Both install missing Debian packages, configure a Release build in build/, build with all cores, run.
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
OUT ?= out
CMAKE_FLAGS ?=

.PHONY: all deps configure build test test-slow reproduce reproduce-quick bench docs install format clean

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

# The API reference: $(BUILD_DIR)/docs/html/index.html (Doxygen, from the public headers).
docs: configure
	@cmake --build $(BUILD_DIR) --target docs

# Installs the library, headers, CMake and pkg-config files, the CLI, the Python module, the data
# and the plot scripts under PREFIX (see README.md, "Install").
PREFIX ?= /usr/local
install: build
	@cmake --install $(BUILD_DIR) --prefix $(PREFIX)

format:
	@find include src apps examples bench tests python -name '*.hpp' -o -name '*.cpp' | xargs clang-format -i

clean:
	@rm -rf $(BUILD_DIR)
