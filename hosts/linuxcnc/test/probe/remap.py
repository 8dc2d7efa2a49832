"""Remap handlers that print what rs274 does (check.py's "probe" case reads the lines).

M281: prints self.task and the words, then self.execute("G0 X5 Y6").
M282: a generator: self.execute("G0 X1 Y2"), yield INTERP_EXECUTE_FINISH, then tries
      self.execute("G0 X7 Y8") and prints whether rs274 accepted it; prints #5420 and current_x.
"""

from interpreter import INTERP_EXECUTE_FINISH, INTERP_OK


def m281(self, **words):
    print("probe: m281 task=%d words=%r" % (self.task, sorted(words.items())), flush=True)
    self.execute("G0 X5 Y6")
    return INTERP_OK


def m282(self, **words):
    self.execute("G0 X1 Y2")
    print("probe: before-yield #5420=%g current_x=%g" % (self.params[5420], self.current_x), flush=True)
    yield INTERP_EXECUTE_FINISH
    status = self.execute("G0 X7 Y8")
    print("probe: execute-after-yield status=%d" % status, flush=True)
    yield INTERP_OK
