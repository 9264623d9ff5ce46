# Our report descriptor on the kernel's own HID gadget (usb_f_hid,
# /dev/hidg0) with the console firmware behind it: the host kernel parses
# the descriptor, hidraw carries our numbered reports with their ID byte.
# usb_f_hid answers GET_REPORT itself and stalls SET_REPORT when it has an
# OUT endpoint, so the feature reports are recorded here, not judged; the
# FunctionFS cases serve them from the firmware as real hardware does.
# limit: 40
# needs: usb_stack_hidg_console usb_stack_console_hidraw_probe
# expect: hidg_enumeration hidg_raw_hidraw hidg_raw_report_descriptor hidg_raw_stream hidg_fw_stream
. /usb_stack/lib.sh

usb_stack_hidg_console --write-descriptor /tmp/console_desc.bin
gadget_create hidg 0x1209 0x0001 "tsm-haptics console (usb_f_hid)" &&
  gadget_add_hid hidg /tmp/console_desc.bin 32 &&
  gadget_bind hidg || { result hidg_enumeration FAIL "configfs gadget setup failed"; exit 0; }
t0=$(uptime_ms)
WAIT_S=10 wait_for test -c /dev/hidg0 || { result hidg_enumeration FAIL "/dev/hidg0 did not appear"; exit 0; }
if ! WAIT_S=10 wait_for hidraw_for 1209 0001; then
  result hidg_enumeration FAIL "no hidraw for 1209:0001 within 10 s"; exit 0
fi
result hidg_enumeration PASS "/dev/hidg0 + $(hidraw_for 1209 0001) $(( $(uptime_ms) - t0 )) ms after bind"
usb_stack_hidg_console --device /dev/hidg0 --prefix hidg &
fw=$!
usb_stack_console_hidraw_probe --prefix hidg_raw --count 1000 --features record
kill -TERM $fw; wait $fw 2>/dev/null || true
