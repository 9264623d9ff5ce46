#!/usr/bin/env python3
"""The re-route demo's figures, from haptic-server's trace and report.

  reroute_report.py TRACE.csv REPORT.json REROUTE_AT_S WRAP RAMP_PER_S [CONTROL.csv [REFIT.csv]]

Adds a "reroute" object to REPORT.json (every existing field kept) with the
distal-torque error of joint1 before the re-route, after it (before the
recalibration) and after the recalibration, the drift alarm's delay and the
recalibration; writes the phases for the plot beside the trace
(reroute-phases.dat) and prints a summary. The slave's clock is its seq
(one sample per 1 kHz tick from 0), so the re-route's tick in the trace is
the first row whose state_seq reaches REROUTE_AT_S x 1000.

CONTROL.csv: the trace of the same scenario on a sheath never re-routed and
never recalibrated; each phase's error is then also measured over the same
time window of the control ("control"), and the recalibrated phase is set
beside its own window there: the phases before and after differ in content
(the first follows a tared start, the last follows the sweep), the control
does not.

REFIT.csv: what a lab re-identification reaches on the new routing: the
same scenario on a sheath re-routed from the start, with the model
identified on that routing by the bench procedure *with* a tip load cell
(the free-motion recalibration has no tip sensor). Measured over the same
windows ("lab_refit"); "recalibrated_over_lab_refit" at or below 1 means the
recalibration is as good as re-identifying in a lab there.
"""
import csv
import json
import math
import os
import sys

