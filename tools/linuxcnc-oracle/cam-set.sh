#!/bin/sh
# Copies LinuxCNC's CAM-style test programs (tests/trajectory-planner/circular-arcs/nc_files)
# into target/linuxcnc-oracle/circular-arcs/ from a local copy of LinuxCNC's repository: the
# git directory given as $1 (or $LINUXCNC_GIT), e.g. the snapshot the search tool's `fetch`
# brings. This machine reaches no code host, so nothing is cloned. The programs are LinuxCNC's:
# read from there, never committed here.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
dest="$root/target/linuxcnc-oracle/circular-arcs"
if [ -d "$dest/tests" ]; then
    echo "$dest"
    exit 0
fi
git_dir=${1:-${LINUXCNC_GIT:-}}
if [ -z "$git_dir" ]; then
    echo "cam-set.sh: give LinuxCNC's git directory (argument or LINUXCNC_GIT)" >&2
    exit 2
fi
mkdir -p "$dest"
git --git-dir="$git_dir" archive HEAD tests/trajectory-planner/circular-arcs/nc_files | tar -x -C "$dest"
echo "$dest"
