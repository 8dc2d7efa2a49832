#!/usr/bin/python3
"""The tests' [DISPLAY] DISPLAY: drives LinuxCNC's task like an operator would, through the
`linuxcnc` Python module of the system python3, and records what the machine did. LinuxCNC
starts it as `driver.py -ini FILE` and shuts down when it exits.

Reads `cases.json` beside the INI: a list of {"name", "ngc", "world", "setup"}. Once: estop
reset, machine on, home all. Then for each case: writes `world.json` (the simulated world the
test TOPLEVEL puts behind the camera), runs the case's `setup` lines in MDI (G54, the camera's
tool-table offset, G92.1, the alignment's persistent parameters), then opens and runs the
program in AUTO, polling `stat` and `error_channel` until the interpreter is idle again.
Writes `results.json` beside the INI: per case the operator messages and errors, the stat
samples (each change of line, position or offsets) and the final state.

Never `wait_complete()` after AUTO_RUN: it blocks for its whole timeout while a program runs.
"""

import json
import os
import sys
import time

import linuxcnc

RUN_DIR = os.path.dirname(os.path.abspath(sys.argv[sys.argv.index("-ini") + 1]))
CASE_TIMEOUT_S = 120.0
# [DISPLAY] MAX_FEED_OVERRIDE in the tests' INI.
FEED_OVERRIDE = 10.0

stat = linuxcnc.stat()
command = linuxcnc.command()
errors = linuxcnc.error_channel()
t0 = time.time()


def now():
    return round(time.time() - t0, 4)


ERROR_KINDS = (linuxcnc.NML_ERROR, linuxcnc.OPERATOR_ERROR)


def drain(into):
    """Moves every pending operator message and error into `into` as [t, "error" or
    "message", text]."""
    while True:
        m = errors.poll()
        if not m:
            return
        into.append([now(), "error" if m[0] in ERROR_KINDS else "message", m[1]])


def snap():
    """The state the checks need, machine units (stat reports the machine's units)."""
    s = stat
    return {
        "t": now(),
        "line": s.current_line,
        "pos": [round(v, 7) for v in s.position[:3]],
        "act": [round(v, 7) for v in s.actual_position[:3]],
        "g5x": list(s.g5x_offset[:2]),
        "g92": list(s.g92_offset[:2]),
        "rot": s.rotation_xy,
        "tool_off": list(s.tool_offset[:2]),
        "tool": s.tool_in_spindle,
        "vel": s.current_vel,
        "gcodes": list(s.gcodes),
        "feed": s.settings[1],
    }


def wait_idle(timeout_s, messages):
    """Polls until the interpreter is idle; False on timeout."""
    deadline = time.time() + timeout_s
    while time.time() < deadline:
        stat.poll()
        drain(messages)
        if stat.interp_state == linuxcnc.INTERP_IDLE:
            return True
        time.sleep(0.005)
    return False


def mdi(lines, messages):
    command.mode(linuxcnc.MODE_MDI)
    command.wait_complete()
    for line in lines:
        command.mdi(line)
        command.wait_complete()
        if not wait_idle(10, messages):
            raise RuntimeError("MDI %r did not finish" % line)


def run_case(case):
    result = {"name": case["name"], "messages": [], "samples": []}
    with open(os.path.join(RUN_DIR, "world.json"), "w") as f:
        json.dump({"case": case["name"], "world": case["world_id"], "sim": case["world"]}, f)
    mdi(case["setup"], result["messages"])
    stat.poll()
    result["before"] = snap()
    command.mode(linuxcnc.MODE_AUTO)
    command.wait_complete()
    command.program_open(case["ngc"])
    command.wait_complete()
    drain(result["messages"])
    start = time.time()
    command.auto(linuxcnc.AUTO_RUN, 0)
    started, last = False, None
    while time.time() - start < CASE_TIMEOUT_S:
        stat.poll()
        drain(result["messages"])
        s = snap()
        key = (s["line"], tuple(s["pos"]), s["rot"], tuple(s["g92"]), tuple(s["g5x"]), s["tool"], s["vel"] == 0)
        if key != last:
            result["samples"].append(s)
            last = key
        if stat.interp_state != linuxcnc.INTERP_IDLE:
            started = True
        elif started or time.time() - start > 3:
            break
        time.sleep(0.002)
    else:
        result["timeout"] = True
    # Late messages (the error of an aborted program comes with the idle state).
    time.sleep(0.2)
    stat.poll()
    drain(result["messages"])
    result["final"] = snap()
    result["seconds"] = round(time.time() - start, 2)
    return result


def main():
    with open(os.path.join(RUN_DIR, "cases.json")) as f:
        cases = json.load(f)
    out = {"cases": [], "messages": []}
    try:
        for _ in range(400):
            try:
                stat.poll()
                break
            except linuxcnc.error:
                time.sleep(0.05)
        command.state(linuxcnc.STATE_ESTOP_RESET)
        command.wait_complete()
        command.state(linuxcnc.STATE_ON)
        command.wait_complete()
        command.mode(linuxcnc.MODE_MANUAL)
        command.wait_complete()
        command.home(-1)
        command.wait_complete()
        deadline = time.time() + 60
        while time.time() < deadline and not all(stat.homed[:3]):
            time.sleep(0.05)
            stat.poll()
        if not all(stat.homed[:3]):
            raise RuntimeError("the machine did not home")
        # The cuts' feeds (F20, F60 in/min) at 10x: the cases take seconds, not minutes.
        command.feedrate(FEED_OVERRIDE)
        for case in cases:
            out["cases"].append(run_case(case))
    except Exception as e:  # recorded for the check, which fails the run
        import traceback

        out["exception"] = "%s\n%s" % (e, traceback.format_exc())
    finally:
        try:
            drain(out["messages"])
        except linuxcnc.error as e:
            out.setdefault("exception", "error channel: %s" % e)
        with open(os.path.join(RUN_DIR, "results.json"), "w") as f:
            json.dump(out, f)


if __name__ == "__main__":
    main()
