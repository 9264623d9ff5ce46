#!/usr/bin/env bash
# Integration over real LCM (udpm, this host only): virtual-slave and
# haptic-server as separate processes. Asserts on the server's report:
# the loop ran and stayed ENABLED, the slave's state reached it, the
# estimate is closer to the true distal torque than the naive proximal
# torque, and torque stayed within the configured limit.
# Usage: integration_lcm.sh BIN_DIR CONFIG PORT
set -euo pipefail
bin=$1 config=$2 port=$3
work=$(mktemp -d)
trap 'kill -INT $slave 2>/dev/null || true; rm -rf "$work"' EXIT
url="udpm://239.255.76.67:${port}?ttl=0"

"$bin/virtual-slave" --lcm-url "$url" --tissue nodule >"$work/slave.log" 2>&1 &
slave=$!
sleep 0.3
"$bin/haptic-server" --config "$config" --lcm-url "$url" --duration 8 --quiet \
  --trace "$work/trace.csv" --report "$work/report.json" 2>"$work/server.log" || {
  cat "$work/server.log" "$work/slave.log"; exit 1; }
kill -INT $slave; wait $slave || true
cat "$work/server.log"
python3 - "$work/report.json" "$work/trace.csv" <<'PY'
import csv, json, math, sys
r = json.load(open(sys.argv[1]))
rows = list(csv.DictReader(open(sys.argv[2])))
fails = []
def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok: fails.append(what)
check(r["loop"]["rate_hz"] > 900, f"loop rate {r['loop']['rate_hz']:.1f} Hz > 900")
check(len(rows) > 7000, f"{len(rows)} trace rows for 8 s")
enabled = sum(1 for x in rows if x["state"] == "1")
check(enabled > 0.9 * len(rows), f"ENABLED for {enabled}/{len(rows)} ticks")
for j in r["joints"]:
    check(j["samples"] > 5000, f"joint {j['name']}: {j['samples']} ticks with matched SLAVE_TRUTH")
    check(j["rmse_estimated"] < j["rmse_naive"], f"joint {j['name']}: estimate rmse {j['rmse_estimated']:.4f} < naive {j['rmse_naive']:.4f}")
worst = max(abs(float(x[f"cmd_{k}"])) for x in rows for k in (0, 1))
check(worst <= 0.3 + 1e-12 and all(math.isfinite(float(x["cmd_0"])) for x in rows), f"torque within 0.3 N m (max {worst:.3f})")
sys.exit(1 if fails else 0)
PY
