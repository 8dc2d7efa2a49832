# The probe's TOPLEVEL. LinuxCNC looks the handlers up in a module named `remap`.
import remap  # noqa: F401
