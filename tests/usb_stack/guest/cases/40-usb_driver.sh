# Our `usb` driver (libusb, async transfers, hotplug) against the console
# firmware on a vendor-class FunctionFS gadget: the same phases as the hid
# case.
# limit: 90
# needs: usb_stack_ffs_console usb_stack_console_host
# expect: usb_gadget usb_list usb_open usb_stream usb_fw_watchdog usb_watchdog_resume usb_unplug1 usb_unplug1_rebind usb_unplug2 usb_unplug2_rebind usb_fw_stream
. /usb_stack/lib.sh
run_driver_case usb usb vendor
