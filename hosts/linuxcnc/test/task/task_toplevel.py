"""The real-task tests' [PYTHON] TOPLEVEL: the shipped remaps (remap, oword) with a simulated
camera behind them, in a running LinuxCNC (milltask, motion, HAL).

* The simulated world changes per case without restarting LinuxCNC: the driver writes
  `world.json` ({"case", "world", "sim"}: the case's name, its world's id and
  Session.simulated's arguments) in $MACH_VISION_TASK_DIR before each program; the first
  vision M-code under a new world id builds that world's session (cases with one id share it).
* The module is $MACH_VISION_TEST_MODULE's (with the `sim` feature), ahead of an installed one.
* The Host is sim_toplevel's (the simulated head is parked where the interpreter's machine is,
  by LinuxCNC's canon) and, at every capture, logs that position beside the one
  `linuxcnc.stat` reports, to `captures.jsonl`: the check holds them together.

The task imports its TOPLEVEL twice into one namespace, so everything here can run twice.
"""

import json
import os
import sys

import linuxcnc

# The tests' module (built with the simulated camera) ahead of any installed one: [PYTHON]
# PATH_PREPEND puts the installed folder first.
if sys.path[0] != os.environ["MACH_VISION_TEST_MODULE"]:
    sys.path.insert(0, os.environ["MACH_VISION_TEST_MODULE"])

import oword  # noqa: F401  (LinuxCNC looks the O-word procedures up in TOPLEVEL's `oword`)
import remap
import sim_toplevel

DIR = os.environ["MACH_VISION_TASK_DIR"]
_STAT = linuxcnc.stat()
_SHIPPED_SESSION = getattr(remap, "_shipped_session", remap.session)
remap._shipped_session = _SHIPPED_SESSION
_WORLD = {"world": None, "case": None}


class TaskHost(sim_toplevel.SimHost):
    """SimHost that logs each synced machine_position() (a capture) with stat's position."""

    def machine_position(self):
        x, y, z = sim_toplevel.SimHost.machine_position(self)
        if self._synced:
            _STAT.poll()
            record = {
                "case": _WORLD["case"],
                "canon": [x, y],
                "metric": self.metric(),
                "position": list(_STAT.position[:2]),
                "actual": list(_STAT.actual_position[:2]),
                "rewaits": remap.arrival_rewaits,
            }
            with open(os.path.join(DIR, "captures.jsonl"), "a") as f:
                f.write(json.dumps(record) + "\n")
        return (x, y, z)


def session():
    """remap.session(), with the world of the case the driver runs now."""
    with open(os.path.join(DIR, "world.json")) as f:
        world = json.load(f)
    if world["world"] != _WORLD["world"]:
        remap.install(sim_toplevel.simulated(world["sim"]), TaskHost)
        _WORLD["world"] = world["world"]
    _WORLD["case"] = world["case"]
    return _SHIPPED_SESSION()


remap.session = session
# Which files the task loaded: the check holds them to --host (the checkout or the package).
with open(os.path.join(DIR, "loaded.json"), "w") as f:
    json.dump({"remap": remap.__file__, "oword": oword.__file__, "mach_vision": sys.modules["mach_vision"].__file__}, f)
