"""Runs the vision M-codes in LinuxCNC's real task, headless: `linuxcnc -r` with milltask,
motion (uspace, not real-time) and HAL from the package's sim configs, on a trivkins XYZ inch
mill and an XYZ millimetre mill, two LinuxCNCs per machine, all at once. The shipped remaps (remap.py, oword.py, m283.ngc and
the INI lines of mach-vision.ini, from --host) and the real `mach_vision` module (built with
the `sim` feature, from --module) run on a simulated camera; driver.py is the DISPLAY that runs
the cases one after another in one LinuxCNC start per machine, and this script checks what the
machine did against the simulator's truth.

Usage: run.py --module DIR [--host DIR] [--work DIR] [--only NAME,...]
Exit status 0 when every check passes.

Every length the checks compare is in inches; `stat` reports machine units.
"""

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
TEST = os.path.dirname(HERE)
REPO_HOST = os.path.dirname(TEST)
TOLERANCE_IN = 0.0005
# A capture must be taken where the machine stands: the simulated camera is parked where the
# interpreter says, stat says where motion put the machine.
CAPTURE_TOLERANCE_IN = 1e-6
RIGID = {"rotation_deg": 0.7, "shift": [0.12, -0.08], "scale": [1.0, 1.0]}
LARGE = {**RIGID, "scale": [1.001, 1.001]}
UNCALIBRATED = {"rotation_deg": 0.7, "shift": [0.0, 0.0], "scale": [1.0, 1.0], "calibrated": False}
# The cut of example 4 (after M282, tool 1): move ends, arc ends and centres, inches.
CUT = [(2.0, 1.0), (4.0, 1.0), (4.0, 3.0), (4.0, 2.0), (2.0, 3.0), (2.0, 1.0), (2.0, 2.0)]

# Two LinuxCNCs cannot share a machine: NML and HAL use fixed System V shared-memory keys, the
# `linuxcnc` script keeps /tmp/linuxcnc.lock and, at exit, stops milltask and linuxcncsvr by
# name. Each runs in its own IPC, PID and mount namespaces, with a private /tmp.
# A folder the run needs that lies under /tmp (a clone in /tmp, as a CI may make) would vanish
# under the private /tmp: the current directory, which keeps pointing at the real folder after
# the mount, is bound back at its own path.
ISOLATE = [
    "unshare", "--ipc", "--pid", "--fork", "--mount-proc", "sh", "-c",
    'here="$(pwd -P)"; keep="${MV_KEEP:-$here}"; cd "$keep" && mount -t tmpfs tmpfs /tmp && '
    'case "$keep/" in /tmp/*) mkdir -p "$keep" && mount --no-canonicalize --bind . "$keep" ;; esac && cd "$here" && exec "$@"',
    "sh",
]

# The cases of one LinuxCNC start (they run one after another): two starts per machine, at once.
ALIGN = ["example-4", "ng", "base-rotation", "scaled-in-gate", "scaled-refused", "c-word", "recentre-modes"]
CALIBRATE = ["sheet", "sheet-then-example-4", "quick"]
# name: (LINEAR_UNITS, machine units per inch, TOPLEVEL, the cases it runs)
MACHINES = {
    "inch": ("inch", 1.0, "test", ALIGN),
    "inch-cal": ("inch", 1.0, "test", CALIBRATE),
    "mm": ("mm", 25.4, "test", ALIGN),
    "mm-cal": ("mm", 25.4, "test", CALIBRATE),
    # From an installed package (--installed): its remaps, INI lines and example 4, with the
    # tests' module (the simulated camera) ahead of the installed one on the path ...
    "installed": ("inch", 1.0, "test", ["example-4"]),
    # ... and its own TOPLEVEL and module, nothing of the tests', on the installed CLI's
    # emulated Keyence camera over TCP.
    "shipped": ("inch", 1.0, "shipped", ["shipped-m284"]),
}


