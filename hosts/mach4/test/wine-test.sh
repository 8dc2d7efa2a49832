#!/usr/bin/env bash
# The Windows build under Wine: what a Mach4 integrator installs, run on Windows' own terms.
#
#   bash hosts/mach4/test/wine-test.sh [LINUX_MACH_VISION]
#
# 1. Builds Windows Lua 5.3.6 (lua.exe + lua53.dll, the DLL name Mach4 exports its Lua under;
#    see ../WINDOWS.md) from Debian's lua5.3 source package, with MinGW-w64, and the shipped
#    artifacts with scripts/build-windows (mach_vision.dll, mach-vision.exe, the zip; the zip's
#    docs are checked to name only files the zip holds: scripts/packaging/package.py).
# 2. Loads the shipped mach_vision.dll with `require` into that lua.exe under Wine and runs the
#    real m280.mcs / m281.mcs against a minimal fake `mc` (load_test.lua, as load-test.sh does in
#    Linux's lua5.3): a success, and a refusal that reaches mcCntlSetLastError and stops the cycle;
#    then m284.mcs through the Keyence driver, over Windows sockets, to the shipped
#    mach-vision.exe's emulator (`emulate`), and to a port nothing answers (refused, cycle stopped).
# 3. Runs mach-vision.exe on examples 1-8 under Wine: its standard output and exit code must be
#    byte for byte those of the Linux build (LINUX_MACH_VISION, default target/debug/mach-vision,
#    built when missing), both on one fixed clock (`--clock`: M283 prints its calibration date).
# 4. Runs, under Wine, the tests of vision-driver-keyence (the client against the scripted mock
#    and the emulator over loopback TCP) and of vision-lua: the real, unmodified Macros/m28x.mcs in
#    Lua 5.3.6 compiled for Windows, full cycles of examples 1, 2, 4, 5 and 7 on the simulated
#    camera and on the Keyence driver against its emulator, compared with `mach-vision run`'s run
#    path, and the refusals (NG, K = 0, wrong tool) that must stop the cycle.
#
# Everything is built for the same target as the shipped files (x86_64-win7-windows-gnu unless
# MACH_VISION_WINDOWS_TARGET says otherwise) in release, so the standard library is built once.
# Installs wine64, MinGW-w64 and Debian's Rust 1.96 with apt-get when missing (needs root).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
triple="${MACH_VISION_WINDOWS_TARGET:-x86_64-win7-windows-gnu}"
win="$root/target/windows"
linux_exe="${1:-$root/target/debug/mach-vision}"
case "$linux_exe" in /*) ;; *) linux_exe="$PWD/$linux_exe" ;; esac
say() { echo "wine-test: $*" >&2; }
started=$SECONDS

if [ ! -x /usr/lib/wine/wine64 ] || ! command -v make >/dev/null; then
    say "installing wine64 and make"
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -qq --no-install-recommends wine64 make >/dev/null 2>&1 \
        || { apt-get update -qq && apt-get install -y -qq --no-install-recommends wine64 make; }
fi
wine=/usr/lib/wine/wine64
# A prefix of our own under target/, quiet, and no prompts for Wine's Mono and Gecko.
export WINEPREFIX="$win/wineprefix" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml="
mkdir -p "$win"
# Wine makes its prefix on first use; start it now, beside the builds.
"$wine" cmd /c exit >/dev/null 2>&1 &
prefix_pid=$!

# The Linux build: compared with in 3, and it draws the zip's calibration sheet in 1a.
if [ ! -x "$linux_exe" ]; then
    cargo build --quiet --manifest-path "$root/Cargo.toml" -p vision-cli
    linux_exe="$root/target/debug/mach-vision"
fi

# 1a. The shipped files and the zip, whose docs are checked to name only files it holds (also
# installs MinGW-w64 and Debian's Rust when missing).
# (against lua53.dll, the Lua built below, whatever MACH4_LUA_DLL says)
MACH4_LUA_DLL="" MACH_VISION_LINUX_CLI="$linux_exe" "$root/scripts/build-windows"

# 1b. Windows Lua 5.3.6 from Debian's source package (its signed index vouches for the tarball),
#     fetched through a private apt configuration with a deb-src line; built once per target/.
lua="$win/lua53"
if [ ! -f "$lua/lua.exe" ] || [ ! -f "$lua/lua53.dll" ]; then
    say "building Windows Lua 5.3 from Debian's lua5.3 source"
    apt_dir="$win/apt"
    rm -rf "$apt_dir" && mkdir -p "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial" "$apt_dir/parts" "$apt_dir/src"
    echo "deb-src [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] http://deb.debian.org/debian bookworm main" \
        >"$apt_dir/sources.list"
    apt_opts=(-o "Dir::State=$apt_dir" -o "Dir::State::Lists=$apt_dir/lists" -o "Dir::State::status=/var/lib/dpkg/status"
        -o "Dir::Cache=$apt_dir/cache" -o "Dir::Etc::SourceList=$apt_dir/sources.list" -o "Dir::Etc::SourceParts=$apt_dir/parts"
        -o "APT::Sandbox::User=root")
    apt-get "${apt_opts[@]}" update -qq
    (cd "$apt_dir/src" && apt-get "${apt_opts[@]}" source --download-only -qq lua5.3)
    tar -xzf "$apt_dir"/src/lua5.3_5.3.6.orig.tar.gz -C "$apt_dir/src"
    make -C "$apt_dir/src/lua-5.3.6/src" mingw CC=x86_64-w64-mingw32-gcc \
        AR="x86_64-w64-mingw32-ar rc" RANLIB=x86_64-w64-mingw32-ranlib >"$apt_dir/make.log" 2>&1 \
        || { cat "$apt_dir/make.log" >&2; exit 1; }
    mkdir -p "$lua"
    cp "$apt_dir/src/lua-5.3.6/src/lua.exe" "$apt_dir/src/lua-5.3.6/src/lua53.dll" "$lua/"
    rm -rf "$apt_dir"
fi
wait "$prefix_pid" || true

# 2. The shipped module in Windows' lua.exe.
out="$win/$triple/release"
work="$win/mach4-load-test"
rm -rf "$work" && mkdir -p "$work/Profiles/LoadTest"
cp "$lua/lua.exe" "$lua/lua53.dll" "$out/mach_vision.dll" "$work/"
# The camera: the shipped mach-vision.exe's Keyence emulator, on a free loopback port.
"$wine" "$out/mach-vision.exe" emulate --port 0 >"$work/emulate.out" 2>&1 &
emulator=$!
# Whatever happens, nothing of ours keeps running in the prefix.
trap 'kill "$emulator" 2>/dev/null || true; /usr/lib/wine/wineserver64 -k 2>/dev/null || true' EXIT
port=""
for _ in $(seq 100); do
    port="$(sed -n 's/^emulating a Keyence VS camera at 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$work/emulate.out")"
    [ -n "$port" ] && break
    kill -0 "$emulator" 2>/dev/null || break
    sleep 0.2
done
[ -n "$port" ] || { say "mach-vision.exe emulate did not start:"; cat "$work/emulate.out" >&2; exit 1; }
say "the shipped mach_vision.dll in Windows Lua 5.3 (lua.exe, lua53.dll), the camera at 127.0.0.1:$port"
(cd "$root" && "$wine" "$work/lua.exe" hosts/mach4/test/load_test.lua "${work#"$root/"}" hosts/mach4/Macros "$port")
kill "$emulator" 2>/dev/null || true

# 3. mach-vision.exe against the Linux build, examples 1-8.
say "mach-vision.exe run on examples 1-8 against $linux_exe"
cd "$root"
for program in examples/programs/0[1-8]-*.nc; do
    linux_rc=0 windows_rc=0
    # One fixed clock for both (M283 prints its calibration date): every byte must match.
    "$linux_exe" run --clock 1764115200 "$program" >"$work/linux.out" 2>"$work/linux.err" || linux_rc=$?
    "$wine" "$out/mach-vision.exe" run --clock 1764115200 "$program" >"$work/windows.out" 2>"$work/windows.err" ||
        windows_rc=$?
    if [ "$linux_rc" != "$windows_rc" ] || ! cmp -s "$work/linux.out" "$work/windows.out"; then
        say "$program: mach-vision.exe (exit $windows_rc) differs from the Linux build (exit $linux_rc):"
        diff "$work/linux.out" "$work/windows.out" | head -20 >&2 || true
        cat "$work/windows.err" >&2
        exit 1
    fi
    echo "  $program: identical ($(wc -c <"$work/linux.out") bytes, exit $linux_rc)"
done
rm -rf "$work"

# 4. The Keyence driver's and the Mach4 bridge's tests under Wine (release, as the shipped files,
#    so std and the shared crates are reused; vision-lua's tests compile Lua 5.3 in).
say "cargo test -p vision-driver-keyence -p vision-lua under Wine"
export PATH="/usr/bin:$PATH" RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1 CARGO_TARGET_DIR="$win"
upper="$(echo "$triple" | tr 'a-z-' 'A-Z_')"
lower="$(echo "$triple" | tr '-' '_')"
export "CARGO_TARGET_${upper}_LINKER=x86_64-w64-mingw32-gcc" "CARGO_TARGET_${upper}_RUNNER=$wine"
# The vendored Lua's C (cc crate): MinGW-w64's compiler and archiver, named rather than guessed.
export "CC_${lower}=x86_64-w64-mingw32-gcc" "AR_${lower}=x86_64-w64-mingw32-ar"
# The same standard library as scripts/build-windows (with `test`), so its crates are reused.
cargo test --quiet -Z build-std=std,panic_abort,test --target "$triple" --release \
    -p vision-driver-keyence -p vision-lua --tests
say "passed in $((SECONDS - started)) s; user and system CPU of the script, then of all it ran:"
times >&2
