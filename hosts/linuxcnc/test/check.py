"""Runs the LinuxCNC remap (../remap.py, ../mach-vision.ini, ../m283.ngc, ../examples/) through
rs274, LinuxCNC's own interpreter, with the real `mach_vision` module (vision-py, built with the
`sim` feature) on a simulated camera, and checks the canonical output against the simulator's
truth.

Usage: check.py --rs274 PATH --module DIR   (run.sh builds DIR/mach_vision.abi3.so and finds
PATH). Exit status 0 when every case passes.

rs274 prints canonical calls before offsets; the check applies them as LinuxCNC's canon does
(canon.py): machine = g5x + R(rotation)·(p + g92) + tool.
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
import urllib.request

from canon import machine_xy

HERE = os.path.dirname(os.path.abspath(__file__))
HOST = os.path.dirname(HERE)
CALL = re.compile(r"^\s*\d+\s+N\S*\s+([A-Z_0-9]+)\((.*)\)\s*$")
TOLERANCE_IN = 0.0005
EXAMPLE_4 = os.path.join(HOST, "examples", "04-rectangle-fit.ngc")
# The manual's example 4: a 6 x 4 in part, marks at the corners.
MARKS = [(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)]
# A shifted and rotated part (no scale), and the same printed 0.1 % large.
RIGID = {"rotation_deg": 0.7, "shift": [0.12, -0.08], "scale": [1.0, 1.0]}
LARGE = {**RIGID, "scale": [1.001, 1.001]}


def ini_text(toplevel):
    """The shipped snippet, pointed at this checkout, with `toplevel` as [PYTHON] TOPLEVEL."""
    with open(os.path.join(HOST, "mach-vision.ini")) as f:
        text = f.read().replace("/usr/lib/mach-vision/linuxcnc", HOST)
    return re.sub(r"(?m)^TOPLEVEL = .*$", "TOPLEVEL = " + toplevel, text)


PROBE_INI = """[RS274NGC]
REMAP = M281 modalgroup=10 argspec=d python=m281
REMAP = M282 modalgroup=10 python=m282
[PYTHON]
TOPLEVEL = %(dir)s/toplevel.py
PATH_PREPEND = %(dir)s
""" % {"dir": os.path.join(HERE, "probe")}


class Rig:
    """How rs274 is run: the interpreter, the module's folder, and the controller's set-up for
    the simulated world (G54, the camera tool's table offset)."""

    def __init__(self, rs274, module_dir, module):
        self.rs274 = rs274
        self.module_dir = module_dir
        self.setup = simulated(module, {}).setup()
        # The alignment's persistent parameters: the var file must list them.
        self.persistent = module.PERSISTENT_PARAMS

    def var_text(self):
        g54 = self.setup["work_offset"]
        lines = ["%d\t0" % n for n in self.persistent] + ["5220\t1", "5221\t%.9f" % g54[0], "5222\t%.9f" % g54[1]]
        return "\n".join(lines) + "\n"

    def tool_table(self, camera_error):
        x, y = self.setup["camera_table_offset"]
        x, y = x + camera_error[0], y + camera_error[1]
        return "T1 P1 ;cutter\nT%d P2 X%.9f Y%.9f ;camera\n" % (self.setup["camera_tool"], x, y)

    def run(self, program, sim=None, task=True, ini=None, camera_error=(0.0, 0.0)):
        """Runs `program`; returns (exit status, canonical calls [(name, args)], other output
        lines). `sim`: Session.simulated's arguments; `task`: rs274 counts as the task (else it
        is a preview); `ini` replaces the shipped snippet; `camera_error` is added to the
        camera tool's true table offset (X, Y, inches)."""
        with tempfile.TemporaryDirectory(prefix="lcnc-remap-") as tmp:
            files = {
                "test.ini": ini if ini is not None else ini_text(os.path.join(HERE, "sim_toplevel.py")),
                "test.tbl": self.tool_table(camera_error),
                "test.var": self.var_text(),
                "test.ngc": program,
            }
            for name, text in files.items():
                with open(os.path.join(tmp, name), "w") as f:
                    f.write(text)
            os.mkdir(os.path.join(tmp, "home"))
            usr = os.path.dirname(os.path.dirname(os.path.abspath(self.rs274)))
            env = dict(os.environ)
            env.update(
                HOME=os.path.join(tmp, "home"),
                LD_LIBRARY_PATH=os.path.join(usr, "lib"),
                PYTHONPATH=os.pathsep.join([self.module_dir, HERE]),
                PYTHONDONTWRITEBYTECODE="1",
                MACH_VISION_SIM=json.dumps(sim or {}),
            )
            env.pop("MACH_VISION_RS274_AS_TASK", None)
            if task:
                env["MACH_VISION_RS274_AS_TASK"] = "1"
            cmd = [self.rs274, "-g", "-i", "test.ini", "-t", "test.tbl", "-v", "test.var", "test.ngc"]
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


def motions(calls):
    """Every point the machine is sent to: [(call index, programmed XY, machine XY)]. Moves give
    their end point; arcs their end point and centre."""
    g5x, g92, rot, tool, out = (0.0, 0.0), (0.0, 0.0), 0.0, (0.0, 0.0), []
    for i, (name, args) in enumerate(calls):
        v = numbers(args)
        if name == "SET_G5X_OFFSET":
            g5x = (v[1], v[2])
        elif name == "SET_G92_OFFSET":
            g92 = (v[0], v[1])
        elif name == "SET_XY_ROTATION":
            rot = v[0]
        elif name == "USE_TOOL_LENGTH_OFFSET":
            tool = (v[0], v[1])
        elif name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "ARC_FEED"):
            points = [(v[0], v[1])] + ([(v[2], v[3])] if name == "ARC_FEED" else [])
            out += [(i, p, machine_xy(g5x, rot, p, g92, tool)) for p in points]
    return out