def ini_text(machine, run_dir, host, units, per_inch, toplevel):
    """The machine's INI: a trivkins XYZ mill with the package's sim HAL, fast limits (the
    cases run in seconds), and the shipped mach-vision.ini lines pointed at `host`, the test
    TOPLEVEL in place of the shipped one."""
    v, a, lim = 30 * per_inch, 300 * per_inch, 50 * per_inch
    axes = "".join(
        "[AXIS_%s]\nMAX_VELOCITY = %g\nMAX_ACCELERATION = %g\nMIN_LIMIT = %g\nMAX_LIMIT = %g\n" % (ax, v, a, -lim, lim)
        for ax in "XYZ"
    )
    joints = "".join(
        "[JOINT_%d]\nTYPE = LINEAR\nHOME = 0\nMAX_VELOCITY = %g\nMAX_ACCELERATION = %g\nFERROR = %g\n"
        "MIN_FERROR = %g\nMIN_LIMIT = %g\nMAX_LIMIT = %g\nHOME_SEARCH_VEL = 0\nHOME_LATCH_VEL = 0\n"
        "HOME_SEQUENCE = 0\n" % (j, v * 1.2, a * 1.2, 0.05 * per_inch, 0.01 * per_inch, -lim, lim)
        for j in range(3)
    )
    with open(os.path.join(host, "mach-vision.ini")) as f:
        shipped = f.read().replace("/usr/lib/mach-vision/linuxcnc", host)
    sections = {}
    for part in re.split(r"(?m)^\[", shipped)[1:]:
        name, body = part.split("]", 1)
        sections[name] = [line for line in body.splitlines() if line.strip() and not line.startswith("#")]
    python = [
        "TOPLEVEL = " + os.path.join(HERE, "task_toplevel.py") if line.startswith("TOPLEVEL") and toplevel == "test" else line
        for line in sections["PYTHON"]
    ]
    return "\n".join(
        [
            "[EMC]\nVERSION = 1.1\nMACHINE = mach-vision-%s\nDEBUG = 0" % machine,
            "[DISPLAY]\nDISPLAY = %s\nCYCLE_TIME = 0.1\nMAX_FEED_OVERRIDE = 10.0" % os.path.join(HERE, "driver.py"),
            "[TASK]\nTASK = milltask\nCYCLE_TIME = 0.001",
            "[RS274NGC]\nPARAMETER_FILE = %s/test.var" % run_dir,
            *sections["RS274NGC"],
            "[PYTHON]",
            *python,
            "[EMCMOT]\nEMCMOT = motmod\nCOMM_TIMEOUT = 1.0\nBASE_PERIOD = 0\nSERVO_PERIOD = 1000000",
            "[EMCIO]\nEMCIO = io\nCYCLE_TIME = 0.1\nTOOL_TABLE = %s/test.tbl" % run_dir,
            "[HAL]\nHALFILE = basic_sim.tcl -no_use_hal_manualtoolchange",
            "[TRAJ]\nCOORDINATES = X Y Z\nLINEAR_UNITS = %s\nANGULAR_UNITS = degree\nMAX_LINEAR_VELOCITY = %g\n"
            "DEFAULT_LINEAR_VELOCITY = %g\nMAX_LINEAR_ACCELERATION = %g\nDEFAULT_LINEAR_ACCELERATION = %g\n"
            "POSITION_FILE = %s/position.txt" % (units, v, v / 2, a, a, run_dir),
            "[KINS]\nKINEMATICS = trivkins\nJOINTS = 3",
            axes + joints,
        ]
    )


def example(host, name, replace=None):
    """hosts/linuxcnc/examples/`name`, with `replace` {old line start: new line}."""
    with open(os.path.join(host, "examples", name)) as f:
        lines = f.read().splitlines()
    for old, new in (replace or {}).items():
        at = [k for k, line in enumerate(lines) if line.startswith(old)]
        if not at:
            raise SystemExit("run.py: no line %r in %s" % (old, name))
        lines[at[0]] = new
    return "\n".join(lines) + "\n"


