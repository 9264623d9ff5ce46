# The console firmware behind a FunctionFS HID function (ep0 handled in
# userspace, like real firmware), seen through the host kernel's usbhid and
# hidraw with our codec but without our driver: descriptor, feature reports,
# report-ID byte, input sequence, output round trip.
# limit: 40
# needs: usb_stack_ffs_console usb_stack_console_hidraw_probe
# expect: ffs_hid_enumeration ffs_hid_raw_hidraw ffs_hid_raw_report_descriptor ffs_hid_raw_get_feature ffs_hid_raw_set_feature ffs_hid_raw_stream ffs_hid_fw_stream
. /usb_stack/lib.sh

gadget_create console 0x1209 0x0001 "tsm-haptics console" &&
  gadget_add_ffs console console || { result ffs_hid_enumeration FAIL "configfs/functionfs setup failed"; exit 0; }
usb_stack_ffs_console --ffs /dev/ffs-console --personality hid --prefix ffs_hid &
fw=$!
WAIT_S=5 wait_for test -e /dev/ffs-console/ep2 || { result ffs_hid_enumeration FAIL "firmware did not write its descriptors"; exit 0; }
t0=$(uptime_ms)
gadget_bind console || { result ffs_hid_enumeration FAIL "bind to $UDC_NAME failed"; exit 0; }
if WAIT_S=10 wait_for hidraw_for 1209 0001; then
  result ffs_hid_enumeration PASS "$(hidraw_for 1209 0001) $(( $(uptime_ms) - t0 )) ms after bind"
  usb_stack_console_hidraw_probe --prefix ffs_hid_raw --count 1000 --features expect
else
  result ffs_hid_enumeration FAIL "no hidraw for 1209:0001 within 10 s"
fi
kill -TERM $fw; wait $fw 2>/dev/null || true
