#!/usr/bin/env bash
# Installs viosfm's Debian package (`make package`) into a clean Debian 12
# root, as a user would (`apt-get install ./viosfm_*.deb`, which brings its
# dependencies), and checks it there: `viosfm --help` runs, the binary
# needs no library the package does not depend on, and a short simulated
# sequence is reconstructed and reported, with the 3D view's three.js found.
# Needs root and debootstrap (scripts/lib/fresh-debian-root.sh). Not part of
# `make test`.
#
#   scripts/check-package.sh PATH/viosfm_VERSION_ARCH.deb WORK_DIR
set -euo pipefail
here=$(dirname "$(realpath "$0")")
source "$here/lib/fresh-debian-root.sh"
deb=$(realpath "$1")
work=$(realpath -m "$2")
[[ $(id -u) -eq 0 ]] || { echo "check-package: needs root (chroot)" >&2; exit 1; }
mkdir -p "$work"
trap release_roots EXIT
tar=$(pristine_root_tar "$work")
root="$work/root-install"
fresh_root "$tar" "$root"
cp "$deb" "$root/tmp/"
echo "== check-package: $(basename "$deb") into a clean Debian 12 root ($root)"
in_root "$root" /bin/bash -c '
set -euo pipefail
fail() { echo "check-package: FAILED: $*" >&2; exit 1; }
t0=$(date +%s)
apt-get update -qq
apt-get install -y -qq --no-install-recommends /tmp/'"$(basename "$deb")"' >/dev/null
echo "-- apt-get update and install of the package and its dependencies: $(($(date +%s) - t0)) s"
echo "-- dpkg -s viosfm"
dpkg -s viosfm | grep -E "^(Package|Version|Architecture|Installed-Size|Depends):"
dpkg -s viosfm | grep -q "^Depends:.*libjs-three" || fail "the package does not depend on libjs-three"
[[ -x /usr/bin/viosfm ]] || fail "/usr/bin/viosfm is not installed"
echo "-- viosfm --help"
viosfm --help > /tmp/help.txt || fail "viosfm --help exited $?"
head -n 3 /tmp/help.txt
grep -q "run" /tmp/help.txt || fail "viosfm --help lists no run command"
missing=$(ldd /usr/bin/viosfm | grep "not found" || true)
[[ -z "$missing" ]] || fail "libraries not found: $missing"
echo "-- a short run: simulate 8 s, run, report"
cd /tmp
viosfm simulate --scenario room --duration 8 --rate 10 --seed 0 --out seq >/dev/null 2>&1 ||
  fail "viosfm simulate exited $?"
viosfm run seq --out run --n1 5 --n2 2 --max-features 500 --no-progress >/dev/null 2>&1 ||
  fail "viosfm run exited $?"
viosfm report run >/dev/null
grep -q "id=\"viewer3d-canvas\"" run/report.html || fail "the report has no 3D view (three.js not found)"
echo "registered frames: $(grep -o "\"registered\": [0-9]*" run/summary.json | head -n 1)"
echo "check-package: OK ($(dpkg -s viosfm | grep ^Version:), viosfm --help, a run and its report)"
'
