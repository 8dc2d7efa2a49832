#!/bin/sh
# The LinuxCNC remap test: obtains rs274 (Debian's linuxcnc-uspace, unpacked by
# tools/linuxcnc-oracle/setup.sh; needs apt and root once), builds the mach_vision module
# (vision-py) as shipped, linking no libpython, plus the tests' simulated camera (feature
# `sim`), and runs check.py against both (and the CLI's `panel --profile` on the folder the
# module publishes).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
target="${CARGO_TARGET_DIR:-$root/target}"
rs274=$(sh "$root/tools/linuxcnc-oracle/setup.sh" | tail -n 1)

PYO3_BUILD_EXTENSION_MODULE=1 cargo build --quiet --manifest-path "$root/Cargo.toml" -p vision-py --features sim
module="$target/linuxcnc-test/module"
mkdir -p "$module"
cp "$target/debug/libvision_py.so" "$module/mach_vision.abi3.so"
# The module must take Python from the process that imports it (LinuxCNC), never bring its own.
if ldd "$module/mach_vision.abi3.so" | grep -q 'libpython'; then
    echo "run.sh: mach_vision.abi3.so links libpython; build it with PYO3_BUILD_EXTENSION_MODULE=1" >&2
    exit 1
fi
# The panel beside the controller: `mach-vision panel --profile` shows what the module published.
cargo build --quiet --manifest-path "$root/Cargo.toml" -p vision-cli
exec python3 "$here/check.py" --rs274 "$rs274" --module "$module" --cli "$target/debug/mach-vision"
