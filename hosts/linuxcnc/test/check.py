"""Runs the LinuxCNC remap (../remap.py, ../mach-vision.ini, ../m283.ngc) through rs274, LinuxCNC's
own interpreter, with the fake mach_vision of this folder, and checks the canonical output.

Usage: check.py --rs274 PATH   (run.sh finds PATH). Exit status 0 when every case passes.

rs274 prints canonical calls before offsets; the check applies them as LinuxCNC's canon does
(emccanon.cc rotate_and_offset_pos): machine = g5x + R(rotation)·(p + g92).
"""

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
HOST = os.path.dirname(HERE)
CALL = re.compile(r"^\s*\d+\s+N\S*\s+([A-Z_0-9]+)\((.*)\)\s*$")
TOLERANCE_IN = 0.0005
# 6 x 4 in part, marks at the corners (the manual's example 4).
MARKS = [(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)]
VAR_PERSISTENT = "3990\t0\n3991\t0\n3992\t0\n"


def ini_text():
    """The shipped snippet, pointed at this checkout."""
    with open(os.path.join(HOST, "mach-vision.ini")) as f:
        return f.read().replace("/opt/mach-vision/linuxcnc", HOST)


PROBE_INI = """[RS274NGC]
REMAP = M281 modalgroup=10 argspec=d python=m281
REMAP = M282 modalgroup=10 python=m282
[PYTHON]
TOPLEVEL = %(dir)s/toplevel.py
PATH_PREPEND = %(dir)s
""" % {"dir": os.path.join(HERE, "probe")}


def run(rs274, program, env_extra, var_text=VAR_PERSISTENT, ini=None):
    """Returns (exit status, canonical calls [(name, args)], other output lines); `ini` defaults
    to the shipped snippet."""
    with tempfile.TemporaryDirectory(prefix="lcnc-remap-") as tmp:
        paths = {name: os.path.join(tmp, name) for name in ("test.ini", "test.tbl", "test.var", "test.ngc")}
        with open(paths["test.ini"], "w") as f:
            f.write(ini if ini is not None else ini_text())
        with open(paths["test.tbl"], "w") as f:
            f.write("T1 P1 ;camera\nT2 P2 ;\n")
        with open(paths["test.var"], "w") as f:
            f.write(var_text)
        with open(paths["test.ngc"], "w") as f:
            f.write(program)
        os.mkdir(os.path.join(tmp, "home"))
        x = os.path.dirname(os.path.dirname(os.path.abspath(rs274)))  # .../usr
        env = dict(os.environ)
        env.update(
            HOME=os.path.join(tmp, "home"),
            LD_LIBRARY_PATH=os.path.join(x, "lib"),
            PYTHONPATH=HERE,  # the fake mach_vision
            PYTHONDONTWRITEBYTECODE="1",
        )
        env.update(env_extra)
        cmd = [rs274, "-g", "-i", paths["test.ini"], "-t", paths["test.tbl"], "-v", paths["test.var"]]
        cmd.append(paths["test.ngc"])
        p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120, cwd=tmp)
    calls, other = [], []
    for line in (p.stdout + p.stderr).splitlines():
        m = CALL.match(line)
        if m:
            calls.append((m.group(1), m.group(2)))
        elif line.strip():
            other.append(line.strip())
    return p.returncode, calls, other


def numbers(args):
    return [float(v) for v in re.split(r"[,\s]+", args.strip()) if v and re.match(r"^-?[\d.]+$", v)]


def traverses(calls):
    """Each STRAIGHT_TRAVERSE's XY in machine coordinates, with the index of the call."""
    g5x, g92, rot, out = (0.0, 0.0), (0.0, 0.0), 0.0, []
    for i, (name, args) in enumerate(calls):
        v = numbers(args)
        if name == "SET_G5X_OFFSET":
            g5x = (v[1], v[2])
        elif name == "SET_G92_OFFSET":
            g92 = (v[0], v[1])
        elif name == "SET_XY_ROTATION":
            rot = v[0]
        elif name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED"):
            c, s = math.cos(math.radians(rot)), math.sin(math.radians(rot))
            px, py = v[0] + g92[0], v[1] + g92[1]
            out.append((i, (g5x[0] + c * px - s * py, g5x[1] + s * px + c * py)))
    return out


