# The two commands of the README: `make run` and `make test`. Both install what
# they need first (scripts/setup.sh is idempotent), so they work on a fresh machine.
SHELL := /bin/bash
ROOT := $(CURDIR)
BUILD_TYPE ?= RelWithDebInfo

.PHONY: run test setup build package package-test check test-python test-cpp test-frontend bench screenshots clean

setup:
	@scripts/setup.sh

# C++ runtime: binaries land in build/bin/. Only what runs (the PubBroker): the
# unit tests are built by `make test` (runtime/cpp/scripts/test.sh), so a first
# `make run` does not wait for them.
build: setup
	@if [ -f runtime/cpp/CMakeLists.txt ]; then \
	  cmake -S runtime/cpp -B build/cpp -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) \
	        -DMODD_BIN_DIR=$(ROOT)/build/bin >/dev/null && \
	  cmake --build build/cpp --target modd-pubbroker ; \
	fi

run: build
	@scripts/run.sh

# Debian packages of the drone and the base station, amd64 and arm64, in build/package/
# (packaging/README.md); checked with lintian and systemd-analyze verify.
package: build
	@scripts/setup.sh arm64
	@packaging/build.sh

# The install test (tests/subbroker/test_install_root.py): the amd64 packages (built
# here if missing) installed offline into a clean Debian root (packaging/test-root.sh,
# cached in build/installroot/), scenario 1 run from it as the modd user, upgrade, purge;
# a fresh drone paired with modd-pair (tests/subbroker/test_install_pair.py); and the
# units' own command lines (ExecStart) run as the modd user, following deploys that add
# and remove an instrument (tests/subbroker/test_install_units.py).
package-test: setup
	@ls build/package/modd-drone_*_amd64.deb build/package/modd-base_*_amd64.deb >/dev/null 2>&1 \
	  || ARCHS=amd64 packaging/build.sh
	@.venv/bin/pytest -q -m "e2e or slow" tests/subbroker/test_install_root.py tests/subbroker/test_install_pair.py \
	  tests/subbroker/test_install_units.py

test: build
	@scripts/check.sh

# The fast tier (formatters, linters, types, unit tests): under 2 minutes.
check: setup
	@scripts/check-fast.sh

test-python: setup
	@.venv/bin/pytest -q

test-cpp: build
	@if [ -x runtime/cpp/scripts/test.sh ]; then runtime/cpp/scripts/test.sh; fi

bench: build
	@scripts/bench.sh

# The user guide's pictures (docs/images), taken by the browser journey; tests
# themselves write their screenshots to a temporary folder.
screenshots: build
	@cd frontend && MODD_SCREENSHOTS=docs/images npm run test:e2e

clean:
	rm -rf build .venv frontend/node_modules frontend/dist
