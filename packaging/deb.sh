# Helpers of packaging/build.sh (sourced): the Debian control files, the units, the
# checks. Expects OUT, VERSION and ROOT.

# units_of KIND ROOT: the KIND's systemd units into ROOT/lib/systemd/system
units_of() {
  install -d "$2/lib/systemd/system"
  install -m 0644 packaging/$1/units/*.service "$2/lib/systemd/system/"
}

# the package's units; templates (name@.service: one instance each, enabled by the
# operator) are not enabled or restarted by name: their running instances are
unit_names() { (cd "$1/lib/systemd/system" && ls -- *.service | grep -v '@\.service$' | xargs); }
instance_patterns() { (cd "$1/lib/systemd/system" && ls -- *@.service 2>/dev/null | sed 's/@\.service$/@*.service/' | xargs); }

strip_for() {  # strip_for ARCH FILE: debug symbols out (lintian: unstripped-binary-or-object)
  if [ "$1" = arm64 ]; then aarch64-linux-gnu-strip --strip-unneeded "$2"; else strip --strip-unneeded "$2"; fi
}

# doc_files PACKAGE ROOT KIND: copyright, changelog, README and lintian overrides
doc_files() {
  local doc=$2/usr/share/doc/$1
  install -d "$doc" "$2/usr/share/lintian/overrides"
  install -m 0644 packaging/copyright "$doc/copyright"
  install -m 0644 packaging/$3/README.md "$doc/README.md"
  printf '%s (%s) unstable; urgency=medium\n\n  * Built from the MoDD workbench (CHANGELOG.md).\n\n -- MoDD maintainers <modd@example.org>  %s\n' \
    "$1" "$VERSION" "$(date -uR)" | gzip -9n > "$doc/changelog.gz"
  sed "s/@PACKAGE@/$1/g" packaging/$3/lintian-overrides > "$2/usr/share/lintian/overrides/$1"
  chmod 0644 "$2/usr/share/lintian/overrides/$1" "$doc/changelog.gz"
}

# deb PACKAGE ARCH ROOT KIND DEPENDS: control files, build, lintian, systemd-analyze
deb() {
  local pkg=$1 arch=$2 root=$3 kind=$4 depends=$5 units instances
  units=$(unit_names "$root")
  instances=$(instance_patterns "$root")
  doc_files "$pkg" "$root" "$kind"
  install -d "$root/DEBIAN"
  for s in postinst prerm postrm; do
    sed -e "s/@PACKAGE@/$pkg/g" -e "s/@UNITS@/$units/g" -e "s/@INSTANCES@/$instances/g" \
      packaging/common/$s > "$root/DEBIAN/$s"
    chmod 0755 "$root/DEBIAN/$s"
  done
  (cd "$root" && find etc -type f | sed 's|^|/|' | sort) > "$root/DEBIAN/conffiles"
  local size; size=$(du -sk --exclude=DEBIAN "$root" | cut -f1)
  sed -e "s/@PACKAGE@/$pkg/" -e "s/@VERSION@/$VERSION/" -e "s/@ARCH@/$arch/" \
      -e "s/@SIZE@/$size/" -e "s/@DEPENDS@/$depends/" packaging/$kind/control > "$root/DEBIAN/control"
  find "$root" -path "$root/DEBIAN" -prune -o -type d -exec chmod 0755 {} +
  local file=$OUT/${pkg}_${VERSION}_${arch}.deb
  rm -f "$OUT/${pkg}"_*_"${arch}".deb
  dpkg-deb --root-owner-group -Zxz -z3 --build "$root" "$file" >/dev/null
  echo "$file: $(du -h "$file" | cut -f1), installed $((size / 1024)) MiB"
  lint "$file"
  verify_units "$root"
}

lint() {  # no error (warnings are listed); the overrides say why each is there
  local out; out=$(lintian --no-tag-display-limit "$1" 2>&1 || true)
  printf '%s\n' "$out" | sed 's/^/  lintian: /' | grep -E 'lintian: [EW]:' | sort | uniq -c | head -30 || true
  if printf '%s\n' "$out" | grep -q '^E:'; then echo "lintian: errors in $1" >&2; return 1; fi
}

verify_units() {  # systemd-analyze verify: the package's tree over this system's units
  local u rc=0 out vroot
  vroot=$(mktemp -d)
  mkdir -p "$vroot/usr" "$vroot/lib/systemd"
  cp -a "$1/usr/bin" "$vroot/usr/" && cp -a "$1/lib/systemd/system" "$vroot/lib/systemd/"
  # the units' ExecStartPre helpers (not the Python tree: verify looks at the commands only)
  find "$1/usr/lib/modd" -maxdepth 1 -type f -exec install -D -t "$vroot/usr/lib/modd" {} +
  cp -an /lib/systemd/system/. "$vroot/lib/systemd/system/"  # the targets they order against
  for u in "$1"/lib/systemd/system/*.service; do
    out=$(SYSTEMD_LOG_LEVEL=warning systemd-analyze verify --root="$vroot" \
          "/lib/systemd/system/$(basename "$u")" 2>&1) || rc=1
    [ -z "$out" ] || { printf '  systemd-analyze: %s\n' "$out"; rc=1; }
  done
  rm -rf "$vroot"
  [ $rc -eq 0 ] && echo "  systemd-analyze verify: $(cd "$1/lib/systemd/system" && ls -- *.service | xargs): clean"
  return $rc
}

# smoke_drone ROOT: the amd64 tree's commands run with the system's python3 and nothing
# else (python -I: no site-packages, no user paths): proves the drone tree is complete.
smoke_drone() {
  local lib=$1/usr/lib/modd/python c
  for c in "modd.sensors" "modd.mavlink.cli" "modd.pairing.cli"; do
    env -i PATH=/usr/bin:/bin PYTHONDONTWRITEBYTECODE=1 PYTHONPATH="$lib" /usr/bin/python3 -c \
      "import sys; from ${c} import main; sys.argv=['x','--help']; main()" >/dev/null \
      || { echo "drone tree: $c does not start" >&2; return 1; }
  done
  env -i PATH=/usr/bin:/bin PYTHONDONTWRITEBYTECODE=1 PYTHONPATH="$lib" /usr/bin/python3 -c \
    "from modd_model import load_or_report; from modd_model.ingress import ingress_of; import pymavlink.mavutil, serial" \
    || { echo "drone tree: the model loader or pymavlink is missing" >&2; return 1; }
  # a unit beyond the paper's: the model check loads UDUNITS-2 (cf-units), as modd-sensors does
  env -i PATH=/usr/bin:/bin PYTHONDONTWRITEBYTECODE=1 PYTHONPATH="$lib" /usr/bin/python3 -c \
    "from modd_model.units import unit_problem; assert unit_problem('deg') is None and unit_problem('furlong/fortnight') is None and unit_problem('nonsense')" \
    || { echo "drone tree: the model's unit check (cf-units) does not run" >&2; return 1; }
  echo "  drone tree: modd-sensors, modd-mavlink, modd-pair start from the package's files alone"
}
