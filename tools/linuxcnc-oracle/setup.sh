#!/bin/sh
# Obtains LinuxCNC's standalone interpreter `rs274` (Debian's linuxcnc-uspace, not installed:
# unpacked) into target/linuxcnc-oracle/, for compare.py. Needs apt (Debian 12) and root for the
# one library it installs. Idempotent: a second run does nothing.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
cache="$root/target/linuxcnc-oracle"
if [ -x "$cache/x/usr/bin/rs274" ]; then
    echo "$cache/x/usr/bin/rs274"
    exit 0
fi
mkdir -p "$cache"
cd "$cache"
apt-get update -qq
# rs274 links libboost_python; the rest of the package's dependencies are not needed for it.
apt-get install -y -qq libboost-python1.74.0 >/dev/null
rm -f linuxcnc-uspace_*.deb
apt-get download linuxcnc-uspace
dpkg -x linuxcnc-uspace_*.deb x
echo "$cache/x/usr/bin/rs274"
