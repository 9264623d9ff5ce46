# Our `hid` driver (hidapi over hidraw) against the console firmware on a
# FunctionFS HID gadget: listing, handshake, 1 kHz stream, firmware watchdog,
# unplug/rebind.
# limit: 90
# needs: usb_stack_ffs_console usb_stack_console_host
# expect: hid_gadget hid_list hid_open hid_stream hid_fw_watchdog hid_watchdog_resume hid_unplug1 hid_unplug1_rebind hid_unplug2 hid_unplug2_rebind hid_fw_stream
. /usb_stack/lib.sh
run_driver_case hid hid hid
