#!/usr/bin/env python3
"""Runs LinuxCNC's interpreter (rs274) and `mach-vision trace` on the same G-code programs and
compares every motion, move by move, in machine coordinates.

rs274 prints canonical commands in the program's units *before* offsets, with 4 decimals; this
script applies the G5x, G92, XY-rotation and tool-length offsets it printed (as LinuxCNC's
canon layer does: machine = g5x + rot(p + g92) + tool) and compares each STRAIGHT_TRAVERSE /
STRAIGHT_FEED end point and each ARC_FEED end point, centre, direction and turn count with
mach-vision's events, within 1e-4 of the printed precision (plus the half unit of the last
printed digit).

Each program gets one verdict:
  agree          both ran; same motions
  differ         both ran; the first different motion is shown
  refused        rs274 ran it, mach-vision refused it (its message is shown)
  both-refuse    rs274 stops with an error, and so does mach-vision (perhaps on another line);
                 a different motion among those both made first is a `differ`
  rs274-refuses  rs274 stops with an error, mach-vision runs it (not a comparison: LinuxCNC's
                 own limits, e.g. a subroutine file run without its call)
  skipped        marked "(oracle: writes length parameters)" and compared on a millimetre
                 machine with an rs274 that keeps length parameters in inches (see
                 honours_machine_units)

Usage: compare.py [--rs274 PATH] [--trace PATH] [--units mm|in] [--subroutine-path DIRS]
                  [--tool-table FILE] [--random N [--seed S]] [--quiet] [PROGRAM...]
Exit status 0 when no program differs (refusals are counted, not failures), 1 otherwise.
"""

import argparse
import collections
import json
import math
import os
import random
import re
import subprocess
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
DEFAULT_RS274 = os.path.join(ROOT, "target", "linuxcnc-oracle", "x", "usr", "bin", "rs274")
DEFAULT_TRACE = os.path.join(ROOT, "target", "debug", "mach-vision")
MM_PER_IN = 25.4
# 1e-4 of the printed unit, plus half of its last printed digit (rs274 rounds to 4 decimals).
TOLERANCE = 1.5e-4
CALL = re.compile(r"^\s*\d+\s+N\S*\s+([A-Z_0-9]+)\((.*)\)\s*$")


def rs274_env(rs274):
    env = dict(os.environ)
    lib = os.path.join(os.path.dirname(os.path.dirname(rs274)), "lib")
    env["LD_LIBRARY_PATH"] = lib + (":" + env["LD_LIBRARY_PATH"] if env.get("LD_LIBRARY_PATH") else "")
    return env


def numbers(args):
    return [float(x) for x in re.split(r"[,\s]+", args.strip()) if x]


