#!/usr/bin/env bash
# Builds the guest's initramfs: busybox (static), the kernel modules and udevd
# fetched by fetch-guest-os.sh, the guest scripts (guest/), and our programs
# with the shared libraries they need (found with ldd, copied at their paths).
#
# Usage: mkinitramfs.sh GUEST_OS_DIR OUTPUT.cpio.gz PROGRAM...
set -euo pipefail

guest_os=${1:?usage: mkinitramfs.sh GUEST_OS_DIR OUTPUT PROGRAM...}
output=${2:?usage: mkinitramfs.sh GUEST_OS_DIR OUTPUT PROGRAM...}
shift 2
here=$(cd "$(dirname "$0")" && pwd)

stage=$(mktemp -d "${TMPDIR:-/tmp}/usb-stack-initramfs.XXXXXX")
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage"/{bin,sbin,usr/bin,lib,lib64,proc,sys,dev,run,tmp,etc,usb_stack}

busybox=$(command -v busybox)
# Debian's busybox-static is what we need; a dynamic busybox would need its libs.
if ldd "$busybox" >/dev/null 2>&1; then
  echo "mkinitramfs: $busybox is dynamically linked; install busybox-static" >&2
  exit 2
fi
cp "$busybox" "$stage/bin/busybox"
for applet in $("$busybox" --list); do
  [ -e "$stage/bin/$applet" ] || ln -s busybox "$stage/bin/$applet"
done

cp -a "$guest_os/modules/lib/modules" "$stage/lib/"

# Copies a dynamically linked file's libraries (and the loader) at their paths.
copy_libs() {
  local lib
  for lib in $(ldd "$1" 2>/dev/null | grep -oE '/[^ ]+' || true); do
    [ -e "$stage$lib" ] && continue
    mkdir -p "$stage$(dirname "$lib")"
    cp -L "$lib" "$stage$lib"
  done
}

if [ -f "$guest_os/udevadm" ]; then
  cp "$guest_os/udevadm" "$stage/bin/udevadm"
  mkdir -p "$stage/lib/systemd" "$stage/etc/udev/rules.d"
  # udevadm runs the daemon when invoked under this name.
  ln -s /bin/udevadm "$stage/lib/systemd/systemd-udevd"
  copy_libs "$stage/bin/udevadm"
fi

for prog in "$@"; do
  [ -x "$prog" ] || { echo "mkinitramfs: not an executable: $prog" >&2; exit 1; }
  cp "$prog" "$stage/usr/bin/"
  copy_libs "$prog"
done

cp -a "$here/guest/." "$stage/usb_stack/"
mv "$stage/usb_stack/init" "$stage/init"
chmod +x "$stage/init"
cp "$guest_os/kernel-version" "$stage/etc/kernel-version"

# Deterministic order; busybox's cpio writes the newc format the kernel wants.
mkdir -p "$(dirname "$output")"
(cd "$stage" && find . -mindepth 1 | LC_ALL=C sort | "$busybox" cpio -o -H newc 2>/dev/null) |
  gzip -1 >"$output.tmp"
mv "$output.tmp" "$output"
