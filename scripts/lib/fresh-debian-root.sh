# Sourced by scripts/check-fresh-debian.sh and scripts/check-package.sh: a
# clean Debian 12 root from a debootstrap tarball, entered with chroot.
# Needs root and debootstrap.

root_mounts=()

# Unmounts what fresh_root mounted, newest first.
release_roots() {
  local i
  for ((i = ${#root_mounts[@]} - 1; i >= 0; --i)); do
    umount -l "${root_mounts[i]}" 2>/dev/null || true
  done
  root_mounts=()
}

# The pristine minimal root (debootstrap --variant=minbase bookworm), made once.
pristine_root_tar() {  # pristine_root_tar WORK_DIR -> prints the tarball's path
  local work=$1 tar="$1/bookworm-minbase.tar"
  if [[ ! -f "$tar" ]]; then
    echo "== debootstrap: a minimal Debian 12 root -> $tar" >&2
    rm -rf "$work/bootstrap"
    debootstrap --variant=minbase bookworm "$work/bootstrap" http://deb.debian.org/debian \
      >"$work/debootstrap.log" 2>&1
    tar -C "$work/bootstrap" -cf "$tar" .
    rm -rf "$work/bootstrap"
  fi
  echo "$tar"
}

# A fresh root at DIR from the pristine tarball, with the host's apt sources
# and resolv.conf, proc, sys (read-only) and dev.
fresh_root() {  # fresh_root TAR DIR
  local tar=$1 dir=$2 conf
  rm -rf "$dir"
  mkdir -p "$dir"
  tar -C "$dir" -xf "$tar"
  cp /etc/resolv.conf "$dir/etc/resolv.conf"
  if [[ -f /etc/apt/sources.list.d/debian.sources ]]; then
    rm -f "$dir/etc/apt/sources.list"
    cp /etc/apt/sources.list.d/debian.sources "$dir/etc/apt/sources.list.d/"
  fi
  for conf in /etc/apt/apt.conf.d/99*; do
    if [[ -f "$conf" ]]; then cp "$conf" "$dir/etc/apt/apt.conf.d/"; fi
  done
  mkdir -p "$dir/tmp" && chmod 1777 "$dir/tmp"
  mount -t proc proc "$dir/proc" && root_mounts+=("$dir/proc")
  bind_into_root /sys "$dir/sys" ro
  bind_into_root /dev "$dir/dev"
  if mount -t devpts devpts "$dir/dev/pts" 2>/dev/null; then root_mounts+=("$dir/dev/pts"); fi
}

bind_into_root() {  # bind_into_root SOURCE TARGET [ro]
  mkdir -p "$2"
  mount --bind "$1" "$2"
  root_mounts+=("$2")
  if [[ "${3:-}" == ro ]]; then mount -o remount,bind,ro "$2"; fi
}

# Runs COMMAND... inside DIR with a clean environment, as root.
in_root() {  # in_root DIR COMMAND...
  local dir=$1
  shift
  chroot "$dir" /usr/bin/env -i HOME=/root \
    PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    LANG=C.UTF-8 TERM=dumb DEBIAN_FRONTEND=noninteractive "$@"
}
