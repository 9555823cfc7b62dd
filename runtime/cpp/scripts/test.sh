#!/usr/bin/env bash
# The C++ runtime's checks, run by `make test` (scripts/check.sh):
#   1. ctest on build/cpp (the regular build of `make build`): units + example project;
#   2. the units again under AddressSanitizer + UndefinedBehaviorSanitizer (build/cpp-asan);
#   3. the libFuzzer targets built with clang (build/cpp-fuzz): the link, ingress, datagram
#      and backfill decoders and the archive recovery's scan, each run for FUZZ_SECONDS.
# Longer fuzzing: FUZZ_SECONDS=600 runtime/cpp/scripts/test.sh  (or run a target by hand:
#   build/cpp-fuzz/fuzz_link_decoder -max_total_time=600 build/cpp-fuzz/corpus-link)
# Exits non-zero on the first failure.
set -euo pipefail
cd "$(dirname "$0")/../../.."
ROOT=$PWD
SRC=runtime/cpp
JOBS=${JOBS:-2}
FUZZ_SECONDS=${FUZZ_SECONDS:-10}
step() { printf '\n== C++: %s\n' "$*"; }

step "build + ctest (build/cpp)"
cmake -S $SRC -B build/cpp -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMODD_BIN_DIR="$ROOT/build/bin" >/dev/null
cmake --build build/cpp -j"$JOBS"
(cd build/cpp && ctest --output-on-failure -j"$JOBS" --timeout 120)

step "units under ASan + UBSan (build/cpp-asan)"
cmake -S $SRC -B build/cpp-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DMODD_SANITIZE=ON \
      -DMODD_BIN_DIR="$ROOT/build/cpp-asan/bin" >/dev/null
cmake --build build/cpp-asan -j"$JOBS" --target modd_unit_tests
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  build/cpp-asan/modd_unit_tests --gtest_brief=1

step "libFuzzer targets, ${FUZZ_SECONDS}s each (build/cpp-fuzz)"
CXX=clang++ cmake -S $SRC -B build/cpp-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMODD_FUZZ=ON \
      -DMODD_TESTS=OFF -DMODD_BIN_DIR="$ROOT/build/cpp-fuzz/bin" >/dev/null
TARGETS=(link_decoder ingress_decoder datagram backfill chunk_scan)  # every decoder of the runtime
cmake --build build/cpp-fuzz -j"$JOBS" --target "${TARGETS[@]/#/fuzz_}"
for t in "${TARGETS[@]}"; do
  corpus=build/cpp-fuzz/corpus-$t
  mkdir -p "$corpus"
  if [ "$t" = link_decoder ]; then
    # Seed with the shared vectors' bytes.
    for v in contracts/vectors/link/*.json; do
      python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); h=d.get("hex"); h and sys.stdout.buffer.write(bytes.fromhex(h))' \
        "$v" > "$corpus/$(basename "$v" .json)"
    done
  fi
  if [ "$t" = backfill ]; then
    # Seed with the backfill vectors, each behind a kind byte: float32 MIN, ON_CHANGE, THRESHOLD.
    python3 -c 'import json,sys; d=json.load(open(sys.argv[1]))
for v in d["vectors"] + d["invalid"]:
    n, w = v["name"], bytes.fromhex(v["hex"])
    for k in (0x00, 0x30, 0x34): open(f"{sys.argv[2]}/{n}-{k:02x}", "wb").write(bytes([k]) + w)' \
      contracts/vectors/link/backfill.json "$corpus"
  fi
  if [ "$t" = chunk_scan ] && [ -x .venv/bin/python ]; then
    # Seed with small crashed files (the recovery tests' independent writer).
    .venv/bin/python -c 'import sys; sys.path.insert(0, "tests"); from support.mcap_oracle import crashed_mcap
for n, k in ((12, 4), (90, 30), (7, 1)): open(f"{sys.argv[1]}/seed-{n}-{k}", "wb").write(crashed_mcap(n, per_chunk=k))' "$corpus"
  fi
  build/cpp-fuzz/fuzz_$t -max_total_time="$FUZZ_SECONDS" -print_final_stats=0 -close_fd_mask=3 "$corpus" \
    > build/cpp-fuzz/$t.log 2>&1 || { tail -50 build/cpp-fuzz/$t.log; echo "fuzz_$t FAILED"; exit 1; }
  echo "fuzz_$t: $(grep -c . "$corpus"/* 2>/dev/null | wc -l) corpus entries, no crash"
done
echo "C++ runtime: all checks passed"
