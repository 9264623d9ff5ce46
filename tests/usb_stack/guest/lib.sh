# Shell helpers for the guest's cases (sourced): result lines, waiting, and
# configfs USB gadgets on dummy_udc.0.
# shellcheck shell=sh

CONFIGFS=/sys/kernel/config/usb_gadget
UDC_NAME=dummy_udc.0

# cmdline_opt KEY: the value of KEY=VALUE on the kernel command line.
cmdline_opt() {
  for w in $(cat /proc/cmdline); do
    case "$w" in "$1"=*) echo "${w#*=}"; return ;; esac
  done
}

# result NAME PASS|FAIL|SKIP DETAIL...: the line the host harness parses.
result() {
  n=$1; s=$2; shift 2
  echo "RESULT $n $s $*"
}

# metric NAME VALUE UNIT: a measured number, reported (not judged) by the harness.
metric() { echo "METRIC $1 $2 $3"; }

# case_limit FILE: the "# limit: N" seconds a case declares (default 60).
case_limit() {
  l=$(sed -n 's/^# limit: *\([0-9]*\).*/\1/p' "$1" | head -n1)
  echo "${l:-60}"
}

# wait_for COMMAND ARGS... : runs COMMAND every 20 ms until it succeeds, for
# up to WAIT_S seconds (default 10). Returns 1 on timeout.
wait_for() {
  i=0; limit=$(( ${WAIT_S:-10} * 50 ))
  while ! "$@" >/dev/null 2>&1; do
    i=$((i + 1)); [ $i -ge $limit ] && return 1
    usleep 20000
  done
}

# uptime_ms: monotonic guest time in ms (for coarse case timing).
uptime_ms() { awk '{ printf "%d\n", $1 * 1000 }' /proc/uptime; }

# gadget_create NAME VID PID PRODUCT: an empty gadget with one configuration.
gadget_create() {
  g=$CONFIGFS/$1
  mkdir -p "$g" || return 1
  echo "$2" >"$g/idVendor"
  echo "$3" >"$g/idProduct"
  echo 0x0200 >"$g/bcdUSB"
  echo 0x0100 >"$g/bcdDevice"
  mkdir -p "$g/strings/0x409" "$g/configs/c.1/strings/0x409"
  echo "tsm-haptics test" >"$g/strings/0x409/manufacturer"
  echo "$4" >"$g/strings/0x409/product"
  echo "usb-stack-0001" >"$g/strings/0x409/serialnumber"
  echo "config 1" >"$g/configs/c.1/strings/0x409/configuration"
  echo 100 >"$g/configs/c.1/MaxPower"
}

# gadget_add_hid NAME REPORT_DESC_FILE REPORT_LENGTH: a usb_f_hid function
# (device side /dev/hidgN) with the given report descriptor.
gadget_add_hid() {
  f=$CONFIGFS/$1/functions/hid.usb0
  mkdir -p "$f" || return 1
  echo 0 >"$f/protocol"
  echo 0 >"$f/subclass"
  echo "$3" >"$f/report_length"
  cat "$2" >"$f/report_desc"
  ln -s "$f" "$CONFIGFS/$1/configs/c.1/"
}

# gadget_add_ffs NAME INSTANCE: a FunctionFS function whose descriptors and
# endpoints a userspace program provides through /dev/ffs-INSTANCE (ep0 first;
# the gadget can be bound only after that program has written descriptors).
gadget_add_ffs() {
  f=$CONFIGFS/$1/functions/ffs.$2
  mkdir -p "$f" || return 1
  ln -s "$f" "$CONFIGFS/$1/configs/c.1/"
  mkdir -p "/dev/ffs-$2"
  mount -t functionfs "$2" "/dev/ffs-$2"
}

# gadget_bind NAME / gadget_unbind NAME: plug / unplug the virtual cable.
gadget_bind() { echo "$UDC_NAME" >"$CONFIGFS/$1/UDC"; }
gadget_unbind() { echo "" >"$CONFIGFS/$1/UDC"; }

# gadget_remove_all: unbinds and removes every gadget (between cases).
gadget_remove_all() {
  for g in "$CONFIGFS"/*/; do
    [ -d "$g" ] || continue
    [ -n "$(cat "$g/UDC" 2>/dev/null)" ] && echo "" >"$g/UDC"
    for l in "$g"configs/*/*; do [ -L "$l" ] && rm -f "$l"; done
    for d in "$g"configs/*/strings/*; do [ -d "$d" ] && rmdir "$d"; done
    for d in "$g"configs/*; do [ -d "$d" ] && rmdir "$d"; done
    for d in "$g"functions/*; do
      [ -d "$d" ] || continue
      case "$d" in */ffs.*) umount "/dev/ffs-${d##*/ffs.}" 2>/dev/null ;; esac
      rmdir "$d"
    done
    for d in "$g"strings/*; do [ -d "$d" ] && rmdir "$d"; done
    rmdir "$g"
  done
}

# hidraw_for VID PID: the /dev/hidrawN whose HID_ID matches (hex, no 0x).
hidraw_for() {
  for u in /sys/class/hidraw/*/device/uevent; do
    [ -f "$u" ] || continue
    if grep -qi "^HID_ID=0003:0000$1:0000$2\$" "$u"; then
      n=${u#/sys/class/hidraw/}; echo "/dev/${n%%/*}"; return 0
    fi
  done
  return 1
}

