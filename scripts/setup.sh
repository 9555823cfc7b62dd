#!/usr/bin/env bash
# Installs everything the project needs on a fresh Debian machine, idempotently:
# Debian packages (apt-get), uv (from PyPI), the Python workspace (.venv), npm packages.
# Each step is skipped when what it installs is already there.
#   scripts/setup.sh arm64    only the aarch64 cross toolchain, the arm64 libraries
#                             (Debian multiarch) and qemu-user: make test's arm64 lane
#                             (runtime/cpp/scripts/test-arm64.sh) and make package.
set -euo pipefail
cd "$(dirname "$0")/.."

# What a first run needs from the network, said when a step that downloads fails
# (an offline machine otherwise sees only a resolver error from uv or npm).
offline_hint() {
  echo "setup: $1 failed. The first \`make run\` or \`make test\` on a machine downloads" >&2
  echo "setup: what it needs: Debian packages (apt), Python packages (PyPI, through uv) and" >&2
  echo "setup: npm packages; later runs need no network. Check that this machine reaches them" >&2
  echo "setup: (a proxy: set http_proxy/https_proxy), then run the command again." >&2
  exit 1
}

# apt_install PKG...: installs those not installed yet (one apt-get run, quiet).
apt_install() {
  local missing=() p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -gt 0 ] || return 0
  echo "setup: installing Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq || offline_hint "apt-get update"
  # tshark asks whether non-root users may capture; the default (no) is what we want.
  echo "wireshark-common wireshark-common/install-setuid boolean false" | $SUDO debconf-set-selections
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null ||
    offline_hint "installing Debian packages (${missing[*]})"
}

if [ "${1:-}" = arm64 ]; then
  if ! dpkg --print-foreign-architectures | grep -qx arm64; then
    echo "setup: adding the arm64 architecture (Debian multiarch)"
    SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO dpkg --add-architecture arm64
  fi
  apt_install g++-aarch64-linux-gnu libssl-dev:arm64 libzstd-dev:arm64 liblz4-dev:arm64 \
              libgtest-dev:arm64 libstdc++6:arm64 nlohmann-json3-dev qemu-user-static
  exit 0
fi

APT_PACKAGES=(cmake ninja-build g++ make libgtest-dev libssl-dev libzstd-dev liblz4-dev
              nlohmann-json3-dev clang clang-format libclang-rt-14-dev tshark chromium postgresql mosquitto
              faketime)  # faketime: the PubBroker's clock-step test (tests/runtime/test_pubbroker_clock_step.py)

apt_install "${APT_PACKAGES[@]}"

if ! command -v uv >/dev/null 2>&1; then
  echo "setup: installing uv from PyPI"
  python3 -m pip install --quiet --disable-pip-version-check uv || offline_hint "installing uv from PyPI"
fi

# --compile-bytecode: the dependencies' bytecode written once here, as pip
# does, not compiled again by every process (where PYTHONDONTWRITEBYTECODE is
# set, Python never writes it: the backend's imports then cost 3.5 s of CPU
# per start instead of 1.3-2 s, `modd plan` 0.6 s instead of 0.15-0.23 s).
# uv sync skips what is compiled already.
uv sync --quiet --all-packages --compile-bytecode || offline_hint "uv sync (Python packages)"
# the same for the workspace's own sources (editable: not in site-packages);
# compileall skips the files whose bytecode is current
.venv/bin/python -m compileall -q -j 0 metamodel/src runtime/python/src backend/src \
  generators/src launcher/src >/dev/null

if [ -f frontend/package.json ]; then
  if [ ! -d frontend/node_modules ] || [ frontend/package-lock.json -nt frontend/node_modules/.package-lock.json ]; then
    echo "setup: installing npm packages"
    (cd frontend && npm ci --no-audit --no-fund --loglevel=error) || offline_hint "npm ci (frontend packages)"
  fi
fi
