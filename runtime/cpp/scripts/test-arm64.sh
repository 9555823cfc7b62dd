#!/usr/bin/env bash
# The C++ runtime built for aarch64 (the companion computers' architecture) with
# Debian's cross toolchain, its unit tests run under qemu-user: run by `make test`
# (scripts/check.sh) beside the other C++ checks, and by `make package` (--build-only).
#   build/cpp-arm64/bin/modd-pubbroker   the PubBroker for arm64 (packaging/, the
#                                        cross-architecture link test in tests/runtime)
#   build/cpp-arm64/modd_unit_tests      the GoogleTest units, run by ctest through
#                                        CMAKE_CROSSCOMPILING_EMULATOR (qemu-aarch64-static)
# Installs what it needs first (scripts/setup.sh arm64: idempotent). The build dir is
# kept: a second run only rebuilds what changed. JOBS (default 1) compile jobs.
set -euo pipefail
cd "$(dirname "$0")/../../.."
ROOT=$PWD
JOBS=${JOBS:-1}
BUILD=build/cpp-arm64
scripts/setup.sh arm64
mkdir -p $BUILD
exec 9>$BUILD.lock
flock 9  # one build of $BUILD at a time (make test and make package may overlap)
command -v ccache >/dev/null && export CMAKE_CXX_COMPILER_LAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER:-ccache}

# pkg-config (FindOpenSSL asks it first) must see the arm64 libraries, not the host's
export PKG_CONFIG_LIBDIR=/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig
echo "== C++ arm64: build ($BUILD, cross toolchain runtime/cpp/cmake/aarch64-linux-gnu.cmake)"
cmake -S runtime/cpp -B $BUILD -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCMAKE_TOOLCHAIN_FILE="$ROOT/runtime/cpp/cmake/aarch64-linux-gnu.cmake" \
      -DCMAKE_CROSSCOMPILING_EMULATOR=/usr/bin/qemu-aarch64-static \
      -DMODD_BIN_DIR="$ROOT/$BUILD/bin" >/dev/null
if [ "${1:-}" = --build-only ]; then
  cmake --build $BUILD -j"$JOBS" --target modd-pubbroker
  exit 0
fi
cmake --build $BUILD -j"$JOBS" --target modd-pubbroker modd_unit_tests
# ELF e_machine 183: EM_AARCH64
[ "$(od -An -tu2 -j18 -N2 $BUILD/bin/modd-pubbroker | tr -d ' ')" = 183 ] || {
  echo "$BUILD/bin/modd-pubbroker is not an aarch64 binary" >&2; exit 1; }

echo "== C++ arm64: ctest under qemu-aarch64-static"
# example_project_builds builds an integrator's project with the host's compiler: the
# amd64 lane runs it.
(cd $BUILD && ctest --output-on-failure -j"$JOBS" --timeout 300 -E '^example_project_builds$')
echo "C++ arm64: all checks passed"