# proc_state PID: the one-letter state of a process (T = stopped), "" when gone.
proc_state() { sed -n 's/^[0-9]* (.*) \([A-Za-z]\).*/\1/p' "/proc/$1/stat" 2>/dev/null; }
proc_stopped_or_gone() { s=$(proc_state "$1"); [ -z "$s" ] || [ "$s" = T ] || [ "$s" = t ]; }

# udevd_running: whether the guest's udevd is up (a case may stop it).
udevd_running() { pidof systemd-udevd >/dev/null 2>&1; }

# run_driver_case PREFIX DRIVER PERSONALITY [HOST_ARGS...]: the console
# firmware on a FunctionFS gadget with the given personality, our DRIVER on
# the host side (usb_stack_console_host HOST_ARGS...), tsm-devices --list when
# it is built. The firmware tells the host, outside the USB stack, when each
# input report left (the mailbox, a shared file) and its watchdog verdict
# (<mailbox>.watchdog).
run_driver_case() {
  prefix=$1; driver=$2; personality=$3
  shift 3
  mailbox=/tmp/${prefix}_mailbox
  gadget_create console 0x1209 0x0001 "tsm-haptics console" &&
    gadget_add_ffs console console || { result "${prefix}_gadget" FAIL "configfs/functionfs setup failed"; return; }
  usb_stack_ffs_console --ffs /dev/ffs-console --personality "$personality" --prefix "$prefix" \
    --mailbox "$mailbox" &
  fw=$!
  WAIT_S=5 wait_for test -e /dev/ffs-console/ep2 ||
    { result "${prefix}_gadget" FAIL "firmware did not write its descriptors"; kill $fw; return; }
  t0=$(uptime_ms)
  gadget_bind console || { result "${prefix}_gadget" FAIL "bind to $UDC_NAME failed"; kill $fw; return; }
  # Enumerated when the USB device is configured (sysfs bConfigurationValue = 1).
  if ! WAIT_S=10 wait_for grep -q 1 /sys/bus/usb/devices/1-1/bConfigurationValue; then
    result "${prefix}_gadget" FAIL "device 1-1 not configured within 10 s"; kill $fw; return
  fi
  udevd_running && udevadm settle -t 5 2>/dev/null
  result "${prefix}_gadget" PASS "enumerated $(( $(uptime_ms) - t0 )) ms after bind"

  # The listings a user runs: the console must be found by VID:PID with the
  # driver that can open it.
  echo "USB_STACK_PHASE ${prefix}_tools uptime=$(cut -d' ' -f1 /proc/uptime)"
  for tool in tsm-devices:--list haptic-server:--list-devices; do
    prog=${tool%%:*}
    command -v "$prog" >/dev/null || continue
    out=$("$prog" "${tool#*:}" 2>&1)
    line=$(echo "$out" | grep -i "1209:0001" | grep -w "$driver" | head -n1)
    if [ -n "$line" ]; then
      result "${prefix}_$(echo "$prog" | tr - _)_list" PASS "$prog ${tool#*:}: $(echo "$line" | tr '\t' ' ')"
    else
      result "${prefix}_$(echo "$prog" | tr - _)_list" FAIL "$prog ${tool#*:}: no $driver 1209:0001 line in: $(echo "$out" | tr '\n' '|')"
    fi
  done

  echo "USB_STACK_PHASE ${prefix}_host uptime=$(cut -d' ' -f1 /proc/uptime)"
  usb_stack_console_host --driver "$driver" --prefix "$prefix" --udc "$CONFIGFS/console/UDC" \
    --mailbox "$mailbox" --seconds "${STREAM_S:-2}" --replugs "${REPLUGS:-2}" "$@" &
  host=$!
  # The host stops itself (SIGSTOP) to play a host that died silently: the
  # firmware's watchdog must zero the torque. Let it judge, then continue.
  # It may ask for another attempt ("retry": nothing to cut), at most 5.
  for attempt in 1 2 3 4 5; do
    rm -f "$mailbox.watchdog"
    WAIT_S=60 wait_for proc_stopped_or_gone $host && [ -n "$(proc_state $host)" ] || break
    usleep 300000
    kill -USR1 $fw
    WAIT_S=5 wait_for test -s "$mailbox.watchdog"
    kill -CONT $host
    [ "$(cat "$mailbox.watchdog" 2>/dev/null)" = retry ] || break
  done
  wait $host || echo "usb_stack_console_host exited with status $?"
  kill -TERM $fw
  wait $fw 2>/dev/null || true
}
