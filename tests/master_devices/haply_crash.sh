#!/usr/bin/env bash
# haptic-server with the `haply` driver (the documented config, its port
# replaced by the emulated board's pty) and virtual-slave's tissue, ended by
# SIGNAL (a core-dumping one: SEGV, ABRT, ...). The board has no watchdog of
# its own, so only the server's crash handler can take the torque off: passes
# when the server died of that signal, the board had been given torque
# before, and its last torque is exactly zero.
# Usage: haply_crash.sh BIN_DIR SOURCE_DIR PORT SIGNAL
set -euo pipefail
bin=$1 src=$2 port=$3 sig=$4
work=$(mktemp -d)
board= slave= server=
trap 'kill $board $slave $server 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$work"' EXIT
export LCM_DEFAULT_URL="udpm://239.255.76.67:${port}?ttl=0"
ulimit -c 0  # no core file from the signal

"$bin/haply_pty_board" --seconds 30 >"$work/board.out" &
board=$!
for _ in $(seq 100); do [ -s "$work/board.out" ] && break; sleep 0.05; done
pty=$(head -n1 "$work/board.out")
sed "s|port: /dev/ttyACM0|port: $pty|" "$src/master_devices/examples/haply-2diy-server.yaml" \
  >"$work/server.yaml"
grep -q "port: $pty" "$work/server.yaml"

"$bin/virtual-slave" --tissue nodule --duration 20 >"$work/slave.log" 2>&1 &
slave=$!
sleep 0.5
"$bin/haptic-server" --config "$work/server.yaml" --quiet >"$work/server.log" 2>&1 &
server=$!
sleep 5  # the hand presses into the tissue and back meanwhile
kill "-$sig" $server
status=0
wait $server || status=$?
server=
sleep 0.3  # the board's last command, if any, has arrived
kill -TERM $board
wait $board || true
board=
cat "$work/server.log"
tail -n1 "$work/board.out"
python3 - "$status" "$sig" "$work/board.out" <<'PY'
import signal, sys
status, sig = int(sys.argv[1]), sys.argv[2]
line = open(sys.argv[3]).read().strip().splitlines()[-1].split()
assert line[0] == "HAPLY_BOARD", line
states, largest = int(line[2]), float(line[4])
final = [float(line[6]), float(line[7])]
fails = []
def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok: fails.append(what)
check(status == 128 + int(getattr(signal, "SIG" + sig)), f"haptic-server ended by SIG{sig} (status {status})")
check(states > 500 and largest > 0.005, f"the board was driven before: {states} commands, up to {largest:.4f} N m")
check(final == [0.0, 0.0], f"zero torque at the board after the crash ({final})")
sys.exit(1 if fails else 0)
PY