def traverses(calls):
    """The programmed XY of every STRAIGHT_TRAVERSE."""
    return [p for i, p, _ in motions(calls) if calls[i][0] == "STRAIGHT_TRAVERSE"]


def messages(calls):
    return [args for name, args in calls if name == "MESSAGE"]


def aligned(calls):
    """The motions under M282's alignment: after its report, until the offsets change again."""
    start = next((i for i, (n, a) in enumerate(calls) if n == "MESSAGE" and "M282:" in a), None)
    if start is None:
        return []
    end = next((i for i, (n, _) in enumerate(calls) if i > start and n in ("SET_G92_OFFSET", "SET_XY_ROTATION")), len(calls))
    return [(p, m) for i, p, m in motions(calls) if start < i < end]


class Check:
    def __init__(self):
        self.failures = 0

    def that(self, case, ok, what):
        print("%s %s: %s" % ("ok  " if ok else "FAIL", case, what))
        self.failures += 0 if ok else 1


def lands(check, case, calls, truth, tolerance):
    """Checks that every motion under the alignment reaches the true part: programmed point p at
    `truth.true_point(p)` (machine coordinates, the simulator's truth)."""
    moves = aligned(calls)
    worst = max((math.dist(m, truth.true_point(*p)) for p, m in moves), default=math.inf)
    what = "%d aligned points land on the true part, worst %.6f in (<= %g)" % (len(moves), worst, tolerance)
    check.that(case, bool(moves) and worst <= tolerance, what)
    return worst


def example_4(replace=None):
    """hosts/linuxcnc/examples/04-rectangle-fit.ngc, with `replace` {old line start: new line}."""
    with open(EXAMPLE_4) as f:
        lines = f.read().splitlines()
    for old, new in (replace or {}).items():
        at = [k for k, line in enumerate(lines) if line.startswith(old)]
        assert at, "no line %r in example 4" % old
        lines[at[0]] = new
    return "\n".join(lines) + "\n"


def program_moves(program):
    """The XY of each `G0 X… Y…` line of `program`."""
    found = re.findall(r"(?m)^G0 X(-?[\d.]+) Y(-?[\d.]+)", program)
    return [(float(x), float(y)) for x, y in found]


def simulated(module, sim):
    """An in-process simulated session (the truth of the world `sim` describes)."""
    pairs = {k: tuple(v) for k, v in sim.items() if k in ("shift", "scale")}
    return module.Session.simulated(**{**sim, **pairs})