def run_rs274(rs274, program, units, tool_table, subroutine_path, timeout):
    """Returns (motions, error) with motions in machine coordinates, millimetres: the motions
    rs274 printed before it stopped, also when it stopped with an error."""
    with tempfile.TemporaryDirectory(prefix="oracle-") as tmp:
        var = os.path.join(tmp, "rs274.var")
        open(var, "w").close()
        ini = os.path.join(tmp, "oracle.ini")
        with open(ini, "w") as f:
            f.write("[RS274NGC]\nSUBROUTINE_PATH = %s\n" % subroutine_path)
            # The machine's units, as mach-vision's --machine-units: the unit of the length
            # parameters (#5221 = 1 is 1 in on an inch machine). Without it rs274 stores them
            # in inches (driver.cc) whatever the program's units.
            f.write("[TRAJ]\nLINEAR_UNITS = %s\n" % ("inch" if units == "in" else "mm"))
        cmd = [rs274, "-g", "-i", ini, "-t", tool_table, "-v", var, program]
        env = rs274_env(rs274)
        env["HOME"] = tmp
        try:
            p = subprocess.run(cmd, env=env, capture_output=True, timeout=timeout, cwd=tmp)
        except subprocess.TimeoutExpired:
            return None, "rs274 timed out"
    out = p.stdout.decode("latin-1")
    err = p.stderr.decode("latin-1").replace("executing", "").strip()
    error = None
    if p.returncode != 0:
        error = err.splitlines()[0] if err else "rs274 exit %d" % p.returncode
    scale = 1.0  # mm per printed unit
    g5x = [0.0, 0.0, 0.0]
    g92 = [0.0, 0.0, 0.0]
    tool = [0.0, 0.0, 0.0]
    rot = 0.0
    plane = "XY"
    motions = []

    def machine(p):
        x, y, z = p[0] * scale + g92[0], p[1] * scale + g92[1], p[2] * scale + g92[2]
        c, s = math.cos(math.radians(rot)), math.sin(math.radians(rot))
        x, y = x * c - y * s, x * s + y * c
        return [x + g5x[0] + tool[0], y + g5x[1] + tool[1], z + g5x[2] + tool[2]]

    for line in out.splitlines():
        m = CALL.match(line)
        if not m:
            continue
        name, args = m.group(1), m.group(2)
        if name == "USE_LENGTH_UNITS":
            scale = MM_PER_IN if "INCHES" in args else (10.0 if "CM" in args else 1.0)
        elif name == "SET_G5X_OFFSET":
            v = numbers(args)
            g5x = [v[1] * scale, v[2] * scale, v[3] * scale]
        elif name == "SET_G92_OFFSET":
            g92 = [x * scale for x in numbers(args)[:3]]
        elif name == "SET_XY_ROTATION":
            rot = numbers(args)[0]
        elif name == "USE_TOOL_LENGTH_OFFSET":
            v = numbers(args)
            tool = [v[0] * scale, v[1] * scale, v[2] * scale]
        elif name == "SELECT_PLANE":
            plane = args.replace("CANON_PLANE_", "").strip()
        elif name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED"):
            v = numbers(args)
            motions.append({"kind": "rapid" if name == "STRAIGHT_TRAVERSE" else "feed",
                            "end": machine(v[:3]), "unit": scale, "src": line.strip()})
        elif name == "ARC_FEED":
            v = numbers(args)
            e1, e2, c1, c2, turn, ax = v[:6]
            if plane == "XY":
                end, centre = [e1, e2, ax], [c1, c2, None]
            elif plane == "XZ":
                end, centre = [e2, ax, e1], [c2, None, c1]
            else:  # YZ
                end, centre = [ax, e1, e2], [None, c1, c2]
            end_m = machine(end)
            filled = [c if c is not None else 0.0 for c in centre]
            centre_m = machine(filled)
            centre_m = [cm if c is not None else None for cm, c in zip(centre_m, centre)]
            # The whole centre (on the end's level along the normal) and the normal, machine
            # frame: a G18/G19 arc in a rotated system is no longer in a machine plane, and
            # mach-vision traces it as feed segments, checked against this axis.
            axis_point = machine([c if c is not None else e for c, e in zip(centre, end)])
            c, s = math.cos(math.radians(rot)), math.sin(math.radians(rot))
            normal = {"XY": [0.0, 0.0, 1.0], "XZ": [-s, c, 0.0]}.get(plane, [c, s, 0.0])
            motions.append({"kind": "arc", "end": end_m, "centre": centre_m, "cw": turn < 0,
                            "turns": int(abs(turn)), "unit": scale, "src": line.strip(),
                            "axis_point": axis_point, "normal": normal,
                            "radius": off_axis(end_m, axis_point, normal)})
        elif name in ("STRAIGHT_PROBE", "RIGID_TAP", "NURBS_FEED", "SPLINE_FEED"):
            motions.append({"kind": name.lower(), "end": None, "unit": scale, "src": line.strip()})
    return motions, error


