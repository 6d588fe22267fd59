#!/usr/bin/env bash
# Times viosfm's README commands on a clean Debian 12 root (no compiler, no
# libraries, no ccache): debootstrap makes the root once (kept as a tarball in
# WORK_DIR), every check starts from a fresh copy of it and runs inside it
# with chroot:
#   apt-get install git make -> git clone -> make demo | make test | make package
# Needs root, debootstrap and the network to Debian's archive (the host's apt
# sources are copied in). Not part of `make test`.
#
#   scripts/check-fresh-debian.sh WORK_DIR demo|test|package [REPO [BRANCH]]
#
# REPO (default: this checkout) is cloned at BRANCH (default: its current
# branch). With `test`, REPO/../shared/data is bound read-only beside the
# clone, as CI has it. The timings go to WORK_DIR/CHECK.times, the whole log to
# WORK_DIR/CHECK.log; `package` then installs the .deb into a second fresh
# root (scripts/check-package.sh).
set -euo pipefail
here=$(dirname "$(realpath "$0")")
source "$here/lib/fresh-debian-root.sh"
work=$(realpath -m "$1")
check=$2
repo=$(realpath "${3:-$here/..}")
branch=${4:-$(git -C "$repo" rev-parse --abbrev-ref HEAD)}
case "$check" in demo | test | package) ;; *) echo "unknown check '$check'" >&2; exit 2 ;; esac
[[ $(id -u) -eq 0 ]] || { echo "check-fresh-debian: needs root (chroot)" >&2; exit 1; }
data_dir=$(realpath -m "$repo/../shared/data")
mkdir -p "$work"
trap release_roots EXIT
tar=$(pristine_root_tar "$work")
root="$work/root-$check"
fresh_root "$tar" "$root"
git clone -q --bare --branch "$branch" --single-branch "$repo" "$root/srv/viosfm.git"
if [[ "$check" == test && -d "$data_dir" ]]; then
  bind_into_root "$data_dir" "$root/root/shared/data" ro
fi

times="$work/$check.times"
log="$work/$check.log"
echo "== $check in $root (log: $log); load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
in_root "$root" /bin/bash -c '
set -euo pipefail
t0=$(date +%s.%N)
apt-get update -qq
apt-get install -y -qq --no-install-recommends git make ca-certificates >/dev/null
t1=$(date +%s.%N)
cd /root
git clone -q /srv/viosfm.git viosfm
cd viosfm
t2=$(date +%s.%N)
make '"$check"'
t3=$(date +%s.%N)
awk -v a="$t0" -v b="$t1" -v c="$t2" -v d="$t3" "BEGIN {
  printf \"apt-get install git make: %.0f s\n\", b - a;
  printf \"git clone: %.0f s\n\", c - b;
  printf \"make '"$check"': %.0f s\n\", d - c;
  printf \"from apt-get to the end of make '"$check"': %.0f s (%d min %02d s)\n\", d - a, int((d - a) / 60), int(d - a) % 60 }"
' 2>&1 | tee "$log" || { echo "check-fresh-debian: make $check failed (log: $log)" >&2; exit 1; }
{
  tail -n 4 "$log"
  echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
} >"$times"
release_roots

if [[ "$check" == package ]]; then
  deb=$(ls "$root"/root/viosfm/build/viosfm_*.deb | head -n 1)
  "$here/check-package.sh" "$deb" "$work"
fi
