#!/bin/sh
# The LinuxCNC remap test: obtains rs274 (Debian's linuxcnc-uspace, unpacked by
# tools/linuxcnc-oracle/setup.sh; needs apt and root once) and runs check.py against it.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
rs274=$(sh "$root/tools/linuxcnc-oracle/setup.sh" | tail -n 1)
exec python3 "$here/check.py" --rs274 "$rs274"
