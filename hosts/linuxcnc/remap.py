"""LinuxCNC remap handlers for the vision M-codes M280-M284, and M289, the capture step of the
M283 walk (m283.ngc).

Thin on purpose: every decision is the session's (`mach_vision.Session`, the vision-py extension
over vision-host). This file maps LinuxCNC's interpreter onto the `Host` interface the session
calls, and honours read-ahead and preview:

* A capture (M281, M289) first yields INTERP_EXECUTE_FINISH so that it runs where the machine
  really is. G-code a handler runs (self.execute) is only queued: M281's re-centring moves are
  handed back to the task and the handler yields again until the machine is there (LinuxCNC
  2.9's task runs G-code queued after the yield).
* In preview (self.task == 0: AXIS's preview, rs274) there is no camera: every vision M-code
  reports and emits nothing. MACH_VISION_RS274_AS_TASK=1 makes rs274 count as the task; only
  the tests set it.
"""

import math
import os
import time

import emccanon
from interpreter import INTERP_ERROR, INTERP_EXECUTE_FINISH, INTERP_OK

import mach_vision
from mach_vision import VisionError

_SESSION = None


def session():
    """The one session of this interpreter, created at the first vision M-code."""
    global _SESSION
    if _SESSION is None:
        _SESSION = mach_vision.Session(os.environ.get("MACH_VISION_PROFILE"))
    return _SESSION


def is_task(interp):
    """True in the interpreter that drives the machine; False in a preview."""
    return interp.task != 0 or os.environ.get("MACH_VISION_RS274_AS_TASK") == "1"


class Host:
    """What the session needs of the controller (vision_core::Machine), over LinuxCNC's
    interpreter. Lengths are in the program's units (G20/G21), angles in degrees."""

    def __init__(self, interp, synced):
        self._interp = interp
        # True after `yield INTERP_EXECUTE_FINISH`: the machine is where the program says; a
        # dwell is then a wait here (a G4 would only be queued behind the capture).
        self._synced = synced

    def program_position(self):
        """Commanded X, Y in the active program frame (after G52/G92, G5x and its rotation)."""
        return (self._interp.current_x, self._interp.current_y)

    def xy_rotation_deg(self):
        """The active G5x system's rotation (G10 L2 R), degrees counter-clockwise."""
        return self._interp.rotation_xy

    def g92_offset(self):
        """The G92/G52 X, Y offset (program units)."""
        return (self._interp.axis_offset_x, self._interp.axis_offset_y)

    def metric(self):
        """True under G21."""
        return self._interp.params["_metric"] == 1.0

    def execute(self, line):
        """Queues one line of G-code (the interpreter's state follows at once, the machine when
        the handler yields or returns); VisionError when LinuxCNC refuses it."""
        try:
            status = self._interp.execute(line)
        except Exception:
            # LinuxCNC 2.9 raises its InterpreterException for a refused line, which Python
            # 3.11 shows as a SystemError; the interpreter's own message says why.
            status = None
        if status != INTERP_OK:
            raise VisionError("LinuxCNC refused %r: %s" % (line, self._interp.get_errormsg()))

    def _machine_to_program(self):
        """Program units per machine unit: the tool table is in the machine's units
        ([TRAJ]LINEAR_UNITS), the session works in the program's (G20/G21)."""
        machine_metric = self._interp.params["_metric_machine"] == 1.0
        if machine_metric == self.metric():
            return 1.0
        return 1.0 / 25.4 if machine_metric else 25.4

    def save_modal_state(self):
        """Before the module's own moves (M281's re-centring): M70 saves the distance, feed,
        plane, units and offsets modes; the motion mode, which M72 does not restore, is kept in
        #<_vision_saved_motion>. Refused under an arc or canned-cycle mode, which a bare word
        cannot set back."""
        motion = self._interp.params["_motion_mode"]
        if motion not in _MOTION_WORDS:
            raise VisionError(
                "cannot move to re-centre under G%g (its mode cannot be set back after the move): "
                "program G0, G1 or G80 before the capture, or set VisionRecenterPasses to 0" % (motion / 10.0)
            )
        self.execute("M70")
        self._interp.params["_vision_saved_motion"] = motion

    def restore_modal_state(self):
        """M72, then the motion mode saved_modal_state() kept."""
        self.execute("M72")
        motion = self._interp.params["_vision_saved_motion"]
        if self._interp.params["_motion_mode"] != motion:
            self.execute(_MOTION_WORDS[motion])

    def tool(self):
        """The tool in the spindle (0 when none)."""
        return max(self._interp.current_tool, 0)

    def tool_offset(self, tool):
        """Tool-table X, Y offset of `tool`, program units; VisionError when it is not there."""
        status, pocket = self._interp.find_tool_pocket(tool)
        if status != INTERP_OK:
            raise VisionError("tool %d is not in the tool table; add it" % tool)
        offset = self._interp.tool_table[pocket].offset
        scale = self._machine_to_program()
        return (offset.x * scale, offset.y * scale)

    def set_tool_offset(self, tool, x, y):
        """Writes the tool-table X, Y offset of `tool` (G10 L1)."""
        self.execute("G10 L1 P%d X%.7f Y%.7f" % (tool, x, y))

    def applied_tool_offset(self):
        """The X, Y tool offset G43 applies now (the active offset's tool-table values; zero
        under G49), program units: the session refuses a capture when it is not the camera
        tool's."""
        offset = self._interp.tool_offset
        try:
            return (offset.x, offset.y)
        except AttributeError:
            # A binding without the pose's x/y: the session then cannot tell, and checks nothing.
            return None

    def pound(self, number):
        """#number."""
        return self._interp.params[number]

    def set_pound(self, number, value):
        """#number = value, at once (the interpreter's own parameter table)."""
        self._interp.params[number] = value

    def dwell(self, seconds):
        """Waits: G4 while G-code can still be queued, a sleep after a sync."""
        if self._synced:
            time.sleep(seconds)
        else:
            self.execute("G4 P%.4f" % seconds)

    def message(self, text):
        """A message to the operator (AXIS shows it; rs274 prints MESSAGE)."""
        emccanon.MESSAGE(text)


