#!/usr/bin/env bash
# The shipped mach_vision module in Debian's stock lua5.3: built with the `module` feature (no
# Lua linked in), loaded with a plain `require`, and the real m280.mcs / m281.mcs run against a
# minimal fake `mc` (load_test.lua). Proves the library is a real native Lua 5.3 module outside
# the cargo test harness. Installs lua5.3 with apt-get when it is missing (needs root).
#
#   bash hosts/mach4/test/load-test.sh
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
target="${CARGO_TARGET_DIR:-$root/target}"

if ! command -v lua5.3 >/dev/null 2>&1; then
    echo "load-test: installing lua5.3" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -qq lua5.3 >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq lua5.3; }
fi

cargo build --quiet --manifest-path "$root/Cargo.toml" -p vision-lua --no-default-features --features module

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# `require("mach_vision")` looks for mach_vision.so (mach_vision.dll on Windows).
cp "$target/debug/libmach_vision.so" "$work/mach_vision.so"
mkdir -p "$work/Profiles/LoadTest"

# The module must take Lua from the process that loads it, never bring its own.
if ldd "$work/mach_vision.so" | grep -qi 'liblua'; then
    echo "load-test: mach_vision.so links a Lua library; build it with --features module" >&2
    exit 1
fi
if nm -D --defined-only "$work/mach_vision.so" | grep -qw 'lua_newstate'; then
    echo "load-test: mach_vision.so carries its own Lua; build it with --no-default-features" >&2
    exit 1
fi

lua5.3 "$root/hosts/mach4/test/load_test.lua" "$work" "$root/hosts/mach4/Macros"

# The panel beside the controller: `mach-vision panel --profile` on the folder the module left
# shows its last call (M281's refusal as Why NG?) and the folder's sequence number.
cargo build --quiet --manifest-path "$root/Cargo.toml" -p vision-cli
"$target/debug/mach-vision" panel --profile "$work/Profiles/LoadTest/MachVision.toml" --listen 127.0.0.1:0 \
    >"$work/panel.out" 2>&1 &
panel_pid=$!
trap 'kill "$panel_pid" 2>/dev/null; rm -rf "$work"' EXIT
python3 "$root/hosts/mach4/test/panel_check.py" "$work/panel.out" "$work/Profiles/LoadTest/MachVision.panel/state.json"