def full_runs(check, rig, module):
    """Example 4 for LinuxCNC, whole, through rs274."""
    for camera in ("sim", "keyence"):
        case = "example-4-%s" % camera
        sim = {**RIGID, "camera": camera}
        status, calls, other = rig.run(example_4(), sim)
        check.that(case, status == 0, "rs274 exit status %d %s" % (status, other[-3:]))
        check.that(case, sum("M281: mark captured" in m for m in messages(calls)) == 4, "four captures reported")
        worst = lands(check, case, calls, simulated(module, sim), TOLERANCE_IN)
        print("     landing error, %s camera: %.6f in" % (camera, worst))
        rot = [numbers(a)[0] for n, a in calls if n == "SET_XY_ROTATION"]
        g92 = [numbers(a)[:2] for n, a in calls if n == "SET_G92_OFFSET"]
        turned = any(abs(r) > 0.1 for r in rot) and any(abs(v) > 0.01 for v in sum(g92, []))
        restored = abs(rot[-1]) < 1e-9 and g92[-1] == [0.0, 0.0]
        check.that(case, turned and restored, "M282 set a rotation and G52, the final M280 restores 0 and 0")

        # NG: the third capture looks at bare table; the program stops there, with the message.
        case = "ng-%s" % camera
        ng = example_4({"G0 X6.0 Y4.0": "G0 X20.0 Y20.0"})
        status, calls, other = rig.run(ng, sim)
        text = " ".join(other)
        check.that(case, status != 0 and "M281: " in text and "no mark" in text, "stopped with: %s" % text[:200])
        # The captures before it may re-centre (moves over the mark and back); the last move is
        # the program's to the bare table.
        moves = traverses(calls)
        check.that(case, moves[-1:] == [(20.0, 20.0)], "no motion after the NG capture (last move to %s)" % (moves[-1:],))

    # An operator's 10° G54 rotation (the part lies turned with it): kept under the alignment,
    # restored by M280.
    case = "base-rotation"
    sim = {**RIGID, "rotation_deg": 10.7}
    status, calls, other = rig.run(example_4({"G54": "G54 G10 L2 P1 R10"}), sim)
    check.that(case, status == 0, "rs274 exit status %d %s" % (status, other[-3:]))
    lands(check, case, calls, simulated(module, sim), TOLERANCE_IN)
    rot = [numbers(a)[0] for n, a in calls if n == "SET_XY_ROTATION"]
    check.that(case, abs(rot[-1] - 10.0) < 1e-9, "M280 restores the 10° rotation (got %s)" % rot[-1])

    # A part printed 0.1 % large, under the default 2 % gate: the rigid part is applied, the
    # ignored scale reported; the points are off by the scale alone.
    case = "scaled-in-gate"
    status, calls, other = rig.run(example_4(), LARGE)
    check.that(case, status == 0, "runs to the end")
    report = [m for m in messages(calls) if "M282:" in m]
    scales = [float(v) for m in report for v in re.findall(r"scale X ([\d.]+) / Y ([\d.]+) ignored", m)[0]]
    ignored = len(scales) == 2 and all(abs(v - 1.001) < 1e-4 for v in scales)
    check.that(case, ignored, "the ignored scale (1.001 and noise) is reported: %s" % report)
    # Off by the ignored scale times the distance from the centroid, plus the landing tolerance.
    lands(check, case, calls, simulated(module, LARGE), 0.001 * math.hypot(3, 2) + TOLERANCE_IN)

    # The same part under a 0.05 % gate: refused, nothing rotated, the program stops at M282.
    case = "scaled-refused"
    sim = {**LARGE, "params": {"VisionFitMaxScaleDev": 0.05}}
    status, calls, other = rig.run(example_4(), sim)
    text = " ".join(other)
    check.that(case, status != 0 and "M282: " in text and "scale" in text, "refused with: %s" % text[:200])
    turned = [numbers(a)[0] for n, a in calls if n == "SET_XY_ROTATION"]
    check.that(case, all(r == 0.0 for r in turned), "no rotation was set")
    moves = traverses(calls)
    stopped = moves[-1:] == [MARKS[-1]] and (2.0, 1.0) not in moves
    check.that(case, stopped, "the program stopped at M282 (last move to %s)" % (moves[-1:],))

    # Re-centring under an arc mode: G2 cannot be set back by a bare word after the move, so
    # M281 refuses to move (the mark is read ~30 px off centre) and nothing moves after it.
    case = "recentre-under-arc"
    program = "G90 G20 G17\nG54\nT98 M6 G43\nG0 X5.9 Y0\nG2 X6.0 Y0 I0.05 J0 F30\nM281\nG0 X0 Y0\nM2\n"
    status, calls, other = rig.run(program, RIGID)
    said = [line for line in other if line.startswith("M281: ") and "cannot move to re-centre under G2" in line]
    check.that(case, status != 0 and bool(said), "stopped with: %s" % other[-2:])
    check.that(case, traverses(calls)[-1:] == [(5.9, 0.0)], "nothing moved after it: %s" % traverses(calls))

    # A word M280 refuses: the program stops with the M-code's own message, named once.
    case = "bad-word"
    status, calls, other = rig.run(example_4({"M280 P4": "M280 P5"}), RIGID)
    said = [line for line in other if "P5" in line]
    once = any(line.startswith("M280 P5 is invalid") for line in said) and not any("M280: M280" in m for m in said)
    check.that(case, status != 0 and once, "stopped with: %s" % said)
    check.that(case, traverses(calls) == [], "nothing moved")

    # Preview (rs274 as it is: self.task == 0): no capture, nothing that moves the preview.
    case = "preview"
    program = example_4()
    status, calls, other = rig.run(program, RIGID, task=False)
    check.that(case, status == 0, "runs to the end")
    # Repeats are the Z moves (G0 Z0.25) where the program stands.
    moves = [p for k, p in enumerate(traverses(calls)) if k == 0 or p != traverses(calls)[k - 1]]
    check.that(case, moves == program_moves(program), "the traverses are the program's own: %s" % moves)
    vision = len(re.findall(r"(?m)^M28[0-4]", program))
    check.that(case, sum("preview" in m for m in messages(calls)) == vision, "each of the %d vision M-codes reports" % vision)


