"""LinuxCNC's canon for the tests: where a programmed XY puts the machine (emccanon.cc
rotate_and_offset_pos, plus the tool offset G43 applies):

    machine = g5x + R(rotation)·(p + g92) + tool

check.py applies it to rs274's canonical calls; the simulated session's Host (sim_toplevel.py)
applies it to the interpreter's own state, to put the simulated camera where rs274's machine is.
"""

import math


def machine_xy(g5x, rotation_deg, p, g92, tool):
    """Machine X, Y of program point `p` under G5x origin `g5x`, its XY rotation `rotation_deg`
    (degrees counter-clockwise), the G92/G52 offset `g92` and the tool's X, Y offset `tool`."""
    c, s = math.cos(math.radians(rotation_deg)), math.sin(math.radians(rotation_deg))
    px, py = p[0] + g92[0], p[1] + g92[1]
    return (g5x[0] + c * px - s * py + tool[0], g5x[1] + s * px + c * py + tool[1])
