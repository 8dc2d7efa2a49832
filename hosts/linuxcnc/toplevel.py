# LinuxCNC loads this file once per interpreter ([PYTHON] TOPLEVEL=). The remap handlers live in
# `remap`, the Python O-word procedures the sheet walk calls in `oword`: LinuxCNC looks both up
# under those names.
import remap  # noqa: F401
import oword  # noqa: F401