def true_part(rot_deg, dx, dy, scale, base_deg=0.0):
    """Where the fake camera's part has mark p, in machine coordinates (G5x origin at zero)."""

    def at(p):
        c, s = math.cos(math.radians(rot_deg)), math.sin(math.radians(rot_deg))
        w = (scale * (c * p[0] - s * p[1]) + dx, scale * (s * p[0] + c * p[1]) + dy)
        cb, sb = math.cos(math.radians(base_deg)), math.sin(math.radians(base_deg))
        return (cb * w[0] - sb * w[1], sb * w[0] + cb * w[1])

    return at


def program(prefix=""):
    lines = ["G20 G90", prefix, "M280 P3"]
    for x, y in MARKS:
        lines += ["G0 X%g Y%g" % (x, y), "M281"]
    lines.append("M282")
    for x, y in MARKS:
        lines.append("G0 X%g Y%g" % (x, y))
    lines += ["M280", "G0 X1 Y1", "M2", ""]
    return "\n".join(line for line in lines if line)


def distinct(points):
    """`points` without consecutive repeats."""
    return [p for k, p in enumerate(points) if k == 0 or p != points[k - 1]]


def messages(calls):
    return [args for name, args in calls if name == "MESSAGE"]


class Check:
    def __init__(self):
        self.failures = 0

    def that(self, case, ok, what):
        print("%s %s: %s" % ("ok  " if ok else "FAIL", case, what))
        self.failures += 0 if ok else 1


