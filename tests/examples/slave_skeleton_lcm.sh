#!/usr/bin/env bash
# slave-node-skeleton against the real haptic-server over LCM (udpm, this
# host only, its own port): the server stays ENABLED on the skeleton's
# SLAVE_STATE, and the skeleton follows the server's MASTER_COMMAND.
# Usage: slave_skeleton_lcm.sh BIN_DIR CONFIG PORT
set -euo pipefail
bin=$1 config=$2 port=$3
work=$(mktemp -d)
trap 'kill -INT $slave 2>/dev/null || true; rm -rf "$work"' EXIT
url="udpm://239.255.76.67:${port}?ttl=0"

"$bin/slave-node-skeleton" --prefix ARM1_ --lcm-url "$url" >"$work/slave.log" 2>&1 &
slave=$!
sleep 0.3
"$bin/haptic-server" --config "$config" --lcm-url "$url" --duration 4 --quiet \
  --trace "$work/trace.csv" 2>"$work/server.log" || {
  cat "$work/server.log" "$work/slave.log"; exit 1; }
kill -INT $slave; wait $slave || true
cat "$work/server.log" "$work/slave.log"
python3 - "$work/trace.csv" <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
fails = []
def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok: fails.append(what)
check(len(rows) > 3500, f"{len(rows)} trace rows for 4 s")
enabled = sum(1 for x in rows if x["state"] == "1")
check(enabled > 0.9 * len(rows), f"ENABLED for {enabled}/{len(rows)} ticks")
tail = rows[len(rows) // 2:]
for j in (0, 1):
    finite = all(math.isfinite(float(x[f"tau_in_{j}"])) and math.isfinite(float(x[f"tau_est_{j}"])) for x in tail)
    check(finite, f"joint {j}: tau_in and the estimate finite over the last 2 s")
    moved = max(abs(float(x[f"ref_{j}"])) for x in rows)
    err = max(abs(float(x[f"x_in_{j}"]) - float(x[f"ref_{j}"])) for x in tail)
    check(moved < 0.01 or err < max(0.05, 0.5 * moved),
          f"joint {j}: slave follows the reference (max |ref| {moved:.3f}, max |x_in - ref| {err:.3f} rad)")
sys.exit(1 if fails else 0)
PY
