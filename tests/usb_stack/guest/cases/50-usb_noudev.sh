# Our `usb` driver without udevd, as in a container or an initramfs: libusb's
# device list and hotplug events come from udevd's announcements, so after a
# rebind the driver must find the console again through its sysfs fallback
# (its reconnect poll, libusb_wrap_sys_device on the usbfs node). Listing,
# handshake, a short stream, one unplug and rebind; no watchdog phase. The
# last case: it stops the guest's udevd.
# limit: 60
# needs: usb_stack_ffs_console usb_stack_console_host
# expect: usb_noudev_gadget usb_noudev_list usb_noudev_open usb_noudev_stream usb_noudev_unplug1 usb_noudev_unplug1_rebind usb_noudev_fw_stream
. /usb_stack/lib.sh

udevd_stopped() { ! udevd_running; }
if udevd_running; then
  udevadm control --exit 2>/dev/null || killall -q systemd-udevd
  WAIT_S=5 wait_for udevd_stopped || killall -q -9 systemd-udevd
fi
udevd_running && { result usb_noudev_gadget FAIL "could not stop udevd"; exit 0; }
STREAM_S=0.5 REPLUGS=1 run_driver_case usb_noudev usb vendor --no-watchdog