# The motion modes (#<_motion_mode>: 10 × the G number) a bare word sets back.
_MOTION_WORDS = {0.0: "G0", 10.0: "G1", 800.0: "G80"}

# The Host class the handlers hand the session; install() replaces it.
_HOST_CLASS = Host


def install(session, host_class=Host):
    """Makes `session` this interpreter's session and `host_class` (a Host subclass) the Host the
    handlers hand it: how the tests put a simulated camera behind the remap."""
    global _SESSION, _HOST_CLASS
    _SESSION, _HOST_CLASS = session, host_class


def host_for(interp, synced=False):
    """The Host over `interp`."""
    return _HOST_CLASS(interp, synced)


def fail(interp, mcode, error):
    """Stops the program with "M<mcode>: <error>" (a remap's or an O-word procedure's return);
    a message that already names the M-code ("M280 P5 is invalid: …") is shown as it is."""
    text = str(error)
    interp.set_errormsg(text if text.startswith("M%d " % mcode) else "M%d: %s" % (mcode, text))
    return INTERP_ERROR


def _call(interp, mcode, words, synced):
    try:
        session().call(mcode, words, host_for(interp, synced))
    except VisionError as e:
        return fail(interp, mcode, e)
    return INTERP_OK


def _preview(interp, mcode):
    emccanon.MESSAGE("M%d: preview, no camera: nothing done" % mcode)
    return INTERP_OK


# A capture triggers only once linuxcnc.stat puts the machine within this of where the
# interpreter put it, inches.
ARRIVAL_TOLERANCE_IN = 1e-5
# How many more times a capture waits for the machine (each wait at least one task cycle).
ARRIVAL_WAITS = 500
# Extra waits so far in this interpreter (the tests report it).
arrival_rewaits = 0
_STAT = []


def _stat():
    """linuxcnc.stat() of the running LinuxCNC, or None where there is none."""
    if not _STAT:
        try:
            import linuxcnc

            stat = linuxcnc.stat()
            stat.poll()
            _STAT.append(stat)
        except Exception:
            _STAT.append(None)
    return _STAT[0]


