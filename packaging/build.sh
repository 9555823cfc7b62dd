#!/usr/bin/env bash
# `make package`: Debian packages of the drone and the base station, for amd64 and
# arm64, built on this amd64 machine (packaging/README.md):
#   build/package/modd-drone_<version>_<arch>.deb   modd-pubbroker, modd-sensors,
#       modd-mavlink and their Python runtime (wheels for <arch>, vendored)
#   build/package/modd-base_<version>_<arch>.deb    modd-subbroker, modd-station, modd-radio,
#       modd-backend and the built workbench, with their Python runtime
# Nothing is fetched at install time. Checks every package with lintian and every
# unit with systemd-analyze verify; fails on an error.
#   ARCHS="amd64" packaging/build.sh     one architecture
#   KINDS="base" packaging/build.sh      one package (drone, base)
#   VERSION=0.1.1 packaging/build.sh     another version (default: the runtime's + UTC time)
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
OUT=$ROOT/build/package
ARCHS=${ARCHS:-"amd64 arm64"}
KINDS=${KINDS:-"drone base"}
VERSION=${VERSION:-$(sed -n 's/^version = "\(.*\)"/\1/p' runtime/python/pyproject.toml)+$(date -u +%Y%m%d%H%M)}
PY=3.11
export PATH="$ROOT/.venv/bin:$PATH"
step() { printf '\n== package: %s\n' "$*"; }
apt_have() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
for p in lintian systemd; do apt_have $p || { SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo;
  $SUDO apt-get install -y -qq --no-install-recommends $p >/dev/null; }; done
mkdir -p "$OUT"

# -- what every architecture shares: our wheels, the frontend, pinned requirements --
step "workspace wheels and pinned requirements"
rm -rf "$OUT/wheels" && mkdir -p "$OUT/wheels"
for d in metamodel runtime/python backend; do
  uv build --quiet --wheel --out-dir "$OUT/wheels" "$d"
done
uv export --quiet --frozen --no-hashes --no-dev --all-packages --no-emit-workspace \
  | grep -E '^[a-z0-9]' > "$OUT/all-requirements.txt"
pins() {  # pins NAME...: NAME==VERSION lines of uv.lock (python < 3.12 markers)
  local n
  for n in "$@"; do
    grep -iE "^${n}==" "$OUT/all-requirements.txt" | grep -v "python_full_version >= '3.12'" \
      | sed 's/ ;.*//' | head -1 | grep . || { echo "package: $n is not in uv.lock" >&2; return 1; }
  done
}
grep -vE '^\s*(#|$)' packaging/drone/python.txt | xargs -n1 | while read -r n; do pins "$n"; done \
  > "$OUT/drone-requirements.txt"
# the base station: everything the backend and the SubBroker need (Linux, CPython)
grep -vE "sys_platform == '(win32|emscripten)'|python_full_version >= '3.12'" "$OUT/all-requirements.txt" \
  | sed 's/ ;.*//' > "$OUT/base-requirements.txt"
# pure-Python distributions PyPI has as sources only (packaging/sdist-only.txt): built
# into wheels here (py3-none-any, so one serves every architecture) and installed with ours
grep -vE '^\s*(#|$)' packaging/sdist-only.txt | while read -r n; do
  /usr/bin/python3 -m pip wheel --quiet --disable-pip-version-check --no-deps --no-cache-dir \
    --wheel-dir "$OUT/wheels" "$(pins "$n")"
  ls "$OUT"/wheels/"${n//-/_}"-*-py3-none-any.whl >/dev/null \
    || { echo "package: $n did not build as a pure-Python wheel" >&2; exit 1; }
  sed -i "/^${n}==/Id" "$OUT/base-requirements.txt" "$OUT/drone-requirements.txt"
done
if [ ! -f frontend/dist/index.html ] || [ -n "$(find frontend/src -newer frontend/dist/index.html -print -quit)" ]; then
  (cd frontend && npm run --silent build >/dev/null)
fi

# cross_wheels ARCH: sets extra (pip's arguments) to the wheels built here for ARCH.
# packaging/README.md: PyPI has no Linux aarch64 wheel of cf-units (drone and base need it)
cross_wheels() {
  extra=()
  if [ "$1" = arm64 ]; then
    packaging/cf-units-arm64.sh "$(pins cf-units | cut -d= -f3)" "$(pins numpy | cut -d= -f3)" "$ROOT/build/cross-wheels"
    extra=(--find-links "$ROOT/build/cross-wheels" --platform linux_aarch64)
  fi
}

platform() { [ "$1" = arm64 ] && echo manylinux2014_aarch64 || echo manylinux2014_x86_64; }

