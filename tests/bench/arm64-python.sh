#!/usr/bin/env bash
# Debian bookworm's arm64 python3.11 and the libraries it loads, unpacked (not
# installed) into build/arm64-python/sys for bench_packages.py: the packages' arm64
# Python trees run under qemu-user (`qemu-aarch64-static -L build/arm64-python/sys`).
# Fetched once with `apt-get download` (the arm64 architecture is added by
# `scripts/setup.sh arm64`); cached. Prints the directory.
set -euo pipefail
cd "$(dirname "$0")/../.."
SYS=$PWD/build/arm64-python/sys
if [ ! -x "$SYS/usr/bin/python3.11" ]; then
  scripts/setup.sh arm64 >&2
  debs=$(mktemp -d) && trap 'rm -rf "$debs"' EXIT
  chmod 0777 "$debs"  # apt-get download fetches as _apt
  (cd "$debs" && apt-get download -qq python3.11-minimal:arm64 libpython3.11-minimal:arm64 \
    libpython3.11-stdlib:arm64 libc6:arm64 libgcc-s1:arm64 libstdc++6:arm64 libbz2-1.0:arm64 \
    libcrypt1:arm64 libexpat1:arm64 libffi8:arm64 liblzma5:arm64 libncursesw6:arm64 \
    libnsl2:arm64 libreadline8:arm64 libsqlite3-0:arm64 libssl3:arm64 libtinfo6:arm64 \
    libtirpc3:arm64 libuuid1:arm64 zlib1g:arm64 libzstd1:arm64 liblz4-1:arm64 libdb5.3:arm64 \
    libgssapi-krb5-2:arm64 libkrb5-3:arm64 libk5crypto3:arm64 libkrb5support0:arm64 \
    libcom-err2:arm64 libkeyutils1:arm64 >/dev/null)
  rm -rf "$SYS.part" && mkdir -p "$SYS.part"
  for d in "$debs"/*.deb; do dpkg-deb -x "$d" "$SYS.part"; done
  rm -rf "$SYS" && mv "$SYS.part" "$SYS"
fi
echo "$SYS"