# M281 re-centres over a mark read off the image centre (the part is shifted), in G91 G1 F30
# G18: the interpreter itself checks that the modes and the position are the program's again
# after M281 (an abort names what changed), and X0.5 must be an incremental feed move.
RECENTRE_MODES = """G90 G20 G17
G54
T98 M6 G43
G0 X6.0 Y0
G91 G1 F30 G18
M281
o<modes> if [[#<_motion_mode> NE 10] OR [#<_incremental> NE 1] OR [#<_feed> NE 30] OR [#<_plane> NE 180] OR [#<_metric> NE 0]]
    (abort, M281 changed the modal state)
o<modes> endif
o<at> if [[ABS[#<_x> - 6.0] GT 0.000001] OR [ABS[#<_y>] GT 0.000001]]
    (abort, M281 left the camera off the program's point)
o<at> endif
X0.5
(MSG, recentre-modes: the modes and the point are the program's)
M2
"""


def cases(host, setup):
    """[(name, world, camera table error (X, Y, in), program text)]. Consecutive cases with the
    same world share one simulated session (the sheet calibration, then example 4 with its K)."""
    ex4 = example(host, "04-rectangle-fit.ngc")
    # The sheet's dot 1 under the camera: the walk starts there.
    sheet = example(host, "01-calibrate-sheet.ngc")
    return [
        ("example-4", RIGID, (0, 0), ex4),
        ("ng", RIGID, (0, 0), example(host, "04-rectangle-fit.ngc", {"G0 X6.0 Y4.0": "G0 X20.0 Y20.0"})),
        ("base-rotation", {**RIGID, "rotation_deg": 10.7}, (0, 0), example(host, "04-rectangle-fit.ngc", {"G54": "G54 G10 L2 P1 R10"})),
        ("scaled-in-gate", LARGE, (0, 0), ex4),
        ("scaled-refused", {**LARGE, "params": {"VisionFitMaxScaleDev": 0.05}}, (0, 0), ex4),
        ("sheet", UNCALIBRATED, (0.04, -0.03), sheet),
        ("sheet-then-example-4", UNCALIBRATED, None, ex4),
        ("quick", {**UNCALIBRATED, "calibrated": True}, (0, 0), "G90 G20 G17\nG54\nT98 M6 G43\nG0 X6.0 Y0\nM283 Q0.5\nM284 P2\nM2\n"),
        ("c-word", RIGID, (0, 0), "G90 G20 G17\nG54\nT98 M6 G43\nG0 X-2.5 Y-4.0\nM283 C1\nM2\n"),
        ("recentre-modes", RIGID, (0, 0), RECENTRE_MODES),
        ("shipped-m284", {}, (0, 0), "G90 G20 G17\nG54\nT98 M6 G43\nM284 P2\nM2\n"),
    ]


def setup_lines(setup, camera_error):
    """MDI before a case: the world's G54 (no rotation), no G92/G52, no alignment, the camera
    tool's table offset plus `camera_error` (None: leave the table as the last case left it)."""
    g54 = setup["work_offset"]
    lines = [
        "G20 G10 L2 P1 X%.9f Y%.9f R0" % (g54[0], g54[1]),
        "G92.1",
        "#3990 = 0",
        "#3991 = 0",
    ]
    if camera_error is not None:
        x, y = setup["camera_table_offset"]
        lines.append("G20 G10 L1 P%d X%.9f Y%.9f" % (setup["camera_tool"], x + camera_error[0], y + camera_error[1]))
    return lines


