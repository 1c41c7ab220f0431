#!/usr/bin/env python3
"""Check canon.py and rs274.py against the samples: exit codes, error lines and
messages, and the numbers the hot-wire and arc samples must produce.

    python3 tests/interp/selftest.py      # ends with "N passed, N failed"

Needs linuxcnc-uspace (tests/interp/install.sh). Exits 0 only if all pass.
"""

import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
S = os.path.join(HERE, "samples")
CANON = [os.path.join(HERE, "canon.py")]
RS274 = [sys.executable, os.path.join(HERE, "rs274.py")]

results = []


def check(name, cond, detail=""):
    results.append(bool(cond))
    print("%s %s%s" % ("ok  " if cond else "FAIL", name, "" if cond else "  -- " + detail))


def canon(sample, *args):
    p = subprocess.run(CANON + list(args) + [os.path.join(S, sample)],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        out = json.loads(p.stdout.decode())
    except ValueError:
        out = None
    return p.returncode, out, p.stderr.decode()


def rs274(sample, *args):
    p = subprocess.run(RS274 + list(args) + [os.path.join(S, sample)],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    return p.returncode, p.stdout.decode(), p.stderr.decode()


def near(a, b, tol=1e-6):
    return a is not None and abs(a - b) <= tol


def feeds(out):
    return [m for m in out["moves"] if m["kind"] == "feed"]


def expect_error(name, sample, axes, line, text):
    rc, out, err = canon(sample, "--axes", axes)
    e = (out or {}).get("error") or {}
    check(name, rc == 1 and out and not out["ok"] and e.get("line") == line
          and text in e.get("message", ""), "rc=%s error=%s %s" % (rc, e, err))


# --- canon.py ---------------------------------------------------------------
rc, out, err = canon("hotwire_g93_xyuv.ngc", "--axes", "XYUV")
check("hotwire accepted on an XYUV machine", rc == 0 and out and out["ok"], "rc=%s %s" % (rc, err))
if out:
    f = feeds(out)
    check("hotwire: F back from G93 feeds", [m.get("inverse_time") for m in f] == [120, 60, 30, 20, 10],
          [m.get("inverse_time") for m in f])
    check("hotwire: each G93 move lasts 60/F s", [m["duration_s"] for m in f] == [0.5, 1, 2, 3, 6],
          [m["duration_s"] for m in f])
    check("hotwire: G93 length is XY only when XY moves (11.18 mm, UV ignored)",
          near(f[0]["length"], 11.18034) and near(f[0]["feed"], 1341.640786), f[0])
    check("hotwire: UV-only move measured on UV", f[3]["line"] == 9 and near(f[3]["length"], 5.0), f[3])
    check("hotwire: U and V come through in mm", f[0]["u"] == 10.0 and f[0]["v"] == 6.0, f[0])
    check("hotwire: dwell G4 P1.5 is 1.5 s", out["dwells"] == [{"line": 5, "seconds": 1.5}], out["dwells"])
    check("hotwire: M3 S800 seen", out["spindle"][0]["state"] == "cw" and out["spindle"][0]["speed"] == 800,
          out["spindle"])

expect_error("hotwire rejected on an XYZ machine (no U axis)", "hotwire_g93_xyuv.ngc", "XYZ", 3,
             "Bad character 'u' used")

rc, out, err = canon("arcs_g94.ngc", "--axes", "XYZ")
check("arcs accepted", rc == 0 and out and out["ok"], "rc=%s %s" % (rc, err))
if out:
    arcs = [m for m in out["moves"] if m["kind"] == "arc"]
    a = arcs[0]
    check("G2 half circle: centre, radius, cw",
          a["centre"] == {"x": 15.0, "y": 0.0} and a["radius"] == 5.0 and a["direction"] == "cw"
          and a["sweep_deg"] == -180.0 and a["start"]["x"] == 10.0 and a["x"] == 20.0, a)
    check("G3 P2: two full turns", arcs[1]["turns"] == 2 and arcs[1]["sweep_deg"] == 720.0, arcs[1])
    check("G3 R10 quarter: centre from R", arcs[2]["centre"] == {"x": 20.0, "y": 10.0}, arcs[2])
    check("helix length", near(arcs[3]["length"], 15.834775) and arcs[3]["z"] == -2.0, arcs[3])
    check("G18 arc is in XZ", arcs[4]["plane"] == "XZ" and arcs[4]["centre"] == {"z": -2.0, "x": 45.0}, arcs[4])
    check("G19 arc is in YZ", arcs[5]["plane"] == "YZ" and arcs[5]["y"] == 10.0, arcs[5])
    check("G94 feed in mm/min", all(m["feed"] == 600.0 for m in arcs), [m["feed"] for m in arcs])
    check("two dwells", [d["seconds"] for d in out["dwells"]] == [1.0, 0.5], out["dwells"])

rc, out, err = canon("inch_mixed.ngc", "--axes", "XYZA")
check("G20 program reported in mm", rc == 0 and out and out["moves"][0]["x"] == 25.4
      and out["moves"][1]["feed"] == 254.0, "rc=%s %s" % (rc, out and out["moves"][:2]))
if out:
    m = out["moves"][-1]
    check("pure A move: feed deg/min", m["a"] == 90.0 and m["feed"] == 360.0 and m["duration_s"] == 15.0, m)

expect_error("syntax error line and message", "syntax_error.ngc", "XYZ", 4, "Q word with no")
expect_error("G93 needs F on every G1", "g93_missing_f.ngc", "XYUV", 5,
             "F word missing with inverse time g1 move")
expect_error("file must end with M2/M30/%", "no_program_end.ngc", "XYZ", 3,
             "File ended with no percent sign or program end")
rc, out, err = canon("percent_wrapped.ngc", "--axes", "XYZ")
check("percent-wrapped program needs no M2", rc == 0 and out["ok"], "rc=%s" % rc)

expect_error("Marlin output rejected (M104)", "dialect_marlin.gcode", "XYZ", 2, "Unknown m code used: M104")
rc, out, err = canon("dialect_marlin_filtered.gcode", "--axes", "XYZ")
check("filtered Marlin output accepted", rc == 0 and out["ok"] and out["dwells"][0]["seconds"] == 0.5,
      "rc=%s %s" % (rc, err))
expect_error("GRBL $H rejected", "dialect_grbl.nc", "XYZ", 1, "Unknown word where unary operation could be")
rc, out, err = canon("dialect_mach3_dwell_ms.tap", "--axes", "XYZ")
check("Mach3 G4 P1000 accepted but means 1000 s", rc == 0 and out["dwells"][0]["seconds"] == 1000.0,
      "rc=%s" % rc)

p = subprocess.run(CANON, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
check("canon.py usage error exits 2", p.returncode == 2, p.returncode)

# --- rs274.py ---------------------------------------------------------------
rc, out, err = rs274("arcs_g94.ngc", "--moves-only")
check("rs274 accepts arcs", rc == 0 and
      "ARC_FEED(20.0000, 0.0000, 15.0000, 0.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)" in out,
      "rc=%s %s" % (rc, err))
rc, out, err = rs274("syntax_error.ngc")
check("rs274 error: exit 1, message, line", rc == 1 and "Q word with no" in err and "line 4:" in err,
      "rc=%s %s" % (rc, err))
rc, out, err = rs274("hotwire_g93_xyuv.ngc")
check("rs274 has no U/V/W", rc == 1 and "Bad character 'u' used" in err, "rc=%s %s" % (rc, err))
rc, out, err = rs274("dialect_marlin.gcode")
check("rs274 rejects M104 too", rc == 1 and "Unknown m code used: M104" in err, "rc=%s %s" % (rc, err))

npass = sum(results)
print("%d passed, %d failed" % (npass, len(results) - npass))
sys.exit(0 if npass == len(results) else 1)
