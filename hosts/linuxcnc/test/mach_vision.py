"""A stand-in for vision-py's `mach_vision`, in pure Python, so that the remap plumbing is proven
through LinuxCNC's own interpreter before the Rust extension exists. Not the product: its M282
is a plain similarity fit written here, so the test checks, independently of the Rust dialect
code, that G10 L2 P0 R + G52 land the marks through rs274's offsets.

The interface is the one vision-py must offer (see ../README.md): `Session(profile)`,
`call(mcode, words, host)` for M280/M281/M282/M284, `walk_begin/walk_next/walk_capture/
walk_finish` for M283, and `VisionError` with the operator's message.

Its camera sees a simulated part, set by environment variables:
  MACH_VISION_FAKE_PART="rot_deg,dx,dy,scale"  the part is the program rotated about the origin
                                              (degrees), scaled, then shifted (default 0,0,0,1)
  MACH_VISION_FAKE_NG=k                        the k-th capture (from 1) answers NG
  MACH_VISION_FAKE_SCALE_GATE=pct              M282's scale gate, percent (default 2)
"""

import cmath
import math
import os

# Persistent parameters (listed in the var file): an alignment is active, and the G5x rotation
# it replaced. vision-host picks the real numbers; the fake uses these.
ACTIVE = 3990
BASE_ROTATION = 3991
WALK_CAPTURES = 3992


class VisionError(Exception):
    """A vision M-code failed; the message is the operator's."""


class Session:
    """One vision session per interpreter."""

    def __init__(self, profile=None):
        rot, dx, dy, scale = (float(v) for v in os.environ.get("MACH_VISION_FAKE_PART", "0,0,0,1").split(","))
        self._linear = scale * cmath.exp(1j * math.radians(rot))
        self._shift = complex(dx, dy)
        self._ng_at = int(os.environ.get("MACH_VISION_FAKE_NG", "0"))
        self._gate_pct = float(os.environ.get("MACH_VISION_FAKE_SCALE_GATE", "2"))
        self._captures = 0
        self._dots = []
        self._walk = []
        self._walked = []

    def call(self, mcode, words, host):
        handlers = {280: self._m280, 281: self._m281, 282: self._m282, 284: self._m284}
        handlers[mcode](words, host)

    def _base_rotation(self, host):
        return host.pound(BASE_ROTATION) if host.pound(ACTIVE) == 1 else host.xy_rotation_deg()

    def _cancel(self, host):
        base = self._base_rotation(host)
        host.execute("G52 X0 Y0")
        host.execute("G10 L2 P0 R%.9f" % base)
        host.set_pound(ACTIVE, 0)
        return base

    def _m280(self, words, host):
        base = self._cancel(host)
        self._dots = []
        host.message("M280: run begun, alignment cancelled, G5x rotation %.6f" % base)

    def _capture(self, host):
        self._captures += 1
        if self._captures == self._ng_at:
            raise VisionError("camera answered NG (no mark found); check the mark, the light and the job")
        x, y = host.program_position()
        commanded = complex(x, y)
        return commanded, self._linear * commanded + self._shift

    def _m281(self, words, host):
        commanded, observed = self._capture(host)
        self._dots.append((commanded, observed))
        host.message("M281: dot %d at X%.4f Y%.4f" % (len(self._dots), observed.real, observed.imag))

    def _m282(self, words, host):
        if len(self._dots) < 2:
            raise VisionError("M282 needs at least 2 dots, got %d; capture more marks" % len(self._dots))
        n_bar = sum(n for n, _ in self._dots) / len(self._dots)
        o_bar = sum(o for _, o in self._dots) / len(self._dots)
        a = sum((o - o_bar) * (n - n_bar).conjugate() for n, o in self._dots) / sum(
            abs(n - n_bar) ** 2 for n, _ in self._dots
        )
        dev_pct = abs(abs(a) - 1) * 100
        if self._gate_pct > 0 and dev_pct > self._gate_pct:
            raise VisionError(
                "LinuxCNC cannot scale: the fit's scale %.6f deviates %.4f %% from 1, more than the "
                "scale gate of %g %%" % (abs(a), dev_pct, self._gate_pct)
            )
        base = self._base_rotation(host)
        turn = a / abs(a)
        # The rigid part keeps the centroid: p -> turn*p + t'; LinuxCNC adds G52 before rotating.
        g52 = turn.conjugate() * (o_bar - turn * n_bar)
        host.execute("G10 L2 P0 R%.9f" % (base + math.degrees(cmath.phase(turn))))
        host.execute("G52 X%.7f Y%.7f" % (g52.real, g52.imag))
        host.set_pound(ACTIVE, 1)
        host.set_pound(BASE_ROTATION, base)
        host.message("M282: aligned, ignored scale %.6f" % abs(a))

    def _m284(self, words, host):
        host.message("M284: job %d" % int(words.get("p", 0)))

    def walk_begin(self, words, host):
        x, y = host.program_position()
        if "q" in words:
            # Axis detect (+0.1 in X, then +0.1 in Y), then the dot again.
            self._walk = [(x, y), (x + 0.1, y), (x + 0.1, y + 0.1), (x, y)]
        elif "c" in words:
            self._walk = [(x + 0.5 * i, y + 0.5 * j) for j in range(3) for i in range(3)]
        else:
            raise VisionError("M283 needs Qd (one dot of diameter d) or Cn (sheet n)")
        self._walked = []

    def walk_next(self, host):
        return self._walk[len(self._walked)] if len(self._walked) < len(self._walk) else None

    def walk_capture(self, host):
        self._walked.append(self._capture(host))

    def walk_finish(self, host):
        host.set_pound(WALK_CAPTURES, len(self._walked))
        host.message("M283: %d captures" % len(self._walked))
