#!/bin/sh
# Fetches LinuxCNC's CAM-style test programs (tests/trajectory-planner/circular-arcs/nc_files)
# into target/linuxcnc-oracle/circular-arcs/ with a sparse, shallow clone. They are LinuxCNC's,
# not ours: they are read from there, never committed here.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
dest="$root/target/linuxcnc-oracle/circular-arcs"
if [ -d "$dest/tests" ]; then
    echo "$dest"
    exit 0
fi
mkdir -p "$dest"
git clone -q --depth 1 --filter=blob:none --sparse https://github.com/LinuxCNC/linuxcnc.git "$dest/clone"
git -C "$dest/clone" sparse-checkout set tests/trajectory-planner/circular-arcs/nc_files
mv "$dest/clone/tests" "$dest/tests"
rm -rf "$dest/clone"
echo "$dest"