def prepare(machine, work, host, module, only, camera_port):
    """The machine's run folder: INI, var file, tool table, programs and cases.json; returns
    it and LinuxCNC's environment."""
    units, per_inch, toplevel, runs = MACHINES[machine]
    run_dir = os.path.join(work, machine)
    shutil.rmtree(run_dir, ignore_errors=True)
    os.makedirs(os.path.join(run_dir, "fifo"))
    import mach_vision

    setup = mach_vision.Session.simulated().setup()
    with open(os.path.join(run_dir, "test.ini"), "w") as f:
        f.write(ini_text(machine, run_dir, host, units, per_inch, toplevel))
    with open(os.path.join(run_dir, "test.var"), "w") as f:
        f.write("".join("%d\t0\n" % n for n in mach_vision.PERSISTENT_PARAMS))
    with open(os.path.join(run_dir, "test.tbl"), "w") as f:
        f.write("T1 P1 ;cutter\nT%d P2 ;camera\n" % setup["camera_tool"])
    listed, world_id = [], None
    for name, world, camera_error, program in cases(host, setup):
        if name not in runs:
            continue
        if only and name not in only:
            continue
        path = os.path.join(run_dir, name + ".ngc")
        with open(path, "w") as f:
            f.write(program)
        # A case that leaves the tool table as it was (None) goes on in the previous world,
        # with its session (the sheet calibration's K).
        world_id = world_id if camera_error is None and world_id is not None else name
        listed.append({"name": name, "world_id": world_id, "world": world, "ngc": path, "setup": setup_lines(setup, camera_error)})
    with open(os.path.join(run_dir, "cases.json"), "w") as f:
        json.dump(listed, f, indent=1)
    # LinuxCNC runs its real-time part as RTAPI_UID (unprivileged): it must write here.
    for root, dirs, files in os.walk(run_dir):
        os.chmod(root, 0o777)
        for name in files:
            os.chmod(os.path.join(root, name), 0o666)
    env = dict(os.environ)
    env.update(
        HOME=run_dir,
        RTAPI_UID=os.environ.get("RTAPI_UID", "65534"),
        RTAPI_FIFO_PATH=os.path.join(run_dir, "fifo", "rtapi_fifo"),
        PYTHONDONTWRITEBYTECODE="1",
    )
    env.pop("PYTHONPATH", None)
    if toplevel == "test":
        env.update(
            PYTHONPATH=os.pathsep.join([TEST, HERE]),
            MACH_VISION_TEST_MODULE=module,
            MACH_VISION_TASK_DIR=run_dir,
            MACH_VISION_SIM="{}",
        )
    else:
        # The shipped module on the emulated Keyence camera; M284 saves the profile.
        profile = os.path.join(run_dir, "profile.toml")
        with open(profile, "w") as f:
            f.write(
                "[vision]\nVisionEnabled = true\nVisionDriver = \"Keyence\"\nVisionCameraToolNumber = %d\n"
                "VisionPoundVarBase = 500\n\n[keyence]\nVisionIP = \"127.0.0.1\"\nVisionPort = %d\n"
                % (setup["camera_tool"], camera_port)
            )
        os.chmod(profile, 0o666)
        env["MACH_VISION_PROFILE"] = profile
    return run_dir, env


class Check:
    def __init__(self):
        self.failures = 0

    def that(self, where, ok, what):
        print("%s %s: %s" % ("ok  " if ok else "FAIL", where, what))
        self.failures += 0 if ok else 1


def rotate(rot_deg, p):
    c, s = math.cos(math.radians(rot_deg)), math.sin(math.radians(rot_deg))
    return (c * p[0] - s * p[1], s * p[0] + c * p[1])


def texts(result):
    return [m[2] for m in result["messages"] if m[1] == "message"]


def captures_of(captures, name):
    return [c for c in captures if c["case"] == name]


def check_captures(check, where, captures, per_inch, want):
    """Each capture was taken where stat says the machine is: its commanded position (machine
    X, Y) within CAPTURE_TOLERANCE_IN, and the position feedback within TOLERANCE_IN (the sim
    HAL's feedback can trail the command by a servo period when the motion queue has just
    drained, up to 0.0001 in here)."""
    commanded, feedback = 0.0, 0.0
    for c in captures:
        canon = [v / (25.4 if c["metric"] else 1.0) for v in c["canon"]]
        commanded = max(commanded, math.dist(canon, [v / per_inch for v in c["position"]]))
        feedback = max(feedback, math.dist(canon, [v / per_inch for v in c["actual"]]))
    check.that(
        where,
        len(captures) >= want and commanded <= CAPTURE_TOLERANCE_IN and feedback <= TOLERANCE_IN,
        "%d captures where stat's position is: commanded within %.1e in, feedback within %.1e in"
        % (len(captures), commanded, feedback),
    )


