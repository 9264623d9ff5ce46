#!/usr/bin/env bash
# external-master-adapter with a master profile and a mapping: a simulated
# 3-DOF Cartesian master (the Falcon profile, the handle in m) presented to
# the server's lcm driver as the 2-DOF slave's joints (x -> joint 0 at
# 10 rad/m, z -> joint 1 at -10 rad/m), read back by tsm-devices --monitor lcm.
# Usage: adapter_profile_lcm.sh BIN_DIR SOURCE_DIR PORT
set -euo pipefail
bin=$1 src=$2 port=$3
work=$(mktemp -d)
trap 'kill -INT $adapter 2>/dev/null || true; rm -rf "$work"' EXIT
export LCM_DEFAULT_URL="udpm://239.255.76.67:${port}?ttl=0"
cat >"$work/mapping.yaml" <<'YAML'
joints:
  - {axis: x, scale: 10}
  - {axis: z, scale: -10}
buttons: {dead_man: center, clutch: left}
YAML
printf 'channel_prefix: FALCON_\ndof: 2\n' >"$work/lcm.yaml"
# A wrong axis name is refused, naming the field and the profile's axes.
if "$bin/external-master-adapter" --profile "$src/master_devices/profiles/masters/novint-falcon.yaml" \
     --mapping <(printf 'joints: [{axis: q}]\n') --duration 0.1 2>"$work/bad.log"; then
  echo "FAIL: a mapping with axis q was accepted"; exit 1; fi
grep -q "joints\[0\].axis: 'q' is not an axis of novint-falcon (its axes: x, y, z)" "$work/bad.log" || {
  echo "FAIL: the error does not name the field:"; cat "$work/bad.log"; exit 1; }
"$bin/external-master-adapter" --profile "$src/master_devices/profiles/masters/novint-falcon.yaml" \
  --mapping "$work/mapping.yaml" --prefix FALCON_ --duration 6 >"$work/adapter.out" 2>"$work/adapter.log" &
adapter=$!
sleep 0.5
"$bin/tsm-devices" monitor lcm --config "$work/lcm.yaml" --seconds 3 >"$work/monitor.log" 2>&1 || true
cat "$work/adapter.log"
python3 - "$work/monitor.log" <<'PY'
import re, sys
lines = [l for l in open(sys.argv[1]) if " seq " in l]
fails = []
def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok: fails.append(what)
ok = [l for l in lines if l.startswith("OK")]
check(len(ok) > 5, f"{len(ok)} OK readings of the 2-joint lcm master")
qs = [[float(x) for x in re.findall(r"[+-]\d+\.\d+", l.split(" q")[1].split("dead-man")[0])] for l in ok]
check(all(len(q) == 2 for q in qs), "every reading has the slave's 2 joints")
q0 = [q[0] for q in qs]
# The hand sweeps x by about 0.02 m around the centre: 10 rad/m -> about
# +-0.2 rad (the hand model overshoots a little); unscaled or unclamped it
# would read 0.02 rad or up to 0.5 rad.
check(max(abs(v) for v in q0) <= 0.25, f"joint 0 within +-0.25 rad (max {max(abs(v) for v in q0):.3f})")
check(max(q0) - min(q0) > 0.2, f"joint 0 follows the moving x axis (span {max(q0) - min(q0):.3f} rad)")
check(all("dead-man 1" in l for l in ok), "the profile's 'center' button is the dead-man")
sys.exit(1 if fails else 0)
PY
