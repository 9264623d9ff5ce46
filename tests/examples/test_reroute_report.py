#!/usr/bin/env python3
"""examples/demo/reroute_report.py on a made-up trace whose errors are known:
the phases, the presses, the control's same windows and their ratios.

Usage: test_reroute_report.py PATH/TO/reroute_report.py
Exits 1 with the failed check named; prints 'N passed, 0 failed' otherwise.
"""
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

script = sys.argv[1]
failures, passed = [], 0


def check(name, ok):
    global passed
    if ok:
        passed += 1
    else:
        failures.append(name)


def write_trace(path, error_at):
    """30 s at 100 Hz; the slave's seq one per ms; presses 2-3 s, 24-25 s."""
    cols = ["t", "state_seq", "state", "true_tau_out_0", "tau_est_0", "indentation_0"]
    with open(path, "w", newline="") as f:
        f.write("# made up for the test\n")
        w = csv.writer(f)
        w.writerow(cols)
        for i in range(3000):
            t = i * 0.01
            pressing = 2.0 <= t < 3.0 or 24.0 <= t < 25.0
            true = 0.1 if pressing else 0.0
            w.writerow([t, i * 10, 1, true, true + error_at(t), 0.002 if pressing else 0.0])


with tempfile.TemporaryDirectory() as d:
    trace, control, refit, report = (os.path.join(d, n)
                                      for n in ("trace.csv", "control.csv", "refit.csv", "r.json"))
    # Re-routed at 8 s: the error 0.001 before, 0.04 until the recalibration
    # (20 s, scales 1.5 / 1.4: settled 1 s later at 0.5/s), then 0.003; the
    # control 0.002 everywhere.
    write_trace(trace, lambda t: 0.001 if t < 8.0 else 0.04 if t < 21.0 else 0.003)
    write_trace(control, lambda t: 0.002)
    write_trace(refit, lambda t: 0.006)
    json.dump({"calibration": {"events": [
        {"t_s": 10.0, "kind": "drift_alarm", "joint": 0, "scale": 1.4},
        {"t_s": 20.0, "kind": "applied", "joint": 0, "scale": 1.45,
         "scale_positive": 1.5, "scale_negative": 1.4}]}}, open(report, "w"))
    out = subprocess.run([sys.executable, script, trace, report, "8", "5.1", "0.5", control, refit],
                         capture_output=True, text=True)
    check("exit 0", out.returncode == 0)
    r = json.load(open(report))["reroute"]
    near = lambda a, b: a is not None and abs(a - b) <= 1e-9 * max(1.0, abs(b))
    check("re-route found at 8 s", near(r["at_s"], 8.0))
    # Documented as a number (rad), as every other figure of the report.
    check("wrap_rad is a number", isinstance(r["wrap_rad"], float) and near(r["wrap_rad"], 5.1))
    check("alarm 2 s after", near(r["drift_alarm_delay_s"], 2.0))
    check("settled after the longer ramp", near(r["scale_settled_s"], 21.0))
    check("before rmse", near(r["phases"]["before"]["rmse_nm"], 0.001))
    check("recalibrated rmse", near(r["phases"]["recalibrated"]["rmse_nm"], 0.003))
    check("after / before", near(r["after_over_before"], 40.0))
    check("control over the same windows", near(r["control"]["recalibrated"]["rmse_nm"], 0.002))
    check("recalibrated / control", near(r["recalibrated_over_control"], 1.5))
    check("in contact / control", near(r["contact_recalibrated_over_control"], 1.5))
    check("the control's own phase ratio", near(r["control_recalibrated_over_before"], 1.0))
    check("verdict on the control", "(target <= 1.2: NOT met)" in out.stderr + out.stdout)
    presses = r["presses"]
    check("two presses", len(presses) == 2)
    check("press phases", [p["phase"] for p in presses] == ["before", "recalibrated"])
    check("press errors", len(presses) == 2 and near(presses[0]["rmse_nm"], 0.001)
          and near(presses[1]["rmse_nm"], 0.003))
    check("summary names the control", "never re-routed" in out.stderr + out.stdout)
    check("lab refit over the same windows", near(r["lab_refit"]["recalibrated"]["rmse_nm"], 0.006))
    check("recalibrated / lab refit", near(r["recalibrated_over_lab_refit"], 0.5))
    check("in contact / lab refit", near(r["contact_recalibrated_over_lab_refit"], 0.5))
    check("summary names the lab refit", "lab re-identification" in out.stderr + out.stdout)
    # Without a control the report has none (and says nothing of it).
    json.dump({"calibration": {"events": []}}, open(report, "w"))
    out = subprocess.run([sys.executable, script, trace, report, "8", "5.1", "0.5"],
                         capture_output=True, text=True)
    r = json.load(open(report))["reroute"]
    check("no control: none", out.returncode == 0 and r["control"] is None and r["lab_refit"] is None
          and r["recalibrated_over_control"] is None and r["phases"]["recalibrated"] is None)

for name in failures:
    print(f"FAILED: {name}")
print(f"{passed} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