trace_path, report_path = sys.argv[1], sys.argv[2]
reroute_at, wrap, ramp = float(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
control_path = sys.argv[6] if len(sys.argv) > 6 and os.path.exists(sys.argv[6]) else None
refit_path = sys.argv[7] if len(sys.argv) > 7 and os.path.exists(sys.argv[7]) else None


def read_trace(path):
    return list(csv.DictReader(line for line in open(path) if not line.startswith("#")))


trace = read_trace(trace_path)
report = json.load(open(report_path))

t_reroute = next(float(r["t"]) for r in trace if int(r["state_seq"]) >= reroute_at * 1000)
events = report.get("calibration", {}).get("events", [])
alarms = [e for e in events if e["kind"] == "drift_alarm" and e["joint"] == 0 and e["t_s"] >= t_reroute]
applied = [e for e in events if e["kind"] == "applied" and e["joint"] == 0]
refused = [e for e in events if e["kind"] == "refused"]
t_applied = applied[0]["t_s"] if applied else math.inf
scale = applied[0]["scale"] if applied else 1.0
# After the recalibration each direction's scale ramps in at RAMP_PER_S:
# judge from the end of the longer ramp.
directions = [applied[0].get(k) for k in ("scale_positive", "scale_negative")] if applied else []
longest = max([abs(k - 1.0) for k in directions if k is not None] + [abs(scale - 1.0)])
t_settled = t_applied + longest / ramp


def phase(lo, hi, rows=None):
    sq = sq_contact = 0.0
    n = n_contact = 0
    for r in trace if rows is None else rows:
        t = float(r["t"])
        if not (lo <= t < hi) or r["state"] != "1":
            continue
        true, est = float(r["true_tau_out_0"]), float(r["tau_est_0"])
        if math.isnan(true) or math.isnan(est):
            continue
        e = (est - true) ** 2
        sq += e
        n += 1
        if abs(true) > 0.005:
            sq_contact += e
            n_contact += 1
    return {"from_s": lo, "to_s": hi if math.isfinite(hi) else None, "samples": n,
            "rmse_nm": math.sqrt(sq / n) if n else None,
            "contact_samples": n_contact,
            "contact_rmse_nm": math.sqrt(sq_contact / n_contact) if n_contact else None}


def presses():
    """Each press (the slave's indentation > 0 for over 0.3 s) with the error
    over it and 0.5 s either side: the phases' rms mixes presses, sweeps and
    rests in different shares, this compares like with like."""
    out, start = [], None
    for r in trace:
        if r["state"] != "1":
            continue
        t, d = float(r["t"]), float(r["indentation_0"])
        if d > 0 and start is None:
            start = t
        elif not d > 0 and start is not None and not math.isnan(d):
            if t - start > 0.3:
                out.append((start, t))
            start = None
    rows_out = []
    for lo, hi in out:
        sq, n, peak = 0.0, 0, 0.0
        for r in trace:
            t = float(r["t"])
            if not (lo - 0.5 <= t < hi + 0.5) or r["state"] != "1":
                continue
            true, est = float(r["true_tau_out_0"]), float(r["tau_est_0"])
            if math.isnan(true) or math.isnan(est):
                continue
            sq += (est - true) ** 2
            n += 1
            peak = max(peak, abs(true))
        rows_out.append({"from_s": lo, "to_s": hi, "peak_nm": peak,
                         "rmse_nm": math.sqrt(sq / n) if n else None})
    return rows_out


end = float(trace[-1]["t"])
phases = {"before": phase(0.0, t_reroute), "after": phase(t_reroute, min(t_applied, end)),
          "recalibrated": phase(t_settled, end) if applied else None}
b, a, c = phases["before"], phases["after"], phases["recalibrated"]


def same_windows(path):
    """Each phase's error over the same time window of another run's trace."""
    if not path:
        return None
    rows = read_trace(path)
    return {k: phase(p["from_s"], p["to_s"] if p["to_s"] is not None else math.inf, rows)
            for k, p in phases.items() if p}


control, refit = same_windows(control_path), same_windows(refit_path)
ratio = lambda x, y, k: (x[k] / y[k]) if x and y and x[k] and y[k] else None
report["reroute"] = {
    "joint": 0, "at_slave_s": reroute_at, "at_s": t_reroute, "wrap_rad": wrap,
    "drift_alarm_s": alarms[0]["t_s"] if alarms else None,
    "drift_alarm_delay_s": alarms[0]["t_s"] - t_reroute if alarms else None,
    "recalibration_applied_s": applied[0]["t_s"] if applied else None,
    "recalibration_scale": scale if applied else None,
    "recalibration_refused": [e["reason"] for e in refused],
    "scale_settled_s": t_settled if applied else None,
    "phases": phases,
    "after_over_before": ratio(a, b, "rmse_nm"),
    "recalibrated_over_before": ratio(c, b, "rmse_nm"),
    "contact_recalibrated_over_before": ratio(c, b, "contact_rmse_nm"),
    "presses": presses(),
    "control": control,
    "recalibrated_over_control": ratio(c, control["recalibrated"], "rmse_nm") if control and c else None,
    "contact_recalibrated_over_control":
        ratio(c, control["recalibrated"], "contact_rmse_nm") if control and c else None,
    # The scenario's own phase ratio with no re-route at all: what
    # recalibrated_over_before would be after a perfect recalibration.
    "control_recalibrated_over_before":
        ratio(control["recalibrated"], control["before"], "rmse_nm") if control and c else None,
    "lab_refit": refit,
    "recalibrated_over_lab_refit": ratio(c, refit["recalibrated"], "rmse_nm") if refit and c else None,
    "contact_recalibrated_over_lab_refit":
        ratio(c, refit["recalibrated"], "contact_rmse_nm") if refit and c else None,
}
for p in report["reroute"]["presses"]:
    p["phase"] = ("before" if p["to_s"] < t_reroute else
                  "recalibrated" if p["from_s"] >= t_settled else
                  "after" if p["to_s"] < t_applied else "mixed")
tmp = report_path + ".tmp"
with open(tmp, "w") as f:
    json.dump(report, f, indent=2)
    f.write("\n")
os.replace(tmp, report_path)
with open(os.path.join(os.path.dirname(trace_path), "reroute-phases.dat"), "w") as f:
    # -1: did not happen (the plot's arrows then fall outside the time axis)
    f.write(f"{t_reroute} {report['reroute']['drift_alarm_s'] or -1} "
            f"{applied[0]['t_s'] if applied else -1} {t_settled if applied else -1}\n")

def fmt(p):
    if not p or p["rmse_nm"] is None:
        return "no data"
    contact = f"{p['contact_rmse_nm']:.4f} N m" if p["contact_rmse_nm"] is not None else "none"
    return f"rmse {p['rmse_nm']:.4f} N m ({p['samples']} ticks), in contact {contact}"
# Every time printed is on the server's clock (s since haptic-server
# started; the slave started about half a second before it).
print(f"   times in s since haptic-server started; re-route at {t_reroute:.1f} s (the slave's "
      f"{reroute_at:g} s; joint1's sheath wrap now {wrap:g} rad); drift alarm "
      + (f"at {alarms[0]['t_s']:.1f} s ({alarms[0]['t_s'] - t_reroute:.1f} s after)" if alarms else "never")
      + "; recalibration " + (f"applied at {t_applied:.1f} s, friction scale x{scale:.3f} "
                              f"(the identified friction times it)" if applied
                              else "not applied " + str([e['reason'] for e in refused])))
print(f"   joint1 distal-torque error: before {fmt(b)}")
print(f"                                after  {fmt(a)}")
print(f"                        recalibrated  {fmt(c)}")
for p in report["reroute"]["presses"]:
    print(f"     press {p['from_s']:5.1f}-{p['to_s']:5.1f} s ({p['phase']}, peak {p['peak_nm']:.3f} N m): "
          f"rmse {p['rmse_nm']:.4f} N m" if p["rmse_nm"] is not None else "no data")
if control:
    print(f"   the same windows on a sheath never re-routed (control run): before {fmt(control['before'])}")
    if "recalibrated" in control:
        print(f"                                                   recalibrated window {fmt(control['recalibrated'])}")
    rr = report["reroute"]
    if rr["recalibrated_over_control"]:
        verdict = "met" if rr["recalibrated_over_control"] <= 1.2 else "NOT met"
        contact = (f"; in contact {rr['contact_recalibrated_over_control']:.2f}"
                   if rr["contact_recalibrated_over_control"] else "")
        print(f"   recalibrated / the same window never re-routed: {rr['recalibrated_over_control']:.2f} "
              f"(target <= 1.2: {verdict}){contact}")
if refit:
    print(f"   the same windows with a lab re-identification (the bench identification with a tip load cell on the new routing):")
    print(f"                                                   before window {fmt(refit['before'])}")
    if "recalibrated" in refit:
        print(f"                                                   recalibrated window {fmt(refit['recalibrated'])}")
    rr = report["reroute"]
    if rr["recalibrated_over_lab_refit"]:
        print(f"   recalibrated (free motion, no tip sensor) / lab re-identification: {rr['recalibrated_over_lab_refit']:.2f}"
              + (f", in contact {rr['contact_recalibrated_over_lab_refit']:.2f}"
                 if rr["contact_recalibrated_over_lab_refit"] else ""))
if report["reroute"]["recalibrated_over_before"]:
    own = report["reroute"].get("control_recalibrated_over_before")
    print(f"   recalibrated / before: {report['reroute']['recalibrated_over_before']:.2f} "
          + (f"(the phases differ in content: on the sheath never re-routed the same ratio is {own:.2f}); "
             if own else "(target <= 1.2; run with the control to judge like with like); ")
          + f"after / before {report['reroute']['after_over_before']:.2f}")
