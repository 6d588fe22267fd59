#!/usr/bin/env bash
# Times viosfm's README commands on a clean Debian 12 root (no compiler, no
# libraries, no ccache): debootstrap makes the root once (kept as a tarball
# beside it), every check starts from a fresh copy of it, and runs inside it
# with chroot:
#   apt-get install git make -> git clone -> make demo | make test | make package
# Needs root, debootstrap and the network to Debian's archive (the host's apt
# sources are copied in). Not part of `make test`.
#
#   scripts/check-fresh-debian.sh WORK_DIR demo|test|package [REPO [BRANCH]]
#
# REPO (default: this checkout) is cloned at BRANCH (default: its current
# branch). With `test`, ../shared/data is bound read-only beside the clone,
# as CI has it. Timings go to WORK_DIR/<check>.times and the whole log to
# WORK_DIR/<check>.log; `package` also installs the .deb into a second fresh
# root (scripts/check-package.sh).
set -euo pipefail
work=$(realpath -m "$1")
check=$2
repo=$(realpath "${3:-$(dirname "$0")/..}")
branch=${4:-$(git -C "$repo" rev-parse --abbrev-ref HEAD)}
case "$check" in demo | test | package) ;; *) echo "unknown check '$check'" >&2; exit 2 ;; esac
[[ $(id -u) -eq 0 ]] || { echo "check-fresh-debian: needs root (chroot)" >&2; exit 1; }
data_dir=$(realpath -m "$repo/../shared/data")
mkdir -p "$work"
pristine="$work/bookworm-minbase.tar"
root="$work/root-$check"

if [[ ! -f "$pristine" ]]; then
  echo "== debootstrap: a minimal Debian 12 root -> $pristine"
  rm -rf "$work/bootstrap"
  debootstrap --variant=minbase bookworm "$work/bootstrap" http://deb.debian.org/debian \
    >"$work/debootstrap.log" 2>&1
  tar -C "$work/bootstrap" -cf "$pristine" .
  rm -rf "$work/bootstrap"
fi

mounts=()
cleanup() {
  for ((i = ${#mounts[@]} - 1; i >= 0; --i)); do umount -l "${mounts[i]}" 2>/dev/null || true; done
}
trap cleanup EXIT
bind() {  # bind SOURCE TARGET [ro]
  mkdir -p "$2"
  mount --bind "$1" "$2"
  mounts+=("$2")
  if [[ "${3:-}" == ro ]]; then mount -o remount,bind,ro "$2"; fi
}

# A fresh root with the host's apt sources, proc/sys/dev and the repository to clone.
fresh_root() {
  local dir=$1
  rm -rf "$dir"
  mkdir -p "$dir"
  tar -C "$dir" -xf "$pristine"
  cp /etc/resolv.conf "$dir/etc/resolv.conf"
  if [[ -f /etc/apt/sources.list.d/debian.sources ]]; then
    rm -f "$dir/etc/apt/sources.list"
    cp /etc/apt/sources.list.d/debian.sources "$dir/etc/apt/sources.list.d/"
  fi
  for conf in /etc/apt/apt.conf.d/99*; do [[ -f "$conf" ]] && cp "$conf" "$dir/etc/apt/apt.conf.d/"; done
  mount -t proc proc "$dir/proc"; mounts+=("$dir/proc")
  bind /sys "$dir/sys" ro
  bind /dev "$dir/dev"
  mount -t devpts devpts "$dir/dev/pts" 2>/dev/null && mounts+=("$dir/dev/pts") || true
  mkdir -p "$dir/tmp" && chmod 1777 "$dir/tmp"
}

in_root() {  # in_root DIR COMMAND...
  local dir=$1
  shift
  chroot "$dir" /usr/bin/env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    LANG=C.UTF-8 TERM=dumb DEBIAN_FRONTEND=noninteractive "$@"
}

fresh_root "$root"
git clone -q --bare --branch "$branch" --single-branch "$repo" "$root/srv/viosfm.git"
if [[ "$check" == test && -d "$data_dir" ]]; then bind "$data_dir" "$root/root/shared/data" ro; fi

case "$check" in
  demo) target=demo ;;
  test) target=test ;;
  package) target=package ;;
esac
times="$work/$check.times"
log="$work/$check.log"
echo "== $check in $root (log: $log)"
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
make '"$target"'
t3=$(date +%s.%N)
awk -v a="$t0" -v b="$t1" -v c="$t2" -v d="$t3" "BEGIN {
  printf \"apt-get install git make: %.0f s\n\", b - a;
  printf \"git clone: %.0f s\n\", c - b;
  printf \"make '"$target"': %.0f s\n\", d - c;
  printf \"total, from apt-get to the end of make '"$target"': %.0f s (%d min %02d s)\n\", d - a, int((d - a) / 60), int(d - a) % 60 }"
' 2>&1 | tee "$log" || { echo "check-fresh-debian: make $target failed (log: $log)" >&2; exit 1; }
# The last 4 lines of the log are the timings.
tail -n 4 "$log" >"$times"

if [[ "$check" == package ]]; then
  deb=$(ls "$root"/root/viosfm/build/viosfm_*.deb | head -n 1)
  cp "$deb" "$work/"
  cleanup
  mounts=()
  "$(dirname "$0")/check-package.sh" "$work/$(basename "$deb")" "$work/root-install"
fi