def check_landing(check, where, result, truth, per_inch, tolerance):
    """The cut of example 4 (tool 1, after M282) against the simulator's truth: each of its
    points through the offsets stat reports (G5x, its rotation, G92/G52, the tool), and the
    place the machine stood still at the cut's start (2, 1). Returns the worst error, inches."""
    cut = [s for s in result["samples"] if s["tool"] == 1]
    if not cut:
        check.that(where, False, "no samples with the cutter in the spindle")
        return math.inf
    states = {(s["rot"], tuple(s["g92"]), tuple(s["g5x"]), tuple(s["tool_off"])) for s in cut}
    rot, g92, g5x, tool = cut[-1]["rot"], cut[-1]["g92"], cut[-1]["g5x"], cut[-1]["tool_off"]
    worst = 0.0
    for p in CUT:
        r = rotate(rot, (p[0] * per_inch + g92[0], p[1] * per_inch + g92[1]))
        machine = ((g5x[0] + r[0] + tool[0]) / per_inch, (g5x[1] + r[1] + tool[1]) / per_inch)
        worst = max(worst, math.dist(machine, truth.true_point(*p)))
    start = truth.true_point(2.0, 1.0)
    stood = min(math.dist([v / per_inch for v in s["pos"][:2]], start) for s in cut if s["vel"] == 0)
    check.that(
        where,
        len(states) == 1 and worst <= tolerance and stood <= tolerance,
        "%d cut points land within %.6f in, the machine stood %.6f in from the true (2, 1) (<= %g; %d offset states)"
        % (len(CUT), worst, stood, tolerance, len(states)),
    )
    return max(worst, stood)


def check_loaded(check, machine, run_dir, host, module):
    """The task ran the remaps of `host` and the tests' module."""
    with open(os.path.join(run_dir, "loaded.json")) as f:
        loaded = json.load(f)
    ok = all(os.path.dirname(loaded[m]) == host for m in ("remap", "oword"))
    ok = ok and os.path.dirname(loaded["mach_vision"]) == module
    check.that(machine, ok, "the task loaded %s" % loaded)


