#!/usr/bin/env bash
# cf-units for linux aarch64, built here (packaging/README.md): PyPI has no Linux aarch64
# wheel of it. Its own x86_64 wheel ships the Cython-generated C of its extension
# (cf_units/_udunits2.c, limited API abi3) and its pure-Python files and UDUNITS-2
# database; this script compiles that C with Debian's aarch64-linux-gnu-gcc against
# Debian's arm64 libudunits2-dev and libpython3.11-dev headers (downloaded with
# `apt-get download`, unpacked, not installed) and numpy's aarch64 headers (its
# wheel), bundles Debian's arm64 libudunits2.so.0 in cf_units.libs/ (RPATH
# $ORIGIN/../cf_units.libs, as the x86_64 wheel does), and packs
# cf_units-<version>-cp311-abi3-linux_aarch64.whl into OUT_DIR.
# Cached: does nothing when that wheel is already there.
#   packaging/cf-units-arm64.sh CF_UNITS_VERSION NUMPY_VERSION OUT_DIR
set -euo pipefail
CF=$1 NP=$2
mkdir -p "$3" && OUT=$(cd "$3" && pwd)
WHEEL=$OUT/cf_units-$CF-cp311-abi3-linux_aarch64.whl
[ -f "$WHEEL" ] && { echo "cf-units $CF aarch64: cached ($WHEEL)"; exit 0; }
WORK=$(mktemp -d) && trap 'rm -rf "$WORK"' EXIT
chmod 0755 "$WORK"
mkdir -p "$WORK/debs" "$WORK/sysroot" "$WORK/dl" "$WORK/np" "$WORK/whl"
chmod 0777 "$WORK/debs"  # apt-get download fetches as _apt
(cd "$WORK/debs" && apt-get download -qq libudunits2-0:arm64 libudunits2-dev:arm64 \
  libpython3.11-dev:arm64 >/dev/null)
for d in "$WORK"/debs/*.deb; do dpkg-deb -x "$d" "$WORK/sysroot"; done
pip_dl() { /usr/bin/python3 -m pip download --quiet --disable-pip-version-check --no-deps \
  --only-binary=:all: --python-version 3.11 --implementation cp --dest "$WORK/dl" "$@"; }
pip_dl --platform manylinux2014_x86_64 --platform manylinux_2_17_x86_64 "cf-units==$CF"
pip_dl --platform manylinux2014_aarch64 --platform manylinux_2_17_aarch64 \
  --platform manylinux_2_28_aarch64 "numpy==$NP"
(cd "$WORK/whl" && python3 -m zipfile -e "$WORK"/dl/cf_units-*.whl .)
(cd "$WORK/np" && python3 -m zipfile -e "$WORK"/dl/numpy-*aarch64*.whl .)
rm -rf "$WORK"/whl/cf_units/_udunits2*.so "$WORK"/whl/cf_units.libs
mkdir -p "$WORK/whl/cf_units.libs"
S=$WORK/sysroot
lib=$(readlink -f "$S"/usr/lib/aarch64-linux-gnu/libudunits2.so.0)
cp "$lib" "$WORK/whl/cf_units.libs/libudunits2.so.0"
aarch64-linux-gnu-gcc -shared -fPIC -O2 -g0 -DNDEBUG -DPy_LIMITED_API=0x030B0000 \
  -DNPY_NO_DEPRECATED_API=NPY_1_7_API_VERSION \
  -I"$S/usr/include/python3.11" -I"$S/usr/include/aarch64-linux-gnu/python3.11" \
  -I"$S/usr/include" -I"$WORK/np/numpy/_core/include" \
  "$WORK/whl/cf_units/_udunits2.c" -o "$WORK/whl/cf_units/_udunits2.abi3.so" \
  -L"$WORK/whl/cf_units.libs" -l:libudunits2.so.0 -Wl,-rpath,'$ORIGIN/../cf_units.libs'
aarch64-linux-gnu-strip --strip-unneeded "$WORK/whl/cf_units/_udunits2.abi3.so" \
  "$WORK/whl/cf_units.libs/libudunits2.so.0"
python3 - "$WORK/whl" "$CF" <<'EOF'
"""WHEEL's tag made linux_aarch64, RECORD written anew."""
import base64, hashlib, sys
from pathlib import Path
root, version = Path(sys.argv[1]), sys.argv[2]
info = root / f"cf_units-{version}.dist-info"
wheel = info / "WHEEL"
lines = [l for l in wheel.read_text().splitlines() if not l.startswith("Tag:")]
wheel.write_text("\n".join(lines + ["Tag: cp311-abi3-linux_aarch64", ""]))
rows = []
for f in sorted(p for p in root.rglob("*") if p.is_file() and p.name != "RECORD"):
    digest = base64.urlsafe_b64encode(hashlib.sha256(f.read_bytes()).digest()).rstrip(b"=")
    rows.append(f"{f.relative_to(root)},sha256={digest.decode()},{f.stat().st_size}")
(info / "RECORD").write_text("\n".join(rows + [f"{info.name}/RECORD,,", ""]))
EOF
(cd "$WORK/whl" && python3 -m zipfile -c "$WHEEL.part" ./*)
mv "$WHEEL.part" "$WHEEL"
echo "cf-units $CF aarch64: built $WHEEL"
