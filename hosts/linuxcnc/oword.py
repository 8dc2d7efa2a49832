"""Python O-word procedures for m283.ngc (the M283 walk).

O-word procedures cannot yield (rs274 stops with "Unknown error, bad error code" when one
does), so this one only plans the next point; the capture is M289, a remap that can wait for
the machine.
"""

from mach_vision import VisionError
from remap import fail, host_for, is_task, session


def vision_walk_next(self, *args):
    """Asks the session for the next target of the walk: sets #<_vision_x>, #<_vision_y> and
    #<_vision_lift> (the height above the Z the walk started at: 0, or VisionCalibrationLift
    while the calibration lift reads; program units) and returns 1, or returns 0 when the walk
    is over. A failed walk stops the program with the message (set_errormsg and INTERP_ERROR,
    as a remap does)."""
    if not is_task(self):
        return 0.0
    try:
        target = session().walk_next(host_for(self))
    except VisionError as e:
        return fail(self, 283, e)
    if target is None:
        return 0.0
    self.params["_vision_x"], self.params["_vision_y"], self.params["_vision_lift"] = target
    return 1.0
