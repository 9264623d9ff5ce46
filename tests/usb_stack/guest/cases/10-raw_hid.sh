# Raw kernel semantics with a stand-in descriptor (no codec of ours): the
# usb_f_hid gadget enumerates through dummy_hcd, usbhid/hidraw bind, numbered
# reports round-trip with their ID byte. Programs: usb_stack_hidg_echo
# (device side), usb_stack_hidraw_probe (host side).
# limit: 40
# expect: raw_enumeration raw_usbfs_node raw_hidraw_found raw_hidraw_info raw_report_descriptor raw_round_trip
. /usb_stack/lib.sh

usb_stack_hidraw_probe --write-descriptor /tmp/raw_desc.bin
gadget_create raw 0x1209 0x0001 "usb-stack raw" &&
  gadget_add_hid raw /tmp/raw_desc.bin 9 &&
  gadget_bind raw || { result raw_gadget FAIL "configfs gadget setup failed"; exit 0; }

t0=$(uptime_ms)
if ! WAIT_S=10 wait_for test -c /dev/hidg0; then
  result raw_gadget FAIL "/dev/hidg0 did not appear"; exit 0
fi
if ! WAIT_S=10 wait_for hidraw_for 1209 0001; then
  result raw_enumeration FAIL "no hidraw for 1209:0001 within 10 s"; exit 0
fi
result raw_enumeration PASS "hidg0 + $(hidraw_for 1209 0001) in $(( $(uptime_ms) - t0 )) ms"
[ -n "$(ls /dev/bus/usb/001/ 2>/dev/null | sed -n 2p)" ] &&
  result raw_usbfs_node PASS "$(ls /dev/bus/usb/001/ | tr '\n' ' ')" ||
  result raw_usbfs_node FAIL "no second node in /dev/bus/usb/001"

usb_stack_hidg_echo --device /dev/hidg0 --seconds 20 &
echo_pid=$!
usb_stack_hidraw_probe --vid 0x1209 --pid 0x0001 --count 200
kill $echo_pid 2>/dev/null; wait $echo_pid 2>/dev/null || true