def calibrations(check, rig, module):
    """M283 through m283.ngc: from K never calibrated and a camera offset 0.05 in off in the
    tool table, the sheet walk (C1) calibrates well enough for example 4 to land; the quick
    calibration (Q) on one mark completes."""
    part = {"rotation_deg": 0.7, "shift": [0.0, 0.0], "scale": [1.0, 1.0]}
    # Over sheet 1's first dot (the built-in world's sheet lies at work zero), walk, re-apply the
    # camera offset M283 wrote, then example 4 from its M280 on.
    lines = example_4().splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith("M280"))
    head = ["G90 G20 G17", "G54", "T98 M6 G43", "G0 X-2.5 Y-4.0", "M283 P1", "T98 M6 G43"]
    program = "\n".join(head + lines[start:]) + "\n"
    # rs274 has no motion to settle from: no dwell after each move.
    sim = {**part, "calibrated": False, "params": {"VisionTriggerSettleSec": 0}}
    status, calls, other = rig.run(program, sim, camera_error=(0.04, -0.03))
    case = "m283-sheet"
    check.that(case, status == 0, "rs274 exit status %d %s" % (status, other[-3:]))
    said = [m for m in messages(calls) if "M283:" in m]
    check.that(case, any("calibration done and saved" in m for m in said), "M283 reports: %s" % said)
    # The walk's moves: the traverses after the first (over dot 1) up to M283's report.
    report = next((i for i, (n, a) in enumerate(calls) if n == "MESSAGE" and "M283:" in a), 0)
    walk = [p for i, p, _ in motions(calls) if calls[i][0] == "STRAIGHT_TRAVERSE" and i < report][1:]
    check.that(case, len(set(walk)) >= 5, "the walk moved to %d points (%d distinct)" % (len(walk), len(set(walk))))
    # The calibration lift (VisionCalibrationLift, 0.25 in): m283.ngc rose and came back down.
    zs = [numbers(calls[i][1])[2] for i, _, _ in motions(calls) if calls[i][0] == "STRAIGHT_TRAVERSE" and i < report]
    rose = max(zs) - min(zs) if zs else 0.0
    check.that(case, abs(rose - 0.25) < 1e-6 and abs(zs[-1] - zs[0]) < 1e-9, "the lift rose %.6f in and came back to Z %s" % (rose, zs[-1:]))
    worst = lands(check, case, calls, simulated(module, sim), TOLERANCE_IN)
    print("     landing error after calibrating: %.6f in" % worst)

    # The walk over bare table: the first capture finds no mark, the program stops there.
    case = "m283-ng"
    program = "G90 G20 G17\nG54\nT98 M6 G43\nG0 X20.0 Y20.0\nM283 P1\nG0 X0 Y0\nM2\n"
    status, calls, other = rig.run(program, sim)
    text = " ".join(other)
    check.that(case, status != 0 and "M283: " in text, "stopped with: %s" % text[:200])
    check.that(case, (0.0, 0.0) not in traverses(calls), "the program ran nothing after the walk")

    # The walk leaves the program's modes as they were: after M283 in G91 G1, a bare X0.5 is an
    # incremental feed move (m283.ngc: M73, and the motion mode set back).
    case = "m283-modes"
    program = "G90 G20 G17\nG54\nT98 M6 G43\nG0 X-2.5 Y-4.0\nG91 G1 F30\nM283 P1\nX0.5\nM2\n"
    status, calls, other = rig.run(program, {**sim, "calibrated": True})
    last = [(n, p) for i, p, _ in motions(calls) for n in [calls[i][0]] if n in ("STRAIGHT_FEED", "STRAIGHT_TRAVERSE")]
    check.that(case, status == 0 and len(last) >= 2, "rs274 exit status %d %s" % (status, other[-3:]))
    if len(last) >= 2:
        (kind, end), (_, before) = last[-1], last[-2]
        moved = (round(end[0] - before[0], 6), round(end[1] - before[1], 6))
        check.that(case, kind == "STRAIGHT_FEED" and moved == (0.5, 0.0), "X0.5 after M283 is %s by %s" % (kind, moved))

    # The manual's C word: LinuxCNC's task refuses it on an XYZ machine before the remap; where
    # it reaches the remap (rs274, a machine with a C axis) the prolog names the replacement.
    # A P that is no sheet number, and P with Q, are refused in LinuxCNC's words.
    for case, line, says in (
        ("m283-c-word", "M283 C1", "M283 C1: on LinuxCNC the sheet number is P: write M283 P1"),
        ("m283-bad-p", "M283 P1.5", "M283 P1.5 is invalid: P is a calibration sheet number (P1)"),
        ("m283-p-and-q", "M283 P1 Q0.5", "M283 takes one of Qd (quick, dot diameter d) or Pn (sheet n), not both"),
    ):
        program = "G90 G20 G17\nG54\nT98 M6 G43\nG0 X-2.5 Y-4.0\n%s\nG0 X0 Y0\nM2\n" % line
        status, calls, other = rig.run(program, sim)
        check.that(case, status != 0 and any(says in o for o in other), "stopped with: %s" % other[-2:])
        check.that(case, (0.0, 0.0) not in traverses(calls), "nothing ran after it")

    case = "m283-quick"
    program = "G90 G20 G17\nG54\nT98 M6 G43\nG0 X6.0 Y0\nM283 Q0.5\nM2\n"
    status, calls, other = rig.run(program, sim)
    said = [m for m in messages(calls) if "M283:" in m]
    check.that(case, status == 0 and any("calibration done" in m for m in said), "%d %s %s" % (status, said, other[-2:]))
    check.that(case, len(traverses(calls)) >= 3, "the axis detect moved (%d moves)" % len(traverses(calls)))


