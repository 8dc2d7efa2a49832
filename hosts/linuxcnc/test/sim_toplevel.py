"""The tests' [PYTHON] TOPLEVEL: the shipped one (remap, oword), then a simulated session behind
the remap (mach_vision built with the `sim` feature) and a Host that also tells the machine
position, so that the simulated camera looks from where rs274's machine is.

MACH_VISION_SIM (JSON) gives `Session.simulated`'s arguments: camera ("sim" or "keyence"),
rotation_deg, shift [x, y], scale [x, y], params {name: value}.
"""

import json
import os

import mach_vision
import oword  # noqa: F401  (LinuxCNC looks the O-word procedures up in `oword`)
import remap

from canon import machine_xy


class SimHost(remap.Host):
    """remap.Host plus machine_position(), which only the simulated camera asks for."""

    def machine_position(self):
        """Machine X, Y, Z (program units) by LinuxCNC's canon; current_x follows
        self.execute() within a handler, where #5420 lags. Z (no rotation acts on it) is what
        the simulated camera's working distance follows."""
        i = self._interp
        x, y = machine_xy(
            (i.origin_offset_x, i.origin_offset_y),
            i.rotation_xy,
            (i.current_x, i.current_y),
            (i.axis_offset_x, i.axis_offset_y),
            (i.tool_offset.x, i.tool_offset.y),
        )
        return (x, y, i.origin_offset_z + i.current_z + i.axis_offset_z + i.tool_offset.z)


def simulated(config):
    """Session.simulated from a JSON-shaped config (lists where it takes pairs)."""
    pairs = {k: tuple(v) for k, v in config.items() if k in ("shift", "scale")}
    return mach_vision.Session.simulated(**{**config, **pairs})


remap.install(simulated(json.loads(os.environ.get("MACH_VISION_SIM", "{}"))), SimHost)