# python_tree ROOT ARCH REQS: the wheels for ARCH installed into ROOT/usr/lib/modd/python
python_tree() {
  local dest=$1/usr/lib/modd/python arch=$2 reqs=$3
  local plat; plat=$(platform "$arch")
  mkdir -p "$OUT/pip-cache"
  pip_args=(--quiet --disable-pip-version-check --root-user-action=ignore --no-deps --only-binary=:all: --target "$dest"
            --python-version $PY --implementation cp --abi cp311 --abi abi3 --abi none
            --platform "$plat" --platform "${plat/manylinux2014/manylinux_2_28}"
            --platform "${plat/manylinux2014/manylinux_2_17}" --platform any
            --cache-dir "$OUT/pip-cache")
  /usr/bin/python3 -m pip install "${pip_args[@]}" -r "$reqs" "${@:4}"
  rm -rf "$dest"/bin "$dest"/*.dist-info/RECORD
  find "$dest" -name __pycache__ -type d -prune -exec rm -rf {} +
}

# wrapper ROOT NAME MODULE:FUNC: /usr/bin/NAME running the private tree's entry point
wrapper() {
  local mod=${3%%:*} fn=${3##*:}
  install -d "$1/usr/bin"
  cat > "$1/usr/bin/$2" <<PYEOF
#!/usr/bin/python3
# $2: MoDD's Python runtime, private to this package (/usr/lib/modd/python).
import os
import sys

LIB = "/usr/lib/modd/python"
sys.path.insert(0, LIB)
# children (the model check, workers) find it too
os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (LIB, os.environ.get("PYTHONPATH")) if p)
from $mod import $fn  # noqa: E402

sys.exit($fn())
PYEOF
  chmod 0755 "$1/usr/bin/$2"
}

. packaging/deb.sh

drone() {
  local arch=$1 root=$OUT/root/modd-drone-$1 bin
  step "modd-drone ($arch)"
  if [ "$arch" = arm64 ]; then
    JOBS=1 nice -n 10 runtime/cpp/scripts/test-arm64.sh --build-only
    bin=build/cpp-arm64/bin/modd-pubbroker
  else
    cmake --build build/cpp --target modd-pubbroker >/dev/null
    bin=build/bin/modd-pubbroker
  fi
  rm -rf "$root" && mkdir -p "$root"
  install -D -m 0755 "$bin" "$root/usr/bin/modd-pubbroker"
  strip_for "$arch" "$root/usr/bin/modd-pubbroker"
  local extra=(); cross_wheels "$arch"
  python_tree "$root" "$arch" "$OUT/drone-requirements.txt" \
    "$OUT"/wheels/modd_runtime-*.whl "$OUT"/wheels/modd_metamodel-*.whl "${extra[@]}"
  wrapper "$root" modd-sensors modd.sensors:main
  wrapper "$root" modd-mavlink modd.mavlink.cli:main
  wrapper "$root" modd-pair modd.pairing.cli:main
  install -D -m 0755 packaging/drone/lib/onboard-init "$root/usr/lib/modd/onboard-init"
  install -D -m 0644 packaging/drone/drone.env "$root/etc/modd/drone.env"
  units_of drone "$root"
  [ "$arch" != amd64 ] || smoke_drone "$root"
  deb modd-drone "$arch" "$root" drone \
    "libc6, libstdc++6, libssl3, libzstd1, liblz4-1, libexpat1, python3 (>= 3.11), python3 (<< 3.12), adduser"
}

base() {
  local arch=$1 root=$OUT/root/modd-base-$1
  step "modd-base ($arch)"
  rm -rf "$root" && mkdir -p "$root"
  local extra=(); cross_wheels "$arch"
  python_tree "$root" "$arch" "$OUT/base-requirements.txt" "$OUT"/wheels/*.whl "${extra[@]}"
  wrapper "$root" modd-subbroker modd.subbroker.cli:main
  wrapper "$root" modd-station modd.station:main
  wrapper "$root" modd-radio modd.radio.cli:main
  wrapper "$root" modd-backend modd_backend.cli:main
  wrapper "$root" modd modd_model.cli:main
  install -d "$root/usr/share/modd" && cp -r frontend/dist "$root/usr/share/modd/frontend"
  install -D -m 0644 packaging/base/base.env "$root/etc/modd/base.env"
  units_of base "$root"
  deb modd-base "$arch" "$root" base "libc6, libstdc++6, libexpat1, python3 (>= 3.11), python3 (<< 3.12), adduser"
}

# architecture by architecture: the amd64 packages (all the install tests need) first
for arch in $ARCHS; do
  for kind in $KINDS; do
    "$kind" "$arch"
  done
done
step "done"
ls -l "$OUT"/*.deb
