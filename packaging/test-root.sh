#!/usr/bin/env bash
# The clean Debian root the install test installs the packages into
# (tests/subbroker/test_install_root.py): bookworm, minbase, with only what a
# bookworm image has and the packages' Debian dependencies (python3, adduser,
# libssl3, libzstd1, liblz4-1). Made once with mmdebstrap from Debian's registry and
# cached as build/installroot/bookworm-minbase.tar; the install itself runs with no
# network. Prints the tarball's path.
set -euo pipefail
cd "$(dirname "$0")/.."
TAR=build/installroot/bookworm-minbase.tar
if [ ! -s "$TAR" ]; then
  command -v mmdebstrap >/dev/null || apt-get install -y -qq --no-install-recommends mmdebstrap >/dev/null
  mkdir -p build/installroot
  mmdebstrap --quiet --format=tar --variant=minbase --include=python3,adduser,libssl3,libzstd1,liblz4-1,libstdc++6 \
    bookworm "$TAR.part" http://deb.debian.org/debian >&2
  mv "$TAR.part" "$TAR"
fi
echo "$PWD/$TAR"