def lands(check, case, calls, part, tolerance):
    """Checks that the moves after M282 (the second visit of the marks) reach `part`'s marks."""
    moves = traverses(calls)
    aligned = moves[len(MARKS) : 2 * len(MARKS)]
    worst = max(math.dist(m, part(p)) for (_, m), p in zip(aligned, MARKS))
    check.that(case, worst <= tolerance, "aligned moves land on the part, worst %.6f in (<= %g)" % (worst, tolerance))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rs274", required=True)
    rs274 = ap.parse_args().rs274
    check = Check()
    task = {"MACH_VISION_RS274_AS_TASK": "1"}

    # 0. The canon order this check applies is LinuxCNC's: its interpreter turns a G53 (machine)
    # move into program coordinates with the inverse of g5x + R(rotation)·(p + g92).
    status, calls, other = run(rs274, "G20\nG10 L2 P1 X1 Y2 R30\nG52 X0.1 Y0.2\nG53 G0 X0.7 Y0.5\nM2\n", {})
    machine = traverses(calls)[0][1]
    check.that("canon-order", math.dist(machine, (0.7, 0.5)) < 1e-4, "G53 X0.7 Y0.5 maps back to %s" % (machine,))

    # Probe: what rs274 does with a Python remap (no vision code involved).
    status, calls, other = run(rs274, "G21\nM281 D1\nM282\nG0 X0 Y0\nM2\n", {}, ini=PROBE_INI)
    moves = [m for _, m in traverses(calls)]
    check.that("probe", moves == [(5.0, 6.0), (1.0, 2.0), (7.0, 8.0), (0.0, 0.0)], "self.execute moves %s" % moves)
    check.that("probe", "probe: m281 task=0 words=[('d', 1.0)]" in other, "rs274 runs remaps with self.task == 0")
    check.that(
        "probe",
        "probe: before-yield #5420=5 current_x=1" in other,
        "#5420 still holds the block's start after self.execute; current_x follows",
    )
    check.that(
        "probe",
        "probe: execute-after-yield status=0" in other,
        "rs274 (no motion) even accepts self.execute after the yield; only the task refuses it",
    )

    # 1. Shifted and rotated part: the marks land; the final M280 puts everything back.
    part = {"MACH_VISION_FAKE_PART": "0.7,0.12,-0.08,1"}
    status, calls, other = run(rs274, program(), {**task, **part})
    check.that("rigid", status == 0, "rs274 exit status %d %s" % (status, other[-3:]))
    lands(check, "rigid", calls, true_part(0.7, 0.12, -0.08, 1.0), TOLERANCE_IN)
    rot = [numbers(a)[0] for n, a in calls if n == "SET_XY_ROTATION"]
    g92 = [numbers(a)[:2] for n, a in calls if n == "SET_G92_OFFSET"]
    check.that("rigid", abs(rot[-1]) < 1e-9 and g92[-1] == [0.0, 0.0], "M280 restores rotation 0 and G52 0")
    check.that("rigid", sum("M281: dot" in m for m in messages(calls)) == 4, "four captures reported")

    # 2. An operator rotation of 10° on G54 is the base: kept under the alignment, restored after.
    status, calls, other = run(rs274, program("G10 L2 P1 R10"), {**task, **part})
    lands(check, "base-rotation", calls, true_part(0.7, 0.12, -0.08, 1.0, base_deg=10.0), TOLERANCE_IN)
    rot = [numbers(a)[0] for n, a in calls if n == "SET_XY_ROTATION"]
    check.that("base-rotation", abs(rot[-1] - 10.0) < 1e-9, "M280 restores the 10° rotation (got %s)" % rot[-1])

    # 3. A part printed 0.1 % large, gate 2 %: the rigid part is applied, the scale reported.
    big = {"MACH_VISION_FAKE_PART": "0.7,0.12,-0.08,1.001"}
    status, calls, other = run(rs274, program(), {**task, **big})
    check.that("scaled-in-gate", status == 0, "runs to the end")
    check.that(
        "scaled-in-gate",
        any("ignored scale 1.001000" in m for m in messages(calls)),
        "the ignored scale is reported",
    )
    lands(check, "scaled-in-gate", calls, true_part(0.7, 0.12, -0.08, 1.001), 0.001 * math.hypot(3, 2) + 1e-4)

    # 4. The same part with a 0.05 % gate: refused, nothing rotated.
    status, calls, other = run(rs274, program(), {**task, **big, "MACH_VISION_FAKE_SCALE_GATE": "0.05"})
    text = " ".join(other)
    check.that("scaled-refused", "LinuxCNC cannot scale" in text, "refused with the message: %s" % text[:160])
    check.that(
        "scaled-refused",
        all(numbers(a)[0] == 0.0 for n, a in calls if n == "SET_XY_ROTATION"),
        "no rotation was set",
    )
    check.that("scaled-refused", len(traverses(calls)) == len(MARKS), "the program stopped at M282")

    # 5. NG at the third capture: the program stops there with the message.
    status, calls, other = run(rs274, program(), {**task, **part, "MACH_VISION_FAKE_NG": "3"})
    text = " ".join(other)
    check.that("ng", "M281: camera answered NG" in text, "stopped with the message: %s" % text[:160])
    check.that("ng", len(traverses(calls)) == 3, "no motion after the NG capture (%d moves)" % len(traverses(calls)))

    # 6. Preview (rs274 as it is: self.task == 0): no capture, nothing that moves the preview.
    status, calls, other = run(rs274, program(), part)
    check.that("preview", status == 0, "runs to the end")
    moves = [m for _, m in traverses(calls)]
    nominal = MARKS + MARKS + [(1.0, 1.0)]
    check.that("preview", moves == nominal, "moves are the program's own")
    check.that("preview", sum("preview" in m for m in messages(calls)) == 7, "each vision M-code reports")

    # 7. M283 C1: the walk moves to each of 9 points and captures there.
    walk = "G20 G90\nG0 X2 Y3\nM283 C1\nG0 X0 Y0\nM2\n"
    status, calls, other = run(rs274, walk, {**task, **part})
    moves = [m for _, m in traverses(calls)]
    rotary = [numbers(a)[5] for n, a in calls if n == "STRAIGHT_TRAVERSE"]
    no_c = bool(rotary) and max(map(abs, rotary)) == 0.0
    check.that("m283", no_c, "C1 is the sheet, not a C-axis move (C: %s)" % sorted(set(rotary)))
    # Repeats are zero-length moves: the walk's first point is where the program stood, and the
    # M283 block's own motion ends where the walk ended.
    moves = distinct(moves)
    want = distinct([(2.0, 3.0)] + [(2.0 + 0.5 * i, 3.0 + 0.5 * j) for j in range(3) for i in range(3)] + [(0.0, 0.0)])
    same = len(moves) == len(want) and all(math.dist(a, b) < 1e-4 for a, b in zip(moves, want))
    check.that("m283", status == 0 and same, "walk moves %s" % moves)
    check.that("m283", any("M283: 9 captures" in m for m in messages(calls)), "the epilog saw 9 captures")

    print("%d failure(s)" % check.failures)
    return 1 if check.failures else 0


if __name__ == "__main__":
    sys.exit(main())
