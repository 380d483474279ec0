# Thin wrapper over CMake presets. `make` builds build/bin/cambium; `make run` runs the main job
# on the built-in default; `make test` builds and runs every test. Each installs the Debian
# packages the project needs first (cmake/debian-packages.txt).
.PHONY: all deps configure build run test asan fuzz format format-check check tidy bench install \
        clean
# `make install PREFIX=/opt/cambium DESTDIR=/tmp/stage` (docs: README, "Installing and linking")
PREFIX ?= /usr/local

all: build

deps:
	@bash cmake/install-deps.sh

configure: deps
	@cmake --preset default >/dev/null

build: configure
	@cmake --build --preset default

run: build
	@bash examples/run-default.sh build/bin/cambium out

test: build
	@ctest --preset default

asan: deps
	@cmake --preset asan >/dev/null
	@cmake --build --preset asan
	@ctest --preset asan

fuzz: deps
	@cmake --preset fuzz >/dev/null
	@cmake --build --preset fuzz

format:
	@clang-format -i $$(git ls-files '*.c' '*.h')

format-check:
	@clang-format --dry-run --Werror $$(git ls-files '*.c' '*.h')

check: format-check
	@bash .ci/check-layers.sh
	@cppcheck --quiet --error-exitcode=1 --enable=warning,performance,portability \
	  --inline-suppr --suppress=missingIncludeSystem -I include -I src src tools

bench: build
	@echo "benchmark programs are in build/bin (see docs/performance.md)"

# clang-tidy over the library, the tool, the tests and the benchmarks with the checks of
# .clang-tidy (tests/ and bench/ leave out a few, each with its reason; findings are errors)
tidy: configure
	@run-clang-tidy-14 -p build -j 2 -quiet '$(CURDIR)/(src|tools|tests|bench)/' >build/tidy.log 2>&1 || \
	  { grep -E '(warning|error):' build/tidy.log | sort -u; echo "make tidy: findings above"; exit 1; }
	@echo "make tidy: clean"

install: build
	@DESTDIR="$(DESTDIR)" cmake --install build --prefix "$(PREFIX)"

clean:
	@rm -rf build build-asan build-fuzz
