#!/usr/bin/env python3
"""What each package ships, and the check that its docs name only what it holds.

    python3 scripts/packaging/package.py stage PACKAGE DIR [NAME=FILE ...]
    python3 scripts/packaging/package.py zip DIR ZIPFILE
    python3 scripts/packaging/package.py check PACKAGE (ZIPFILE | DEBFILE | DIR)
    python3 scripts/packaging/package.py self-test
    python3 scripts/packaging/package.py check-rust SCRIPT

PACKAGE is `windows` or `deb`: its file list is scripts/packaging/PACKAGE.txt (the format is in
that file's header). `stage` copies the listed files into DIR (NAME=FILE gives the file the build
made for each `@NAME` source), with CRLF line ends where the manifest says `%crlf`. `zip` writes
DIR as a zip with its entries sorted and dated SOURCE_DATE_EPOCH, so the same files give the
same bytes. `check` reads every text doc (.md, .txt) in the package, lists every path it names
(markdown links, backticked paths, file names in prose, "SPEC §5"-style document names, "the
root README") and fails, naming doc, line and path, for each one the package does not hold;
scripts/packaging/not-in-package.txt lists the few names that are the user's machine's, not the
package's. It runs its self-test first, so a check that cannot fail cannot pass. `check-rust`
fails, saying what to install, when the Rust that cargo runs is older than the workspace's
rust-version.
"""

import fnmatch
import glob
import os
import re
import shutil
import stat
import subprocess
import sys
import tempfile
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))

# Extensions that make a backticked or code-block word a path (with a / or \ in it).
PATH_EXTENSIONS = {
    "md", "txt", "pdf", "nc", "ngc", "lua", "mcs", "py", "ini", "toml", "sh", "rs", "dll",
    "exe", "so", "svg", "png", "json", "csv", "html", "deb", "zip",
}
# A bare file name (no folder) is checked when it has one of these: the documents, programs,
# macros and scripts the project writes. Other bare names (`Machine.ini`, `lua53.dll`,
# `MachVision.toml`) are the machine's or the user's.
BARE_EXTENSIONS = {"md", "txt", "pdf", "nc", "ngc", "lua", "mcs", "py"}
# The docs a package holds, which the check reads.
TEXT_DOC = re.compile(r"\.(md|txt)$", re.IGNORECASE)


class ManifestError(Exception):
    pass


def fail(msg):
    print(f"package: {msg}", file=sys.stderr)
    sys.exit(1)


# ---------------------------------------------------------------- the manifest