def run_trace(trace, program, units, subroutine_path, timeout):
    """Returns (motions, error) with motions in machine coordinates, millimetres."""
    cmd = [trace, "trace", "--json", "--machine-units", units, "--dialect", "linuxcnc", "--subroutine-path", subroutine_path, program]
    try:
        p = subprocess.run(cmd, capture_output=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, "trace timed out"
    to_mm = MM_PER_IN if units == "in" else 1.0
    motions = []
    error = None
    for line in p.stdout.decode("utf-8", "replace").splitlines():
        try:
            e = json.loads(line)
        except ValueError:
            continue
        t = e.get("type")
        if t == "linear":
            motions.append({"kind": e["rate"], "end": [x * to_mm for x in e["end"]], "line": e["line"]})
        elif t == "arc":
            motions.append({"kind": "arc", "end": [x * to_mm for x in e["end"]],
                            "centre": [x * to_mm for x in e["center"]], "cw": e["direction"] == "cw",
                            "turns": e["extra_turns"] + 1, "line": e["line"]})
        elif t == "error":
            error = e["message"]
    if p.returncode != 0 and error is None:
        error = p.stderr.decode("utf-8", "replace").strip().splitlines()[-1:] or ["exit %d" % p.returncode]
        error = error[0]
    return motions, error


# A program marked so reads or writes length parameters (#5221 = 1 ...), whose unit is the
# machine's: compared on a millimetre machine only where rs274 keeps them in millimetres.
LENGTH_PARAMETERS = "(oracle: writes length parameters)"


def honours_machine_units(rs274, tool_table, timeout):
    """Whether rs274 keeps length parameters in the [TRAJ] LINEAR_UNITS its INI names. The
    2.9.0 pre-release in Debian 12 keeps them in inches whatever the INI says (LinuxCNC issue
    #1279, fixed in 2.9.0 by reading LINEAR_UNITS in driver.cc)."""
    with tempfile.TemporaryDirectory(prefix="oracle-probe-") as tmp:
        probe = os.path.join(tmp, "probe.ngc")
        with open(probe, "w") as f:
            f.write("G21\n#5221 = 1\nG55\nG54\nG0 X0\nM2\n")
        motions, error = run_rs274(rs274, probe, "mm", tool_table, tmp, timeout)
    # G0 X0 in G54 with X offset #5221 = 1: machine X1 mm, or 25.4 mm on an inch-only rs274.
    return error is None and len(motions) == 1 and abs(motions[0]["end"][0] - 1.0) < TOLERANCE


def close(a, b, unit):
    return all(x is None or y is None or abs(x - y) / unit <= TOLERANCE for x, y in zip(a, b))


def off_axis(p, point, normal):
    """Distance of p from the line through point along the unit vector normal."""
    d = [a - b for a, b in zip(p, point)]
    along = sum(a * b for a, b in zip(d, normal))
    return math.sqrt(max(0.0, sum(a * a for a in d) - along * along))


# How far mach-vision's feed segments for an arc may lie from the true arc: its chord tolerance
# (0.0001 in, or 0.0025 mm), in millimetres.
CHORD_MM = 0.0025


def sagitta(t, start):
    """The sagitta of rs274's arc t (one turn) from start: how far one chord strays from it."""
    if start is None or t["turns"] != 1:
        return None
    n, c = t["normal"], t["axis_point"]

    def flat(p):
        d = [a - b for a, b in zip(p, c)]
        along = sum(a * b for a, b in zip(d, n))
        return [a - along * b for a, b in zip(d, n)]
    u, v = flat(start), flat(t["end"])
    cross = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    ccw = math.atan2(sum(a * b for a, b in zip(cross, n)), sum(a * b for a, b in zip(u, v)))
    sweep = -ccw if t["cw"] else ccw
    if sweep <= 0:
        sweep += 2 * math.pi
    return t["radius"] * (1 - math.cos(sweep / 2))


def polyline(t, ours, j, start=None):
    """When ours[j:] starts a run of feed segments of one line standing for rs274's arc t (a
    G18/G19 arc in a rotated system): the index after the run, else None. A run of one
    segment stands for an arc from `start` (rs274's previous end) short enough that one chord
    is within the chord tolerance."""
    k = j
    while k < len(ours) and ours[k]["kind"] == "feed" and ours[k]["line"] == ours[j]["line"]:
        k += 1
    if k == j or not close(t["end"], ours[k - 1]["end"], t["unit"]):
        return None
    slack = CHORD_MM + TOLERANCE * t["unit"]
    if k - j == 1:
        bulge = sagitta(t, start)
        return k if bulge is not None and bulge <= slack else None
    if all(abs(off_axis(o["end"], t["axis_point"], t["normal"]) - t["radius"]) <= slack for o in ours[j:k]):
        return k
    return None


def compare(theirs, ours, prefix=False):
    """The first difference as text, or None. With `prefix` (both refused the program, perhaps
    on different lines) only the motions both made are compared."""
    j = done = 0
    for i, t in enumerate(theirs):
        if j >= len(ours):
            break
        done = i + 1
        o = ours[j]
        j += 1
        where = "motion %d (our line %s; rs274 %s)" % (i + 1, o.get("line"), t["src"])
        if t["end"] is None:
            return "%s: rs274 did %s" % (where, t["kind"])
        if t["kind"] == "arc" and o["kind"] == "feed":
            after = polyline(t, ours, j - 1, theirs[i - 1]["end"] if i > 0 else None)
            if after is not None:
                j = after
                continue
        if t["kind"] != o["kind"]:
            return "%s: rs274 %s, ours %s" % (where, t["kind"], o["kind"])
        if not close(t["end"], o["end"], t["unit"]):
            return "%s: end %s mm, ours %s mm" % (where, fmt(t["end"]), fmt(o["end"]))
        if t["kind"] == "arc":
            if not close(t["centre"], o["centre"], t["unit"]):
                return "%s: centre %s mm, ours %s mm" % (where, fmt(t["centre"]), fmt(o["centre"]))
            if t["cw"] != o["cw"] or t["turns"] != o["turns"]:
                return "%s: rs274 %s x%d, ours %s x%d" % (
                    where, "cw" if t["cw"] else "ccw", t["turns"], "cw" if o["cw"] else "ccw", o["turns"])
    if not prefix and (done != len(theirs) or j != len(ours)):
        return "rs274 made %d motions, ours %d" % (len(theirs), len(ours))
    return None


def fmt(p):
    return "(" + ", ".join("-" if x is None else "%.4f" % x for x in p) + ")"


def fmt4(v):
    return "%.4f" % v


def axis_words(rng, big, span=1.0, letters="XYZ"):
    """One to three of the letters with random values (program units)."""
    return " ".join("%s%s" % (a, fmt4(rng.uniform(-span, span) * big))
                    for a in sorted(rng.sample(letters, rng.randint(1, len(letters)))))


def focus_feature(rng, lines, pos, absolute, big):
    """Appends one of the features issue 25 found differences in; returns the tracked program
    point (None when unknown) and whether G90 is in force:
      - G10 L20 (any system, some axes), G52 and G92 in a rotated system, then a move;
      - G53 between the lines of an active canned cycle (and a cycle repeated after it);
      - full circles with P turns, their end written, left out, or read back from #5420-#5422
        (one rounding step off the start when the machine's units are not the program's)."""
    f = fmt4
    form = rng.random()
    if form < 0.4:
        lines.append("G10 L2 P%d R%s" % (rng.choice([0, 0, rng.randint(1, 6)]), f(rng.uniform(-180, 180))))
        for _ in range(rng.randint(1, 3)):
            what = rng.random()
            if what < 0.45:
                lines.append("G10 L20 P%d %s" % (rng.choice([0, 0, 1, rng.randint(1, 6)]), axis_words(rng, big)))
            elif what < 0.7:
                lines.append("G52 %s" % axis_words(rng, big))
            elif what < 0.95:
                lines.append("G92 %s" % axis_words(rng, big))
            else:
                lines.append("G92.1")
        if absolute and rng.random() < 0.5:
            lines.append("G0 X0 Y0 Z0")
            return [0.0, 0.0, 0.0], absolute
        lines.append("%s %s" % (rng.choice(["G0", "G1"]), axis_words(rng, big)))
        return None, absolute
    if form < 0.7:
        if not absolute:
            lines.append("G90")
            lines.append("G0 X0 Y0 Z0")
        cycle = rng.choice(["G81", "G82 P0.1", "G83 Q%s" % f(0.1 * big), "G73 Q%s" % f(0.07 * big), "G85", "G89 P0.2"])
        hole = lambda: "X%s Y%s Z%s R%s" % (f(rng.uniform(-2, 2) * big), f(rng.uniform(-2, 2) * big),
                                             f(-0.4 * big), f(0.1 * big))
        lines.append("%s %s %s" % (rng.choice(["G98", "G99"]), cycle, hole()))
        if rng.random() < 0.5:
            lines.append("X%s" % f(rng.uniform(-2, 2) * big))  # the cycle again, before the G53
        lines.append("G53 %s %s" % (rng.choice(["G0", "G0", "G1"]),
                                    rng.choice(["Z%s" % f(rng.uniform(-1, 2) * big), axis_words(rng, big, 2.0)])))
        again = rng.random()
        if again < 0.6:
            lines.append("%s %s %s" % (rng.choice(["G98", "G99", ""]), cycle, hole()))
        elif again < 0.8:
            lines.append("X%s Y%s" % (f(rng.uniform(-2, 2) * big), f(rng.uniform(-2, 2) * big)))  # a G0 now
        lines.append("G80")
        lines.append("G0 X0 Y0 Z0")
        return [0.0, 0.0, 0.0], True
    # From a known point: the program point after the first line's G10 L2 is not (0, 0, 0).
    pos = [round(rng.uniform(-2, 2) * big, 4) for _ in range(3)]
    lines.append("G90 G0 X%s Y%s Z%s" % tuple(f(v) for v in pos))
    plane, (a, b), (ca, cb) = rng.choice([("G17", (0, 1), ("I", "J")), ("G18", (2, 0), ("K", "I")),
                                          ("G19", (1, 2), ("J", "K"))])
    normal = 3 - a - b
    r = rng.uniform(0.2, 2) * big
    phi = rng.uniform(0, 6.283)
    ia, ib = -r * math.cos(phi), -r * math.sin(phi)
    letters = "XYZ"
    end = rng.random()
    if end < 0.3:
        words = ""
    elif end < 0.7:
        words = "%s[#%d] %s[#%d] " % (letters[a], 5420 + a, letters[b], 5420 + b)
    else:
        words = "%s%s %s%s " % (letters[a], f(pos[a]), letters[b], f(pos[b]))
    if rng.random() < 0.3:
        pos[normal] = round(pos[normal] + rng.uniform(-0.5, 0.5) * big, 4)
        words += "%s%s " % (letters[normal], f(pos[normal]))
    turns = rng.choice(["", " P1", " P2", " P2", " P3"])
    lines.append("%s %s %s%s%s %s%s%s" % (plane, rng.choice(["G2", "G3"]), words, ca, f(ia), cb, f(ib), turns))
    lines.append("G17")
    return pos, True


def carry_feature(rng, lines, big):
    """Appends one of issue 33's features: an XY rotation change (G10 L2 R) with a G52/G92
    offset in force, which leaves rs274's current point off the machine position, then what
    carries that point (a G54-G59 change, a parameter write, G43.1/G49), then what goes from
    it (G28/G30's first leg, a G91 move, a G91 polar move). Leaves G90 in force. No M6: after
    a tool change LinuxCNC's task re-reads the point from the machine, the standalone rs274
    its last printed point, unrotated (saicanon.cc), so the two differ by design there."""
    f = fmt4
    lines.append("G90 G0 X%s Y%s" % (f(rng.uniform(0.2, 1) * big), f(rng.uniform(0.2, 1) * big)))
    lines.append("%s X%s Y%s" % (rng.choice(["G52", "G92"]), f(rng.uniform(-1, 1) * big), f(rng.uniform(-1, 1) * big)))
    lines.append("G10 L2 P0 R%s" % f(rng.uniform(-180, 180)))
    for _ in range(rng.randint(1, 2)):
        what = rng.random()
        if what < 0.4:
            lines.append("G%d" % rng.randint(54, 59))
        elif what < 0.6:
            # Rewriting a stored value (or an angle) is the same in every machine unit.
            n = rng.choice([5221 + 20 * rng.randint(0, 5) + rng.randint(0, 2), 5230 + 20 * rng.randint(0, 5)])
            lines.append("#%d = #%d" % (n, n) if n % 10 != 0 else "#%d = %s" % (n, f(rng.uniform(-90, 90))))
        elif what < 0.85:
            lines.append("G43.1 Z%s" % f(rng.uniform(-0.5, 0.5) * big))
        else:
            lines.append("G49")
    go = rng.random()
    if go < 0.5:
        lines.append("%s%s" % (rng.choice(["G28", "G30"]), rng.choice(["", " " + axis_words(rng, big)])))
    elif go < 0.8:
        lines.append("G91 %s %s" % (rng.choice(["G0", "G1"]), axis_words(rng, big, 0.5)))
    else:
        lines.append("G91 G0 @%s ^%s" % (f(rng.uniform(0.1, 1) * big), f(rng.uniform(-180, 180))))
    lines.append("G90 G49")


def random_program(rng, focus=0.0, carry=0.0):
    """A random program of the G-code both interpreters share: units, planes, G90/G91, G0-G3
    (centre and R forms, full circles, P turns), polar words, work offsets, G10 L2 rotations,
    G10 L20, G52, G92, G53, canned cycles and o-word loops. `focus` is the share of steps
    given to `focus_feature`'s programs (issue 25)."""
    f = fmt4
    units = rng.choice(["G20", "G21"])
    big = 1.0 if units == "G20" else 25.4
    lines = ["%s G90 G17 G40 G49 G80 G94 F%s" % (units, f(rng.uniform(5, 50) * big))]
    lines.append("G10 L2 P%d X%s Y%s Z%s" % (rng.randint(1, 6), f(rng.uniform(-2, 2) * big),
                                            f(rng.uniform(-2, 2) * big), f(rng.uniform(-1, 1) * big)))
    pos = [0.0, 0.0, 0.0]  # the program point, tracked for arcs under G90 only
    absolute = True
    for _ in range(rng.randint(5, 25)):
        if carry and rng.random() < carry:
            carry_feature(rng, lines, big)
            pos, absolute = None, True
            continue
        if focus and rng.random() < focus:
            pos, absolute = focus_feature(rng, lines, pos, absolute, big)
            continue
        kind = rng.random()
        if kind < 0.05:
            # LinuxCNC's polar words: distance and/or angle, absolute or as changes (G91).
            words = rng.choice([["@%s" % f(rng.uniform(0.1, 3) * big), "^%s" % f(rng.uniform(-360, 360))],
                                ["@%s" % f(rng.uniform(-1, 1) * big)], ["^%s" % f(rng.uniform(-90, 90))]])
            # Away from the origin first: there a lone @ (G90) or any G91 polar word is undefined.
            lines.append("G0 X%s Y%s" % (f(rng.uniform(0.2, 1) * big), f(rng.uniform(0.2, 1) * big)))
            lines.append("%s %s" % (rng.choice(["G0", "G1"]), " ".join(words)))
            pos = None
        elif kind < 0.30:
            code = rng.choice(["G0", "G1"])
            axes = rng.sample("XYZ", rng.randint(1, 3))
            words = []
            for a in axes:
                v = rng.uniform(-3, 3) * big
                words.append("%s%s" % (a, f(v)))
                if absolute and pos is not None:
                    pos["XYZ".index(a)] = round(v, 4)
            lines.append("%s %s" % (code, " ".join(words)))
            if not absolute:
                pos = None
        elif kind < 0.55 and absolute and pos is not None:
            plane, (a, b), (ca, cb) = rng.choice([("G17", (0, 1), ("I", "J")), ("G18", (2, 0), ("K", "I")),
                                                  ("G19", (1, 2), ("J", "K"))])
            code = rng.choice(["G2", "G3"])
            r = rng.uniform(0.2, 2) * big
            phi0 = rng.uniform(0, 6.283)
            centre = (pos[a] - r * math.cos(phi0), pos[b] - r * math.sin(phi0))
            if rng.random() < 0.15:
                # A full circle from the centre words alone, possibly several turns.
                turns = rng.choice(["", " P2"])
                lines.append("%s %s %s%s %s%s%s" % (plane, code, ca, f(centre[0] - pos[a]), cb,
                                                    f(centre[1] - pos[b]), turns))
            else:
                phi1 = rng.uniform(0, 6.283)
                end = [centre[0] + r * math.cos(phi1), centre[1] + r * math.sin(phi1)]
                end = [round(end[0], 4), round(end[1], 4)]
                letters = "XYZ"
                normal = 3 - a - b
                rise = rng.choice([0.0, rng.uniform(-0.5, 0.5) * big])
                words = "%s%s %s%s" % (letters[a], f(end[0]), letters[b], f(end[1]))
                if rise:
                    pos[normal] = round(pos[normal] + rise, 4)
                    words += " %s%s" % (letters[normal], f(pos[normal]))
                if rng.random() < 0.3 and math.hypot(end[0] - pos[a], end[1] - pos[b]) > 0.01 * big:
                    half = math.hypot(end[0] - pos[a], end[1] - pos[b]) / 2
                    radius = max(half * rng.uniform(1.0, 3.0), half + 0.001 * big)
                    lines.append("%s %s %s R%s" % (plane, code, words, f(rng.choice([1, -1]) * radius)))
                else:
                    lines.append("%s %s %s %s%s %s%s" % (plane, code, words, ca, f(centre[0] - pos[a]), cb,
                                                         f(centre[1] - pos[b])))
                pos[a], pos[b] = end
            lines.append("G17")
        elif kind < 0.62:
            absolute = not absolute
            lines.append("G90" if absolute else "G91")
            if absolute:
                lines.append("G0 X%s Y%s Z%s" % (f(pos[0] if pos else 0), f(pos[1] if pos else 0), f(pos[2] if pos else 0)))
                pos = pos or [0.0, 0.0, 0.0]
        elif kind < 0.68:
            lines.append("G%d" % rng.randint(54, 59))
            pos = None if absolute else pos
            if absolute:
                lines.append("G0 X0 Y0 Z0")
                pos = [0.0, 0.0, 0.0]
        elif kind < 0.73 and absolute:
            lines.append("G92 X%s Y%s" % (f(rng.uniform(-1, 1) * big), f(rng.uniform(-1, 1) * big)))
            lines.append("G0 X0 Y0 Z0")
            pos = [0.0, 0.0, 0.0]
        elif kind < 0.76:
            lines.append("G92.1")
            if absolute:
                lines.append("G0 X0 Y0 Z0")
                pos = [0.0, 0.0, 0.0]
        elif kind < 0.80 and absolute:
            lines.append("G53 G0 Z%s" % f(rng.uniform(-1, 1) * big))
            lines.append("G0 X0 Y0 Z0")
            pos = [0.0, 0.0, 0.0]
        elif kind < 0.86:
            # LinuxCNC's coordinate-system rotation, the shared G52/G92 offset added before it,
            # and moves that start from the current point rs274 computes after a rotation change.
            form = rng.random()
            if form < 0.5:
                lines.append("G10 L2 P%d R%s" % (rng.choice([0, 0, rng.randint(1, 6)]), f(rng.uniform(-180, 180))))
            elif form < 0.75:
                lines.append("G52 X%s Y%s" % (f(rng.uniform(-1, 1) * big), f(rng.uniform(-1, 1) * big)))
            else:
                lines.append("G10 L20 P0 X%s Y%s" % (f(rng.uniform(-1, 1) * big), f(rng.uniform(-1, 1) * big)))
            if absolute and rng.random() < 0.5:
                lines.append("G0 X0 Y0 Z0")
                pos = [0.0, 0.0, 0.0]
            else:
                lines.append("G1 X%s" % f(rng.uniform(-1, 1) * big))
                pos = None
        elif kind < 0.92:
            cycle = rng.choice(["G81", "G82 P0.1", "G83 Q%s" % f(0.1 * big), "G73 Q%s" % f(0.07 * big),
                                "G85", "G89 P0.2"])
            retract = rng.choice(["G98", "G99"])
            if absolute:
                lines.append("%s %s X%s Y%s Z%s R%s L%d" % (retract, cycle, f(rng.uniform(-2, 2) * big),
                                                          f(rng.uniform(-2, 2) * big), f(-0.4 * big),
                                                          f(0.1 * big), rng.randint(1, 2)))
            else:
                lines.append("%s %s X%s Y%s Z%s R%s L%d" % (retract, cycle, f(0.3 * big), f(0.2 * big),
                                                          f(-0.4 * big), f(0.1 * big), rng.randint(1, 3)))
            lines.append("G80")
            pos = None if absolute else pos
            if absolute:
                lines.append("G0 X0 Y0 Z0")
                pos = [0.0, 0.0, 0.0]
        else:
            n = rng.randint(100, 999)
            lines.append("#1 = 0")
            lines.append("o%d while [#1 LT %d]" % (n, rng.randint(1, 4)))
            lines.append("G91 G1 X%s Y[#1 * %s]" % (f(0.1 * big), f(0.05 * big)))
            lines.append("#1 = [#1 + 1]")
            lines.append("o%d endwhile" % n)
            lines.append("G90 G0 X0 Y0 Z0" if absolute else "G91")
            if absolute:
                pos = [0.0, 0.0, 0.0]
    lines.append("M2")
    return "\n".join(lines) + "\n"


def default_tool_table(directory):
    path = os.path.join(directory, "oracle.tbl")
    with open(path, "w") as f:
        # Tools 1-254 with zero offsets: mach-vision's default table.
        for t in range(1, 255):
            f.write("T%d P%d Z0 D0\n" % (t, t))
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rs274", default=DEFAULT_RS274)
    ap.add_argument("--trace", default=DEFAULT_TRACE, help="the mach-vision binary")
    ap.add_argument("--units", default="mm", choices=["mm", "in"],
                    help="mach-vision's --machine-units (rs274 starts in mm: use mm to compare programs "
                         "that set no units)")
    ap.add_argument("--subroutine-path", default=None,
                    help="rs274's SUBROUTINE_PATH (default: each program's folder)")
    ap.add_argument("--tool-table", default=None, help="rs274's tool table (default: tools 1-254, zero offsets)")
    ap.add_argument("--timeout", type=float, default=30.0)
    ap.add_argument("--quiet", action="store_true", help="print only the summary")
    ap.add_argument("--random", type=int, default=0, metavar="N",
                    help="also compare N random programs (written to a temporary folder, kept)")
    ap.add_argument("--seed", type=int, default=1, help="seed of --random")
    ap.add_argument("--focus", type=float, default=0.0, metavar="SHARE",
                    help="share (0-1) of each random program's steps given to G10 L20/G52/G92 in "
                         "rotated systems, G53 inside canned cycles and full circles with P")
    ap.add_argument("--carry", type=float, default=0.0, metavar="SHARE",
                    help="share (0-1) of each random program's steps given to rotation changes with "
                         "G52/G92 in force followed by G54-G59, parameter writes or G43.1/G49 and then "
                         "G28/G30 or a G91 move (issue 33)")
    ap.add_argument("--strict", action="store_true",
                    help="also fail (exit 1) when only one side refuses a program (for the cases/ set)")
    ap.add_argument("programs", nargs="*")
    a = ap.parse_args()
    if a.random:
        rng = random.Random(a.seed)
        folder = tempfile.mkdtemp(prefix="oracle-random-")
        for i in range(a.random):
            path = os.path.join(folder, "random-%04d.ngc" % i)
            with open(path, "w") as f:
                f.write(random_program(rng, a.focus, a.carry))
            a.programs.append(path)
    with tempfile.TemporaryDirectory(prefix="oracle-tbl-") as tbl_dir:
        tool_table = a.tool_table or default_tool_table(tbl_dir)
        verdicts = collections.Counter()
        reasons = collections.Counter()
        inch_only = a.units == "mm" and not honours_machine_units(a.rs274, tool_table, a.timeout)
        for program in a.programs:
            with open(program, encoding="latin-1") as f:
                if inch_only and LENGTH_PARAMETERS in f.read():
                    verdicts["skipped"] += 1
                    if not a.quiet:
                        print("%-13s %s: it writes length parameters, which this rs274 keeps in inches "
                              "(LinuxCNC issue #1279; compare with --units in)" % ("skipped", program))
                    continue
            sub_path = a.subroutine_path or os.path.dirname(os.path.abspath(program))
            theirs, their_error = run_rs274(a.rs274, os.path.abspath(program), a.units, tool_table, sub_path, a.timeout)
            ours, our_error = run_trace(a.trace, program, a.units, sub_path, a.timeout)
            if their_error is not None:
                verdict = "both-refuse" if our_error is not None else "rs274-refuses"
                detail = their_error if our_error is None else "%s | ours: %s" % (their_error, our_error)
                # Refused by both, yet a move before the refusals may still go elsewhere.
                both = our_error is not None and None not in (theirs, ours)
                diff = compare(theirs, ours, prefix=True) if both else None
                if diff:
                    verdict, detail = "differ", "before both refuse (%s): %s" % (their_error, diff)
            else:
                if our_error is not None:
                    verdict, detail = "refused", our_error
                    reasons[re.sub(r"^.*?line \d+(, column \d+)?: ", "", our_error)[:90]] += 1
                else:
                    diff = compare(theirs, ours)
                    verdict, detail = ("differ", diff) if diff else ("agree", "%d motions" % len(ours))
            verdicts[verdict] += 1
            if not a.quiet:
                print("%-13s %s: %s" % (verdict, program, detail))
        print("# %d programs: %s" % (len(a.programs), ", ".join(
            "%d %s" % (verdicts[k], k) for k in ("agree", "differ", "refused", "both-refuse", "rs274-refuses")))
              + (", %d skipped" % verdicts["skipped"] if verdicts["skipped"] else ""))
        if reasons and not a.quiet:
            print("# mach-vision's refusals, most frequent first:")
            for reason, n in reasons.most_common(25):
                print("#   %4d  %s" % (n, reason))
        failed = verdicts["differ"] + (verdicts["refused"] + verdicts["rs274-refuses"] if a.strict else 0)
        return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
