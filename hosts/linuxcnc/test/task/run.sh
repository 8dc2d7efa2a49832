#!/bin/sh
# The real-task stage of scripts/test: LinuxCNC 2.9's task, motion and HAL, headless, with the
# remaps and the real module on a simulated camera (run.py), then the Debian package built
# (scripts/package-deb, which also checks that every path the docs it holds name is in it),
# installed with dpkg -i and run the same way from the installed files.
# Installs linuxcnc-uspace with apt-get when LinuxCNC is missing (root; Debian 12). The package
# is removed again at the end unless it was installed before.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../../.." && pwd)
target="${CARGO_TARGET_DIR:-$root/target}"
start=$(date +%s)

if ! command -v linuxcnc >/dev/null 2>&1; then
    echo "task: installing linuxcnc-uspace (apt-get)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends linuxcnc-uspace >/dev/null
fi

# The module as shipped (no libpython), with the tests' simulated camera (feature `sim`).
PYO3_BUILD_EXTENSION_MODULE=1 cargo build --quiet --manifest-path "$root/Cargo.toml" -p vision-py --features sim
module="$target/linuxcnc-task-module"
mkdir -p "$module"
cp "$target/debug/libvision_py.so" "$module/mach_vision.abi3.so"
work="$target/linuxcnc-task"

# The package (release builds) first: built beside the LinuxCNC runs it starved their
# non-real-time task and motion on a 2-core machine (homing and moves timed out).
deb=$(bash "$root/scripts/package-deb" "$target/deb" | tail -n 1)
# (sh has no pipefail: a package-deb that failed, e.g. on a doc naming a file the package lacks,
# printed no package path)
case "$deb" in *.deb) [ -f "$deb" ] ;; *) false ;; esac || { echo "task: scripts/package-deb failed" >&2; exit 1; }
python3 "$here/run.py" --module "$module" --work "$work"
installed_before=$(dpkg-query -W -f='${Status}' mach-vision 2>/dev/null || true)
dpkg -i "$deb" >/dev/null
cleanup() {
    case "$installed_before" in
        *" installed") ;;
        *) dpkg -r mach-vision >/dev/null ;;
    esac
}
trap cleanup EXIT
lib=/usr/lib/mach-vision/linuxcnc
mach-vision --version
# The installed module is the shipped one: no libpython, no simulated camera.
if ldd "$lib/mach_vision.abi3.so" | grep -q libpython; then
    echo "task: the installed module links libpython" >&2
    exit 1
fi
python3 -c "
import sys
sys.path.insert(0, '$lib')
import mach_vision
assert not hasattr(mach_vision.Session, 'simulated'), 'the package ships the simulated camera'
print('task: installed mach_vision', mach_vision.__version__, 'from', mach_vision.__file__)
"
python3 "$here/run.py" --module "$module" --work "$work" --installed "$lib"
rm -rf "$work"
# Removal leaves nothing, also where Python cached the remaps beside them (as it does when
# LinuxCNC runs as root; the runs above set PYTHONDONTWRITEBYTECODE): the package's prerm.
case "$installed_before" in
    *" installed") ;;
    *)
        python3 -m compileall -q "$lib"
        [ -d "$lib/__pycache__" ] || { echo "task: compileall left no $lib/__pycache__" >&2; exit 1; }
        trap - EXIT
        dpkg -r mach-vision >/dev/null
        if [ -e /usr/lib/mach-vision ]; then
            echo "task: dpkg -r mach-vision left /usr/lib/mach-vision:" >&2
            find /usr/lib/mach-vision | head -n 5 >&2
            exit 1
        fi
        echo "task: dpkg -r removed the package and its __pycache__"
        ;;
esac
echo "task: the stage took $(( $(date +%s) - start )) s"