def panel_page(cli, profile):
    """What `mach-vision panel --profile PROFILE` serves as /state.json once it has read the
    folder (its first line names the address), or {} when it shows nothing within 30 s."""
    child = subprocess.Popen([cli, "panel", "--profile", profile, "--listen", "127.0.0.1:0"],
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        line = child.stdout.readline()
        if "http://" not in line:
            return {}
        url = "http://" + line.split("http://")[1].split()[0].rstrip("/") + "/state.json"
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            page = json.load(urllib.request.urlopen(url, timeout=10))
            if "(state " in page.get("source", ""):
                return page
            time.sleep(0.2)
        return {}
    finally:
        child.kill()
        child.wait()


def panel(check, rig, module, cli):
    """A session on a profile publishes beside it, for the panel beside a real controller:
    after M283 P1 and example 4 through rs274, `P.panel/state.json` holds the fit, its status
    and a sequence number that the next run raises; in process, `Session.param` reads the same
    parameters and refuses an unknown name."""
    with tempfile.TemporaryDirectory(prefix="lcnc-panel-") as tmp:
        profile = os.path.join(tmp, "mill.toml")
        with open(profile, "w") as f:
            f.write('[vision]\nVisionEnabled = true\nVisionDriver = "Sim"\nVisionCameraToolNumber = %d\n'
                    % rig.setup["camera_tool"])
        lines = example_4().splitlines()
        start = next(k for k, line in enumerate(lines) if line.startswith("M280"))
        # Up to M282 and the cut: the example's own last M280 (cancel) starts a new run.
        end = max(k for k, line in enumerate(lines) if line.startswith("M280"))
        head = ["G90 G20 G17", "G54", "T98 M6 G43", "G0 X-2.5 Y-4.0", "M283 P1", "T98 M6 G43"]
        program = "\n".join(head + lines[start:end] + ["M2"]) + "\n"
        sim = {"profile": profile, "params": {"VisionTriggerSettleSec": 0}}
        state_path = os.path.join(tmp, "mill.panel", "state.json")

        def published(case, program, status_expected=0):
            """Runs `program` through rs274; the panel state it left, or None."""
            status, calls, other = rig.run(program, sim)
            check.that(case, status == status_expected, "rs274 exit status %d %s" % (status, other[-3:]))
            try:
                with open(state_path) as f:
                    return json.load(f)
            except (OSError, ValueError) as e:
                check.that(case, False, "no panel state: %s" % e)
                return None

        state = published("panel-fit", program)
        if state is None:
            return
        page = panel_page(cli, profile)
        check.that("panel-page", page.get("source", "").endswith("(state %d)" % state["seq"]),
                   "`mach-vision panel --profile` shows the folder's state %d: %r" % (state["seq"], page.get("source")))
        call = page.get("call") or {}
        check.that("panel-page", call.get("mcode") == 282 and call.get("ok") is True and bool(call.get("gcode")),
                   "the page's last call is the fit, with the G-code it ran: %s" % call)
        last, telemetry = state.get("last") or {}, state.get("telemetry", {})
        check.that("panel-fit", last.get("mcode") == 282 and last.get("ok") is True,
                   "the last call is M282's fit: %s" % {k: last.get(k) for k in ("mcode", "ok", "message")})
        check.that("panel-fit", telemetry.get("VisionLastStatus") == "OK" and len(state.get("dots", [])) == 4,
                   "status %r, %d dots" % (telemetry.get("VisionLastStatus"), len(state.get("dots", []))))
        # The next session on the profile (a new rs274) goes on from the folder's number. A new
        # rs274 starts from the tool table file, without the camera offset M283 measured, so its
        # M280 is refused (the offset changed since K was calibrated): a refusal is published too.
        again = published("panel-seq", "G90 G20 G17\nG54\nT98 M6 G43\nM280\nG0 X1.0 Y1.0\nM2\n", 1)
        if again is not None:
            seqs = (state.get("seq", 0), again.get("seq", 0))
            check.that("panel-seq", seqs[1] > seqs[0] > 0, "the next run's sequence numbers: %s" % (seqs,))
            refusal = again.get("last") or {}
            check.that("panel-seq", refusal.get("mcode") == 280 and refusal.get("ok") is False
                       and "offset changed" in (refusal.get("message") or ""),
                       "the refusal published: %s" % {k: refusal.get(k) for k in ("mcode", "ok", "message")})

        session = module.Session.simulated(profile=profile)
        k11 = session.param("visioncal_k11")
        check.that("panel-param", k11 == state["params"].get("VisionCal_K11") and k11 != 0.0,
                   "Session.param reads the calibration M283 saved: %r" % k11)
        check.that("panel-param", session.param("VisionEnabled") is True and session.param("VisionDriver") == "Sim",
                   "Session.param's types")
        try:
            session.param("VisionNoSuch")
            message = None
        except module.VisionError as e:
            message = str(e)
        check.that("panel-param", message is not None and "VisionNoSuch" in message, "an unknown name: %r" % message)
        # Its publisher writes into the folder until the session goes: before the folder does.
        del session


def probes(check, rig):
    """What rs274 itself does, with no vision code."""
    # The canon order this check applies is LinuxCNC's: its interpreter turns a G53 (machine)
    # move into program coordinates with the inverse of g5x + R(rotation)·(p + g92).
    program = "G20\nG10 L2 P1 X1 Y2 R30\nG52 X0.1 Y0.2\nG53 G0 X0.7 Y0.5\nM2\n"
    status, calls, other = rig.run(program, ini=PROBE_INI)
    machine = [m for i, p, m in motions(calls)][0]
    check.that("canon-order", math.dist(machine, (0.7, 0.5)) < 1e-4, "G53 X0.7 Y0.5 maps back to %s" % (machine,))

    status, calls, other = rig.run("G21\nM281 D1\nM282\nG0 X0 Y0\nM2\n", ini=PROBE_INI)
    moves = traverses(calls)
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
        "rs274 (no motion) accepts self.execute after the yield, as 2.9's task does (task/: re-centring)",
    )