def read_manifest(package):
    """(entries, settings) of scripts/packaging/PACKAGE.txt: entries are (line, dest, source)."""
    path = os.path.join(HERE, f"{package}.txt")
    if not os.path.isfile(path):
        raise ManifestError(f"no manifest {path} (the packages are windows, deb)")
    entries, settings = [], {"crlf": set(), "root": [], "owns": []}
    with open(path, encoding="utf-8") as f:
        for n, raw in enumerate(f, 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            words = line.split()
            if words[0].startswith("%"):
                key = words[0][1:]
                if key not in settings:
                    raise ManifestError(f"{path}:{n}: unknown setting {words[0]} (%crlf, %root, %owns)")
                settings[key].update(words[1:]) if key == "crlf" else settings[key].extend(words[1:])
                continue
            if len(words) != 2:
                raise ManifestError(f"{path}:{n}: expected `DEST SOURCE`, got {line!r}")
            entries.append((f"{os.path.basename(path)}:{n}", words[0], words[1]))
    if not settings["root"]:
        settings["root"] = ["."]
    return entries, settings


def is_text(name, settings):
    base = os.path.basename(name)
    ext = base.rsplit(".", 1)[-1].lower() if "." in base else base
    return ext in settings["crlf"] or base in settings["crlf"]


def stage(package, out, artifacts):
    """Copies the package's files into `out`; returns the list of package paths."""
    entries, settings = read_manifest(package)
    written = []
    for where, dest, source in entries:
        if source.startswith("@"):
            name = source[1:]
            if name not in artifacts:
                raise ManifestError(f"{where}: {source} is made by the build, but no {name}=FILE was given")
            sources = [artifacts[name]]
            if not os.path.isfile(sources[0]):
                raise ManifestError(f"{where}: {source} = {sources[0]} is not a file")
        elif any(c in source for c in "*?["):
            sources = sorted(glob.glob(os.path.join(REPO, source)))
            if not sources:
                raise ManifestError(f"{where}: {source} matches no file in the repository")
        else:
            sources = [os.path.join(REPO, source)]
            if not os.path.isfile(sources[0]):
                raise ManifestError(f"{where}: {source} is not a file in the repository")
        if len(sources) > 1 and not dest.endswith("/"):
            raise ManifestError(f"{where}: {source} is several files: DEST must be a folder (end in /)")
        for src in sources:
            rel = dest + os.path.basename(src) if dest.endswith("/") else dest
            if rel in written:
                raise ManifestError(f"{where}: {rel} is listed twice")
            target = os.path.join(out, rel)
            os.makedirs(os.path.dirname(target), exist_ok=True)
            if is_text(rel, settings):
                with open(src, "rb") as f:
                    data = f.read()
                data = data.replace(b"\r\n", b"\n").replace(b"\n", b"\r\n")
                with open(target, "wb") as f:
                    f.write(data)
            else:
                shutil.copyfile(src, target)
            written.append(rel)
    for a in set(artifacts) - {s[1:] for _, _, s in entries if s.startswith("@")}:
        raise ManifestError(f"{package}.txt lists no @{a}, but the build made it")
    return written


def source_date_epoch():
    """SOURCE_DATE_EPOCH, else the last commit's time, else 1980-01-01 (zip's first date)."""
    if os.environ.get("SOURCE_DATE_EPOCH"):
        return int(os.environ["SOURCE_DATE_EPOCH"])
    try:
        out = subprocess.run(["git", "-C", REPO, "log", "-1", "--format=%ct"], capture_output=True, text=True, check=True)
        return int(out.stdout.strip())
    except (OSError, ValueError, subprocess.CalledProcessError):
        return 315532800


def write_zip(folder, zip_path):
    """`folder` as a zip, the folder's name its top entry: sorted, one date, fixed modes."""
    import time

    stamp = max(source_date_epoch(), 315532800)
    date = time.gmtime(stamp)[:6]
    top = os.path.basename(os.path.normpath(folder))
    names = []
    for dirpath, dirnames, filenames in os.walk(folder):
        dirnames.sort()
        for fn in filenames:
            names.append(os.path.relpath(os.path.join(dirpath, fn), folder).replace(os.sep, "/"))
    tmp = zip_path + ".part"
    with zipfile.ZipFile(tmp, "w") as z:
        for name in sorted(names):
            info = zipfile.ZipInfo(f"{top}/{name}", date_time=date)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.create_system = 3  # Unix, so the mode below is read
            info.external_attr = (stat.S_IFREG | 0o644) << 16
            with open(os.path.join(folder, name), "rb") as f:
                z.writestr(info, f.read(), compresslevel=9)
    os.replace(tmp, zip_path)


# ---------------------------------------------------------------- the check


def read_allow_list():
    """(doc patterns, name patterns) of not-in-package.txt: names a doc may give that are no file
    of the package (fnmatch; `/` stands for either slash)."""
    path = os.path.join(HERE, "not-in-package.txt")
    rules = []
    with open(path, encoding="utf-8") as f:
        for n, raw in enumerate(f, 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            docs, colon, names = line.partition(":")
            if not colon or not docs.split() or not names.split():
                raise ManifestError(f"{path}:{n}: expected `DOC... : NAME...`, got {line!r}")
            rules.append((docs.split(), [w.replace("\\", "/") for w in names.split()]))
    return rules


def allowed(rules, doc, name):
    return any(
        any(fnmatch.fnmatchcase(doc, d) for d in docs) and any(fnmatch.fnmatchcase(name, p) for p in names)
        for docs, names in rules
    )


class Package:
    """The files of an unpacked package (paths relative to its top, `/` separated)."""

    def __init__(self, top, settings):
        self.top = top
        self.files, self.dirs = set(), {""}
        for dirpath, dirnames, filenames in os.walk(top):
            rel = os.path.relpath(dirpath, top).replace(os.sep, "/")
            rel = "" if rel == "." else rel
            for d in dirnames:
                self.dirs.add(f"{rel}/{d}".lstrip("/"))
            for fn in filenames:
                self.files.add(f"{rel}/{fn}".lstrip("/"))
        self.roots = [r.strip("/").replace("\\", "/") if r != "." else "" for r in settings["root"]]
        self.owns = ["/" + o.strip("/") for o in settings["owns"]]
        self.basenames = {}
        for f in self.files:
            self.basenames.setdefault(os.path.basename(f).lower(), []).append(f)

    def holds(self, rel, want_dir):
        rel = norm(rel)
        if rel is None:
            return False
        if any(c in rel for c in "*?["):
            pool = self.dirs if want_dir else self.files | self.dirs
            return any(fnmatch.fnmatchcase(p, rel) for p in pool)
        return rel in self.dirs if want_dir else (rel in self.files or rel in self.dirs)


def norm(path):
    """`a/./b/../c` → `a/c`; None when it climbs out of the package."""
    parts = []
    for p in path.split("/"):
        if p in ("", "."):
            continue
        if p == "..":
            if not parts:
                return None
            parts.pop()
        else:
            parts.append(p)
    return "/".join(parts)


INLINE_CODE = re.compile(r"`([^`\n]+)`")
LINK = re.compile(r"!?\[[^\]\n]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
PROSE_FILE = re.compile(r"(?<![\w./\\<>-])([\w<>.-]+(?:[/\\][\w<>.-]+)*\.(?:md|pdf|nc|ngc|mcs|lua))(?![\w/\\-])")
SECTION_OF = re.compile(r"\b([A-Z][A-Za-z0-9_-]+)(?:\.md)? §\s?\d")
ROOT_README = re.compile(r"\b(?:the )?(?:root|top-level|main) README\b", re.IGNORECASE)


def ext_of(word):
    base = word.rstrip("/").rsplit("/", 1)[-1]
    return base.rsplit(".", 1)[-1].lower() if "." in base.strip(".") else ""


def pathlike(word):
    """The path a backticked or code word names, `/`-separated, or None if it names none."""
    word = word.strip().rstrip(".,;:)").lstrip("(")
    if not word or "://" in word or word.startswith("-") or "=" in word:
        return None
    w = word.replace("\\", "/")
    if w.startswith("/") or re.match(r"^[A-Za-z]:/", w):
        return w
    if "/" in w:
        if w.endswith("/") or ext_of(w) in PATH_EXTENSIONS:
            return w
        return None
    return w if ext_of(w) in BARE_EXTENSIONS else None


def names_in(text):
    """(line, kind, name) for every path a doc names."""
    found = []
    in_fence = False
    for n, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith(("```", "~~~")):
            in_fence = not in_fence
            continue
        if in_fence:
            for word in line.split("#", 1)[0].split():
                p = pathlike(word)
                if p:
                    found.append((n, "code", p))
            continue
        for m in LINK.finditer(line):
            target = m.group(1)
            if re.match(r"^[A-Za-z][\w+.-]*:", target) or target.startswith("#"):
                continue
            found.append((n, "link", target.split("#", 1)[0]))
        for m in INLINE_CODE.finditer(line):
            for word in m.group(1).split():
                p = pathlike(word)
                if p:
                    found.append((n, "code", p))
        prose = LINK.sub(" ", INLINE_CODE.sub(" ", line))
        prose = re.sub(r"https?://\S+", " ", prose)
        for m in PROSE_FILE.finditer(prose):
            found.append((n, "prose", m.group(1).replace("\\", "/")))
        for m in SECTION_OF.finditer(prose):
            found.append((n, "document", m.group(1) + ".md"))
        if ROOT_README.search(prose):
            found.append((n, "document", "/README.md"))
    return found


def resolve(pkg, doc, kind, name, allow):
    """True when the package holds what `doc` names (or it is the machine's, per the allow-list)."""
    if "<" in name or name.startswith(("$", "%", "~")) or re.match(r"^[A-Za-z]:/", name):
        return True  # a placeholder or a drive: a path on the user's machine
    if allowed(allow, doc, name):
        return True
    want_dir = name.endswith("/")
    here = os.path.dirname(doc)
    if kind == "document":
        if name.startswith("/"):
            return any(pkg.holds(f"{r}/{name[1:]}", False) for r in pkg.roots)
        return name.lower() in pkg.basenames
    if name.startswith("/"):
        if not any(name == o or name.startswith(o + "/") for o in pkg.owns):
            return True  # the machine's (/usr/share/linuxcnc, /tmp)
        return pkg.holds(name[1:], want_dir)
    if kind == "link":
        return pkg.holds(f"{here}/{name}", want_dir)
    if "/" not in name.rstrip("/") and kind != "link":
        if pkg.holds(f"{here}/{name}", want_dir) or name.lower() in pkg.basenames:
            return True
    return any(pkg.holds(f"{base}/{name}", want_dir) for base in [here] + pkg.roots)


def check_tree(top, settings, allow):
    """The names the package's docs give that it does not hold: (doc, line, kind, name)."""
    pkg = Package(top, settings)
    missing = []
    docs = sorted(f for f in pkg.files if TEXT_DOC.search(f))
    for doc in docs:
        with open(os.path.join(top, doc), encoding="utf-8", errors="replace") as f:
            text = f.read()
        for n, kind, name in names_in(text):
            if not resolve(pkg, doc, kind, name, allow):
                missing.append((doc, n, kind, name))
    return docs, missing


def unpack(package_file, into):
    """The package's files under `into`; returns the folder its paths are relative to."""
    if os.path.isdir(package_file):
        return package_file
    if package_file.endswith(".zip"):
        with zipfile.ZipFile(package_file) as z:
            z.extractall(into)
        tops = os.listdir(into)
        return os.path.join(into, tops[0]) if len(tops) == 1 and os.path.isdir(os.path.join(into, tops[0])) else into
    if package_file.endswith(".deb"):
        subprocess.run(["dpkg-deb", "-x", package_file, into], check=True)
        return into
    fail(f"{package_file}: not a .zip, a .deb or a folder")


def check(package, package_file):
    self_test(quiet=True)
    _, settings = read_manifest(package)
    allow = read_allow_list()
    with tempfile.TemporaryDirectory() as tmp:
        top = unpack(package_file, tmp)
        docs, missing = check_tree(top, settings, allow)
    if not docs:
        fail(f"{package_file}: holds no doc (.md, .txt) to check")
    for doc, n, kind, name in missing:
        print(f"package: {package_file}: {doc}:{n} names {name!r} ({kind}), which the package does not hold", file=sys.stderr)
    if missing:
        fail(
            f"{len(missing)} name(s) in the docs of {os.path.basename(package_file)} lead nowhere: add the file to "
            f"scripts/packaging/{package}.txt, fix the doc, or (only for a path on the user's machine) "
            "scripts/packaging/not-in-package.txt"
        )
    print(f"package: {os.path.basename(package_file)}: every path its {len(docs)} docs name is in it")


# ---------------------------------------------------------------- the toolchain


def check_rust(script):
    """Exits with what to install when `rustc` is older than Cargo.toml's rust-version."""
    with open(os.path.join(REPO, "Cargo.toml"), encoding="utf-8") as f:
        m = re.search(r'^rust-version = "([0-9.]+)"', f.read(), re.MULTILINE)
    if not m:
        return
    need = tuple(int(x) for x in m.group(1).split("."))
    rustc = os.environ.get("RUSTC", "rustc")
    try:
        out = subprocess.run([rustc, "--version"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        out = ""
    v = re.match(r"rustc (\d+)\.(\d+)\.(\d+)", out)
    have = tuple(int(x) for x in v.groups()) if v else None
    if have is not None and have[: len(need)] >= need:
        return
    found = f"Rust {'.'.join(map(str, have))}" if have else f"no Rust (`{rustc} --version` failed)"
    fail(
        f"{script}: needs Rust {m.group(1)} or newer (the workspace's rust-version), found {found}. "
        "On Debian 12, whose rustc is 1.63, install Debian's Rust 1.96: "
        "`sudo apt-get install rustc-web cargo-web` (they replace rustc and cargo in /usr/bin); "
        "elsewhere use rustup (https://rustup.rs)."
    )


# ---------------------------------------------------------------- self-test


def self_test(quiet=False):
    """The check on a small package: each kind of name, held and not held."""
    settings = {"crlf": set(), "root": [".", "usr/share/doc/x"], "owns": ["/usr/lib/x"]}
    doc = "\n".join([
        "[held](../prog/a.nc) [gone](../prog/b.nc) [web](https://example.com/c.md) [anchor](#top)",
        "Run `mach-vision run prog/a.nc` then `prog\\c.nc`; the folder `prog/` and `nowhere/`.",
        "Put the first lines of a.lua in each macro (see gone.md and docs/x.md).",
        "The manual (SPEC §5), the Keyence section of the root README.",
        "`<Mach4>\\Modules\\` `C:\\Mach4Hobby` `/usr/share/linuxcnc/nc_files` `/usr/lib/x/m.so` `/usr/lib/x/gone.so`",
        "`Machine.ini` `VisionCal_ResX/ResY` `in/s` `prog/*.nc` `prog/z*.nc`",
        "```sh",
        "mach-vision run prog/a.nc --report out/  # prog/ignored.nc",
        "mach-vision run prog/missing.nc",
        "```",
    ])
    expect = {
        (1, "link", "../prog/b.nc"),
        (2, "code", "prog/c.nc"),
        (2, "code", "nowhere/"),
        (3, "prose", "gone.md"),
        (4, "document", "SPEC.md"),
        (4, "document", "/README.md"),
        (5, "code", "/usr/lib/x/gone.so"),
        (6, "code", "prog/z*.nc"),
        (8, "code", "out/"),
        (9, "code", "prog/missing.nc"),
    }
    with tempfile.TemporaryDirectory() as top:
        for rel, body in [
            ("docs/guide.md", doc),
            ("docs/x.md", "[back](guide.md)"),
            ("prog/a.nc", ""),
            ("a.lua", ""),
            ("usr/lib/x/m.so", ""),
        ]:
            os.makedirs(os.path.dirname(os.path.join(top, rel)) or top, exist_ok=True)
            with open(os.path.join(top, rel), "w") as f:
                f.write(body)
        docs, missing = check_tree(top, settings, [])
        got = {(n, kind, name) for d, n, kind, name in missing}
        if docs != ["docs/guide.md", "docs/x.md"] or got != expect:
            fail(f"self-test: the check found {sorted(got)} in {docs}; expected {sorted(expect)}")
        # With a README at the top and the SPEC shipped, those two names resolve.
        for rel in ("README.md", "usr/share/doc/x/SPEC.md"):
            os.makedirs(os.path.dirname(os.path.join(top, rel)) or top, exist_ok=True)
            open(os.path.join(top, rel), "w").close()
        _, missing = check_tree(top, settings, [(["docs/g*"], ["out/"]), (["other.md"], ["prog/missing.nc"])])
        got = {(n, kind, name) for d, n, kind, name in missing if d == "docs/guide.md"}
        if got != expect - {(4, "document", "SPEC.md"), (4, "document", "/README.md"), (8, "code", "out/")}:
            fail(f"self-test: with README.md, SPEC.md and the allow-list the check found {sorted(got)}")
    if not quiet:
        print("package: self-test passed")


def main(argv):
    if len(argv) >= 3 and argv[0] == "stage":
        artifacts = {}
        for a in argv[3:]:
            name, eq, path = a.partition("=")
            if not eq:
                fail(f"stage: expected NAME=FILE, got {a!r}")
            artifacts[name] = path
        os.makedirs(argv[2], exist_ok=True)
        stage(argv[1], argv[2], artifacts)
    elif len(argv) == 3 and argv[0] == "zip":
        write_zip(argv[1], argv[2])
    elif len(argv) == 3 and argv[0] == "check":
        check(argv[1], argv[2])
    elif len(argv) == 2 and argv[0] == "check-rust":
        check_rust(argv[1])
    elif argv == ["self-test"]:
        self_test()
    else:
        fail(__doc__.strip().split("\n\n")[0])


if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except ManifestError as e:
        fail(str(e))