def machine_xy(interp):
    """Where the interpreter has put the machine: X, Y in the machine's units, by LinuxCNC's
    canon (g5x + R(rotation)·(p + g92) + tool)."""
    c, s = math.cos(math.radians(interp.rotation_xy)), math.sin(math.radians(interp.rotation_xy))
    px, py = interp.current_x + interp.axis_offset_x, interp.current_y + interp.axis_offset_y
    x = interp.origin_offset_x + c * px - s * py + interp.tool_offset.x
    y = interp.origin_offset_y + s * px + c * py + interp.tool_offset.y
    machine_metric, metric = interp.params["_metric_machine"] == 1.0, interp.params["_metric"] == 1.0
    scale = 1.0 if machine_metric == metric else (25.4 if machine_metric else 1.0 / 25.4)
    return (x * scale, y * scale)


def wait_for_machine(interp):
    """Generator (`yield from`): waits for the queued motion (INTERP_EXECUTE_FINISH), then, in
    the task, until linuxcnc.stat shows the machine where the interpreter put it. Returns None,
    or the refusal when it never gets there.

    Why the second wait: on a loaded machine 2.9's task was seen to resume a handler after the
    yield before the last move had run, its interpreter resynchronised to the machine's old
    position (test/task/, one sheet walk in several): a trigger then would read the wrong
    place. Waiting again lets the move run and the interpreter resynchronise."""
    global arrival_rewaits
    yield INTERP_EXECUTE_FINISH
    stat = _stat() if interp.task else None
    if stat is None:
        return None
    per_inch = 25.4 if interp.params["_metric_machine"] == 1.0 else 1.0
    for _ in range(ARRIVAL_WAITS):
        stat.poll()
        if math.dist(stat.position[:2], machine_xy(interp)) <= ARRIVAL_TOLERANCE_IN * per_inch:
            return None
        arrival_rewaits += 1
        yield INTERP_EXECUTE_FINISH
    return "the machine did not arrive where the program put the camera (at %s, sent to %s, machine units)" % (
        tuple(round(v, 6) for v in stat.position[:2]),
        tuple(round(v, 6) for v in machine_xy(interp)),
    )


def m280(self, **words):
    """Begin a run: cancels any alignment (G52 X0 Y0, G10 L2 P0 R back to the rotation before)."""
    if not is_task(self):
        return _preview(self, 280)
    return _call(self, 280, words, synced=False)


def m281(self, **words):
    """Capture where the machine is: waits for the queued motion, then triggers. Re-centring
    (VisionRecenterPasses): the session queues a move over the mark and the handler waits for
    the machine again before the next trigger; the last step queues the move back and puts the
    modal state back (M70/M72)."""
    if not is_task(self):
        yield _preview(self, 281)
        return
    late = yield from wait_for_machine(self)
    if late:
        yield fail(self, 281, late)
        return
    try:
        moving = session().capture_begin(words, host_for(self, synced=True))
        while moving:
            late = yield from wait_for_machine(self)
            if late:
                raise VisionError(late)
            moving = session().capture_next(host_for(self, synced=True))
    except VisionError as e:
        yield fail(self, 281, e)
        return
    yield INTERP_OK


def m282(self, **words):
    """Fit and align: the session emits G10 L2 P0 R + G52 (LinuxCNC has no G68, no G51)."""
    if not is_task(self):
        return _preview(self, 282)
    return _call(self, 282, words, synced=False)


def m284(self, **words):
    """Switch the camera job."""
    if not is_task(self):
        return _preview(self, 284)
    return _call(self, 284, words, synced=False)


def m283_begin(self, **words):
    """M283's prolog: the session plans the walk (Q: one dot, P: a sheet, the manual's C; the
    session's LinuxCNC controller maps P to C and refuses C, naming P)."""
    if not is_task(self):
        return _preview(self, 283)
    try:
        session().walk_begin(words, host_for(self))
    except VisionError as e:
        return fail(self, 283, e)
    return INTERP_OK


def m289(self, **words):
    """The walk's capture, called by m283.ngc at each point: waits for the motion, triggers."""
    if not is_task(self):
        yield INTERP_OK
        return
    late = yield from wait_for_machine(self)
    if late:
        yield fail(self, 283, late)
        return
    try:
        session().walk_capture(host_for(self, synced=True))
    except VisionError as e:
        yield fail(self, 283, e)
        return
    yield INTERP_OK


def m283_finish(self, **words):
    """M283's epilog: solves and writes K and the camera tool offset, reports the residuals."""
    if not is_task(self):
        return INTERP_OK
    try:
        session().walk_finish(host_for(self))
    except VisionError as e:
        return fail(self, 283, e)
    return INTERP_OK