class BareHost:
    """A Host with no interpreter behind it, for the module's own error paths."""

    def __init__(self, **broken):
        self.broken = broken
        self.executed = []

    def __getattribute__(self, name):
        broken = object.__getattribute__(self, "broken")
        if name in broken:
            return broken[name]
        return object.__getattribute__(self, name)

    def program_position(self):
        return (0.0, 0.0)

    def machine_position(self):
        return (0.0, 0.0)

    def xy_rotation_deg(self):
        return 0.0

    def g92_offset(self):
        return (0.0, 0.0)

    def metric(self):
        return False

    def execute(self, line):
        self.executed.append(line)

    def tool(self):
        return 98

    def tool_offset(self, tool):
        return (0.0, 0.0)

    def set_tool_offset(self, tool, x, y):
        pass

    def pound(self, number):
        return 0.0

    def set_pound(self, number, value):
        pass

    def dwell(self, seconds):
        pass

    def message(self, text):
        pass


def module_errors(check, module):
    """The module's refusals, in process: bad words and a failing Host become VisionError with
    the operator's message, never a crash."""
    session = simulated(module, {})

    def refusal(words, host):
        try:
            session.call(280, words, host)
        except module.VisionError as e:
            return str(e)
        return None

    cases = [
        ({"p": "four"}, BareHost(), "word P is 'four', not a number"),
        ({"pq": 4.0}, BareHost(), 'word "pq" is not a letter'),
        ({"p": True}, BareHost(), "word P is True, not a number"),
        ({"p": float("nan")}, BareHost(), "M280 P word is not a finite number"),
        ({"q": 1.0}, BareHost(), "M280 does not take a Q word"),
        ({"p": 5.0}, BareHost(), "M280 P5 is invalid"),
        ({}, BareHost(tool=lambda: "T98"), "Host.tool() returned 'T98', not a tool number"),
        ({}, BareHost(pound=lambda n: {}[n]), "Host.pound(): KeyError: "),
        ({}, BareHost(execute=lambda line: 1 / 0), "Host.execute(): ZeroDivisionError"),
        ({}, BareHost(execute=lambda line: (_ for _ in ()).throw(module.VisionError("refused %s" % line))), "refused G"),
    ]
    for words, host, says in cases:
        message = refusal(words, host)
        check.that("module-errors", message is not None and says in message, "%r -> %r" % (words, message))
    check.that("module-errors", refusal({"p": 4.0}, BareHost()) is None, "a good M280 P4 runs")
    try:
        module.Session(None)
        message = None
    except module.VisionError as e:
        message = str(e)
    check.that("module-errors", message is not None and "MACH_VISION_PROFILE" in message, "no profile -> %r" % message)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rs274", required=True)
    ap.add_argument("--module", required=True, help="the folder holding mach_vision.abi3.so")
    ap.add_argument("--cli", required=True, help="the mach-vision executable (its `panel --profile`)")
    args = ap.parse_args()
    sys.path.insert(0, args.module)
    import mach_vision

    check = Check()
    rig = Rig(args.rs274, args.module, mach_vision)
    probes(check, rig)
    module_errors(check, mach_vision)
    full_runs(check, rig, mach_vision)
    calibrations(check, rig, mach_vision)
    panel(check, rig, mach_vision, args.cli)
    print("%d failure(s)" % check.failures)
    return 1 if check.failures else 0


if __name__ == "__main__":
    sys.exit(main())
