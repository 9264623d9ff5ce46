# The Haply board's emulator behind the kernel's CDC-ACM gadget function
# (usb_f_acm, /dev/ttyGS0) and our `haply` driver on the /dev/ttyACM0 that
# cdc_acm makes of it: the handshake, a stream with torque, the host-side
# watchdog and an unplug, over the real USB serial stack. VID:PID 1209:0002
# is a test ID (the board's own IDs are not published with its protocol).
# limit: 60
# needs: usb_stack_haply_board usb_stack_haply_host
# expect: acm_enumeration acm_list acm_open acm_stream acm_watchdog acm_unplug
. /usb_stack/lib.sh

if ! modprobe usb_f_acm 2>/tmp/acm.err || ! modprobe cdc-acm 2>>/tmp/acm.err; then
  result acm_enumeration FAIL "the guest kernel lacks the CDC-ACM modules: $(cat /tmp/acm.err)"
  exit 0
fi
gadget_create haply 0x1209 0x0002 "tsm-haptics haply board (emulated)" &&
  mkdir -p "$CONFIGFS/haply/functions/acm.usb0" &&
  ln -s "$CONFIGFS/haply/functions/acm.usb0" "$CONFIGFS/haply/configs/c.1/" &&
  gadget_bind haply || { result acm_enumeration FAIL "configfs acm gadget setup failed"; exit 0; }
t0=$(uptime_ms)
WAIT_S=10 wait_for test -c /dev/ttyGS0 || { result acm_enumeration FAIL "/dev/ttyGS0 did not appear"; exit 0; }
WAIT_S=10 wait_for test -c /dev/ttyACM0 || { result acm_enumeration FAIL "/dev/ttyACM0 did not appear"; exit 0; }
result acm_enumeration PASS "/dev/ttyGS0 + /dev/ttyACM0 $(( $(uptime_ms) - t0 )) ms after bind"
if [ -x /usr/bin/tsm-devices ]; then
  listing=$(tsm-devices list 2>&1)
  if echo "$listing" | grep -q "^haply.*/dev/ttyACM0.*1209:0002"; then
    result acm_list PASS "tsm-devices list: $(echo "$listing" | grep ttyACM0 | tr '\t' ' ')"
  else
    result acm_list FAIL "tsm-devices list does not show /dev/ttyACM0 for haply: $(echo "$listing" | tr "\n" ";")"
  fi
else
  result acm_list SKIP "tsm-devices is not built"
fi
rm -f /tmp/haply.silent /tmp/haply.state
usb_stack_haply_board --tty /dev/ttyGS0 --control /tmp/haply &
board=$!
usb_stack_haply_host --port /dev/ttyACM0 --control /tmp/haply --gadget haply
kill -TERM $board 2>/dev/null; wait $board 2>/dev/null || true
