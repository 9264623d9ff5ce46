#!/usr/bin/env bash
# Fetches the guest "OS" of the USB-stack test into a cache directory:
# Debian's own kernel (linux-image-amd64 and the versioned image it depends
# on), the closure of the kernel modules the test loads, and udevd (from the
# udev package, unpacked, never installed on this host). Everything comes
# from the Debian mirror through `apt-get download`; nothing is committed.
#
# Usage: fetch-guest-os.sh CACHE_DIR
# Prints the directory holding the result (CACHE_DIR/<kernel version>):
#   vmlinuz, modules/lib/modules/<kver>/..., udevadm, kernel-version
# Exit status 2 means "cannot be had here" (the caller reports skipped).
set -euo pipefail

cache=${1:?usage: fetch-guest-os.sh CACHE_DIR}
# The modules the guest loads; their dependencies are added from modules.dep.
modules=(dummy_hcd libcomposite usb_f_hid usb_f_fs usbhid hid-generic usb_f_acm cdc-acm)
meta_pkg=${TSMH_USB_STACK_KERNEL_PKG:-linux-image-amd64}

die_unavailable() { echo "fetch-guest-os: $*" >&2; exit 2; }

mkdir -p "$cache"
cache=$(cd "$cache" && pwd)
# The module list is part of the cache key: changing it refetches.
key=$(printf '%s\n' "$meta_pkg" "${modules[@]}" | md5sum | cut -c1-12)
if [ -f "$cache/current" ]; then
  dir=$(cat "$cache/current")
  if [ -f "$dir/complete.$key" ] && [ -f "$dir/vmlinuz" ]; then
    echo "$dir"
    exit 0
  fi
fi

work=$(mktemp -d "$cache/.fetch.XXXXXX")
trap 'rm -rf "$work"' EXIT

# apt-get download needs package lists; a fresh machine may have none.
download() {
  (cd "$work" && apt-get download "$@" >/dev/null 2>"$work/apt.err") && return 0
  if [ "$(id -u)" -eq 0 ]; then
    apt-get update -qq >/dev/null 2>&1 || true
  fi
  (cd "$work" && apt-get download "$@" >/dev/null 2>"$work/apt.err") ||
    die_unavailable "apt-get download $* failed: $(tail -n1 "$work/apt.err")"
}

command -v apt-get >/dev/null || die_unavailable "no apt-get: not a Debian-like host"
download "$meta_pkg"
meta_deb=$(ls "$work"/*.deb)
# Depends: linux-image-6.1.0-56-amd64 (= 6.1.192-2)  -> the versioned image
image_pkg=$(dpkg-deb -f "$meta_deb" Depends | tr ',|' '\n\n' | sed -n 's/^ *\(linux-image-[^ ]*\).*/\1/p' | head -n1)
[ -n "$image_pkg" ] || die_unavailable "$meta_pkg: no linux-image dependency in its Depends field"
download "$image_pkg"
image_deb=$(ls "$work"/"${image_pkg}"_*.deb)

root="$work/root"
dpkg-deb -x "$image_deb" "$root"
kver=$(basename "$(ls -d "$root"/lib/modules/*/ | head -n1)")
vmlinuz="$root/boot/vmlinuz-$kver"
[ -f "$vmlinuz" ] || die_unavailable "$image_pkg: no /boot/vmlinuz-$kver inside"

# Newer Debian kernels compress their modules; busybox modprobe wants them plain.
find "$root/lib/modules/$kver" \( -name '*.ko.xz' -o -name '*.ko.zst' -o -name '*.ko.gz' \) -print0 |
  while IFS= read -r -d '' m; do
    case "$m" in
      *.xz) xz -d "$m" ;;
      *.zst) zstd -q -d --rm "$m" ;;
      *.gz) gzip -d "$m" ;;
    esac
  done
# The package ships no modules.dep (its postinst runs depmod); busybox's depmod
# writes one without needing kmod on this host.
busybox depmod -b "$root" "$kver"
moddir="$root/lib/modules/$kver"

# Closure of the wanted modules: each wanted line of modules.dep names the
# module and all its (transitive) dependencies.
closure=()
for m in "${modules[@]}"; do
  line=$(grep -E "(^|/)${m}\.ko:" "$moddir/modules.dep" || true)
  [ -n "$line" ] || die_unavailable "$image_pkg: kernel $kver has no module $m"
  for f in ${line/:/}; do closure+=("$f"); done
done
mapfile -t closure < <(printf '%s\n' "${closure[@]}" | sort -u)

out="$cache/$kver"
rm -rf "$out"
mkdir -p "$out/modules/lib/modules/$kver"
for f in "${closure[@]}"; do
  mkdir -p "$out/modules/lib/modules/$kver/$(dirname "$f")"
  cp "$moddir/$f" "$out/modules/lib/modules/$kver/$f"
done
# A modules.dep restricted to the copied modules, for busybox modprobe.
for f in "${closure[@]}"; do grep -E "^${f}:" "$moddir/modules.dep"; done \
  >"$out/modules/lib/modules/$kver/modules.dep"
cp "$vmlinuz" "$out/vmlinuz"
echo "$kver" >"$out/kernel-version"
echo "$image_pkg $(dpkg-deb -f "$image_deb" Version)" >"$out/kernel-package"

# udevd: real hosts run it; libusb's hotplug and device list and libudev
# monitors only see devices that udevd has announced. Optional: without it
# the guest runs the cases that do not need it.
if (cd "$work" && apt-get download udev >/dev/null 2>&1); then
  udev_deb=$(ls "$work"/udev_*.deb)
  dpkg-deb -x "$udev_deb" "$work/udev"
  for p in bin/udevadm usr/bin/udevadm; do
    if [ -f "$work/udev/$p" ]; then cp "$work/udev/$p" "$out/udevadm"; break; fi
  done
  echo "udev $(dpkg-deb -f "$udev_deb" Version)" >>"$out/kernel-package"
fi

touch "$out/complete.$key"
echo "$out" >"$cache/current"
echo "$out"