def check_machine(check, machine, run_dir, module_truth):
    per_inch = MACHINES[machine][1]
    with open(os.path.join(run_dir, "results.json")) as f:
        out = json.load(f)
    captures = []
    path = os.path.join(run_dir, "captures.jsonl")
    if os.path.exists(path):
        with open(path) as f:
            captures = [json.loads(line) for line in f]
    check.that(machine, "exception" not in out, out.get("exception", "the driver ran every case")[:400])
    if captures:
        print("     %s: %d captures, %d extra waits for the machine" % (machine, len(captures), captures[-1]["rewaits"]))
    worst = {}
    for result in out["cases"]:
        name, where = result["name"], "%s %s" % (machine, result["name"])
        said = texts(result)
        errors = [m[2] for m in result["messages"] if m[1] == "error"]
        truth = module_truth(result)
        final = result["final"]
        check.that(where, not result.get("timeout"), "ran in %.1f s" % result["seconds"])
        if name in ("example-4", "base-rotation", "sheet-then-example-4"):
            check.that(where, not errors and sum("M281: mark captured" in m for m in said) == 4, "four captures, no error: %s" % errors)
            worst[name] = check_landing(check, where, result, truth, per_inch, TOLERANCE_IN)
            check_captures(check, where, captures_of(captures, name), per_inch, 4)
            base = 10.0 if name == "base-rotation" else 0.0
            restored = abs(final["rot"] - base) < 1e-9 and all(abs(v) < 1e-9 for v in final["g92"])
            check.that(where, restored, "the final M280 restores rotation %g and G52 0 (got %s, %s)" % (base, final["rot"], final["g92"]))
        elif name == "ng":
            stop = [m for m in errors if m.startswith("M281: ") and "no mark" in m]
            check.that(where, bool(stop), "stopped with: %s" % errors)
            at = [v / per_inch for v in final["pos"][:2]]
            check.that(where, all(s["tool"] != 1 for s in result["samples"]), "nothing ran after the NG capture (machine at %s)" % at)
        elif name == "scaled-in-gate":
            report = [m for m in said if m.startswith("M282:")]
            scales = [float(v) for m in report for pair in re.findall(r"scale X ([\d.]+) / Y ([\d.]+) ignored", m) for v in pair]
            ok = len(scales) == 2 and all(abs(v - 1.001) < 2e-4 for v in scales)
            check.that(where, ok and not errors, "the ignored scale is reported: %s" % report)
            worst[name] = check_landing(check, where, result, truth, per_inch, 0.001 * math.hypot(3, 2) + TOLERANCE_IN)
        elif name == "scaled-refused":
            refused = [m for m in errors if m.startswith("M282: ") and "scale" in m]
            check.that(where, bool(refused), "refused with: %s" % errors)
            check.that(where, all(s["rot"] == 0.0 for s in result["samples"]), "no rotation was set")
        elif name == "sheet":
            check.that(where, not errors and any("M283: calibration done and saved" in m for m in said), "%s %s" % (errors, [m for m in said if "M283" in m]))
            check_captures(check, where, captures_of(captures, name), per_inch, 20)
        elif name == "quick":
            check.that(where, not errors and any("M283: calibration done" in m for m in said), "%s %s" % (errors, said))
            check.that(where, any(m.startswith("M284: camera job") for m in said), "M284 P2: %s" % [m for m in said if "M284" in m])
            check_captures(check, where, captures_of(captures, name), per_inch, 3)
        elif name == "shipped-m284":
            with open(os.path.join(run_dir, "profile.toml")) as f:
                saved = re.search(r"(?m)^VisionActiveJob = 2$", f.read()) is not None
            ok = not errors and "M284: camera job selected" in said and saved
            check.that(where, ok, "the installed module selected job 2 on the camera over TCP and saved it: %s %s" % (errors, said))
        elif name == "recentre-modes":
            mine = captures_of(captures, name)
            places = {tuple(round(v, 6) for v in c["canon"]) for c in mine}
            check.that(where, len(mine) >= 2 and len(places) >= 2, "M281 re-centred: %d triggers at %d places" % (len(mine), len(places)))
            check_captures(check, where, mine, per_inch, 2)
            kept = any("recentre-modes: the modes and the point are the program's" in m for m in said)
            check.that(where, kept and not errors, "the interpreter found the modes and the point unchanged: %s" % errors)
            # X0.5 after M281 (G91): 0.5 in from where the program put the camera, which is
            # where the first trigger was taken.
            if mine:
                point = mine[0]["canon"]
                end = [v / per_inch for v in final["pos"][:2]]
                off = math.dist(end, (point[0] + 0.5, point[1]))
                check.that(where, off <= CAPTURE_TOLERANCE_IN, "X0.5 after M281 ends 0.5 in from the program's point (off by %.1e in)" % off)
        elif name == "c-word":
            check.that(where, any("Bad character 'c' used" in m for m in errors), "the task refuses C on an XYZ machine: %s" % errors)
    return worst


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--module", required=True, help="the folder of mach_vision.abi3.so (built with the sim feature)")
    ap.add_argument("--host", default=REPO_HOST, help="the hosts/linuxcnc folder to run (the checkout's or the installed one)")
    ap.add_argument("--work", required=True, help="a scratch folder outside /tmp (each LinuxCNC gets a private /tmp)")
    ap.add_argument("--only", default="", help="comma-separated case names")
    ap.add_argument("--machines", default="inch,inch-cal,mm,mm-cal", help="of %s" % ",".join(MACHINES))
    ap.add_argument("--installed", help="the installed package's hosts/linuxcnc folder: runs the machines installed,shipped on it")
    args = ap.parse_args()
    sys.path.insert(0, args.module)
    import mach_vision

    def simulated(world):
        """The simulated world's truth (as sim_toplevel.simulated, which needs LinuxCNC)."""
        pairs = {k: tuple(v) for k, v in world.items() if k in ("shift", "scale")}
        return mach_vision.Session.simulated(**{**world, **pairs})

    only = [n for n in args.only.split(",") if n]
    machines = args.machines.split(",")
    emulator, camera_port = None, 0
    if args.installed:
        args.host, machines = args.installed, ["installed", "shipped"]
        # The installed CLI serves the emulated camera the shipped module talks to.
        emulator = subprocess.Popen(["mach-vision", "emulate", "--port", "0"], stdout=subprocess.PIPE, text=True)
        banner = emulator.stdout.readline()
        found = re.search(r"127\.0\.0\.1:(\d+)", banner)
        if not found:
            emulator.kill()
            raise SystemExit("run.py: mach-vision emulate said %r" % banner)
        camera_port = int(found.group(1))
    args.work = os.path.abspath(args.work)
    os.makedirs(args.work, exist_ok=True)
    os.chmod(args.work, 0o777)
    runs = {}
    start = time.time()
    # One LinuxCNC per machine at once, each in its own namespaces when the kernel lets us
    # (root with CAP_SYS_ADMIN); else one after the other.
    isolated = subprocess.run(ISOLATE + ["true"], capture_output=True).returncode == 0
    print("LinuxCNC runs %s" % ("in parallel, isolated" if isolated else "one after the other (no unshare)"))
    for machine in machines:
        run_dir, env = prepare(machine, args.work, os.path.abspath(args.host), os.path.abspath(args.module), only, camera_port)
        # The one folder under /tmp holding all this run reads there (see ISOLATE).
        read = [run_dir, args.host, args.module, os.path.dirname(__file__)]
        env["MV_KEEP"] = os.path.commonpath([p for p in map(os.path.realpath, read) if p.startswith("/tmp/")] or [run_dir])
        log = open(os.path.join(run_dir, "linuxcnc.log"), "w")
        cmd = ["timeout", "600", "linuxcnc", "-r", os.path.join(run_dir, "test.ini")]
        if os.geteuid() == 0:
            # Not real-time: ahead of other work on a shared machine, the task and motion keep
            # their cycles (starved, homing and moves time out).
            cmd = ["nice", "-n", "-10"] + cmd
        if isolated:
            cmd = ISOLATE + cmd
        runs[machine] = (run_dir, subprocess.Popen(cmd, env=env, cwd=run_dir, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL))
        if not isolated:
            runs[machine][1].wait()
    check = Check()
    for machine, (run_dir, p) in runs.items():
        status = p.wait()
        print("%s: linuxcnc exit status %d after %.1f s" % (machine, status, time.time() - start))
        if not os.path.exists(os.path.join(run_dir, "results.json")):
            with open(os.path.join(run_dir, "linuxcnc.log")) as f:
                print(f.read()[-3000:])
            check.that(machine, False, "no results (LinuxCNC did not start the driver)")
            continue
        with open(os.path.join(run_dir, "cases.json")) as f:
            worlds = {c["name"]: c["world"] for c in json.load(f)}
        truths = {}

        def truth(result):
            key = json.dumps(worlds[result["name"]], sort_keys=True)
            if key not in truths:
                truths[key] = simulated(worlds[result["name"]])
            return truths[key]

        if MACHINES[machine][2] == "test":
            check_loaded(check, machine, run_dir, os.path.abspath(args.host), os.path.abspath(args.module))
        worst = check_machine(check, machine, run_dir, truth)
        for name, err in sorted(worst.items()):
            print("     %s %s: landing error %.6f in" % (machine, name, err))
    if emulator is not None:
        emulator.terminate()
        emulator.wait()
    print("%d failure(s), %.1f s" % (check.failures, time.time() - start))
    return 1 if check.failures else 0


if __name__ == "__main__":
    sys.exit(main())
