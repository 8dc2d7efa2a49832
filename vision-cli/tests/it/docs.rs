//! The documentation checked against the program: every sample output in README.md and
//! docs/ is what the command prints, README.md stays short, and every relative link resolves.
//!
//! A sample is a fenced `text` block right after a marker line naming the command:
//!
//! ```text
//! <!-- output of: mach-vision run examples/programs/04-rectangle-fit.nc -->
//! <!-- output of: mach-vision trace PROGRAM.nc (first 8 lines, last 2 lines) -->
//! <!-- stderr of: mach-vision fit missing.json (exit 2) -->
//! ```
//!
//! The command runs from the repository root with empty standard input, the built
//! `mach-vision` in place of the word `mach-vision`; its standard output (`output of`) or
//! standard error (`stderr of`) must equal the block line for line. The one normalisation:
//! `first N lines` / `last N lines` show only those lines, with a `...` line where the others
//! were left out. The exit status must be 0 unless the marker says `exit N`. A block may
//! start with `$ COMMAND`, the marker's command as a user types it. Every `text` block is a
//! sample and needs a marker: write formulas and other text in a plain ``` block.
//!
//! README.md has at most 250 lines, none over 100 characters but a sample's (the program's
//! own lines), and every relative link in these files, with its `#anchor`, must resolve.
//!
//! `MACH_VISION_BLESS=1 cargo test -p vision-cli --test it docs::` rewrites stale samples with
//! what the commands print now (then read the diff).

use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// README.md's length limit, lines: the guide's details go to docs/.
const README_MAX_LINES: usize = 250;
/// The longest README line, characters; a sample's lines are exempt (they are what the command
/// prints).
const README_MAX_WIDTH: usize = 100;
/// How long one sample's command may run before the test gives up on it, seconds.
const COMMAND_SECONDS: u64 = 300;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("workspace root").to_path_buf()
}

/// README.md, docs/**/*.md and the hosts' guides (the packages ship those).
fn doc_files(root: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = fs::read_dir(dir) else { return };
        let mut entries: Vec<PathBuf> = entries.map(|e| e.expect("dir entry").path()).collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let mut files = vec![root.join("README.md")];
    walk(&root.join("docs"), &mut files);
    for host in ["mach4", "linuxcnc", "grbl"] {
        let dir = root.join("hosts").join(host);
        let mut guides: Vec<PathBuf> = fs::read_dir(&dir)
            .expect("hosts folder")
            .map(|e| e.expect("dir entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "md"))
            .collect();
        guides.sort();
        files.extend(guides);
    }
    files
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Stream {
    Stdout,
    Stderr,
}

/// One marked sample: where it is and what it claims.
#[derive(Debug)]
struct Sample {
    /// The marker's line, 0-based.
    marker: usize,
    stream: Stream,
    command: String,
    first: Option<usize>,
    last: Option<usize>,
    exit: i32,
    /// The block's content lines, `[start, end)`, 0-based; `end` is the closing fence.
    start: usize,
    end: usize,
}

/// What a marker line claims.
struct Marker {
    stream: Stream,
    command: String,
    first: Option<usize>,
    last: Option<usize>,
    exit: i32,
}

/// The marker on `line`, or `None` when it is no marker; `Err` for a malformed one.
fn parse_marker(line: &str) -> Option<Result<Marker, String>> {
    let t = line.trim();
    let (stream, rest) = if let Some(r) = t.strip_prefix("<!-- output of:") {
        (Stream::Stdout, r)
    } else if let Some(r) = t.strip_prefix("<!-- stderr of:") {
        (Stream::Stderr, r)
    } else {
        return None;
    };
    let Some(rest) = rest.strip_suffix("-->") else {
        return Some(Err("the marker must end with --> on the same line".into()));
    };
    let mut command = rest.trim().to_string();
    let (mut first, mut last, mut exit) = (None, None, 0);
    if command.ends_with(')') {
        if let Some(open) = command.rfind(" (") {
            let options = command[open + 2..command.len() - 1].to_string();
            command.truncate(open);
            for option in options.split(',').map(str::trim) {
                let words: Vec<&str> = option.split_whitespace().collect();
                let number = |w: &str| w.parse::<usize>().map_err(|_| format!("not a count: {option:?}"));
                match words.as_slice() {
                    ["first", n, "lines" | "line"] => {
                        first = Some(match number(n) {
                            Ok(v) => v,
                            Err(e) => return Some(Err(e)),
                        });
                    }
                    ["last", n, "lines" | "line"] => {
                        last = Some(match number(n) {
                            Ok(v) => v,
                            Err(e) => return Some(Err(e)),
                        });
                    }
                    ["exit", n] => {
                        exit = match n.parse() {
                            Ok(v) => v,
                            Err(_) => return Some(Err(format!("not an exit status: {option:?}"))),
                        }
                    }
                    _ => {
                        return Some(Err(format!(
                            "unknown option {option:?}: use `first N lines`, `last N lines`, `exit N`"
                        )))
                    }
                }
            }
        }
    }
    if !command.starts_with("mach-vision ") {
        return Some(Err(format!("the command must start with `mach-vision `: {command:?}")));
    }
    Some(Ok(Marker { stream, command, first, last, exit }))
}

/// Whether `line` opens or closes a fence, and its info string.
fn fence(line: &str) -> Option<&str> {
    line.trim_start().strip_prefix("```").map(str::trim)
}

/// The samples of one file, or the problems found in its markers.
fn samples(lines: &[&str]) -> (Vec<Sample>, Vec<String>) {
    let (mut found, mut problems) = (Vec::new(), Vec::new());
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        if let Some(info) = fence(line) {
            // A closing fence carries no info string (CommonMark).
            let close = (i + 1..lines.len()).find(|&j| lines[j].trim() == "```");
            let Some(close) = close else {
                problems.push(format!("line {}: a fence that is never closed", i + 1));
                break;
            };
            if info == "text" {
                let marker = i.checked_sub(1).and_then(|m| parse_marker(lines[m]).map(|r| (m, r)));
                match marker {
                    Some((m, Ok(Marker { stream, command, first, last, exit }))) => {
                        found.push(Sample { marker: m, stream, command, first, last, exit, start: i + 1, end: close });
                    }
                    Some((m, Err(e))) => problems.push(format!("line {}: {e}", m + 1)),
                    None => problems.push(format!(
                        "line {}: a `text` block is a sample output and needs a marker line right \
                         before it (<!-- output of: mach-vision … -->); for other text use a plain ``` block",
                        i + 1
                    )),
                }
            }
            i = close + 1;
            continue;
        }
        if let Some(marker) = parse_marker(line) {
            let next_is_text = lines.get(i + 1).and_then(|l| fence(l)) == Some("text");
            if !next_is_text {
                problems.push(format!("line {}: a marker must be followed at once by a ```text block", i + 1));
            }
            if let Err(e) = marker {
                problems.push(format!("line {}: {e}", i + 1));
            }
        }
        i += 1;
    }
    (found, problems)
}

/// The command's words: blanks separate them, double quotes group.
fn words(command: &str) -> Vec<String> {
    let (mut out, mut word, mut quoted, mut any) = (Vec::new(), String::new(), false, false);
    for c in command.chars() {
        match c {
            '"' => {
                quoted = !quoted;
                any = true;
            }
            c if c.is_whitespace() && !quoted => {
                if any {
                    out.push(std::mem::take(&mut word));
                    any = false;
                }
            }
            c => {
                word.push(c);
                any = true;
            }
        }
    }
    if any {
        out.push(word);
    }
    out
}

/// Runs the sample's command: its exit status, standard output and standard error.
fn run(root: &Path, command: &str) -> Result<(i32, String, String), String> {
    let args = words(command);
    let mut child = Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(&args[1..])
        .current_dir(root)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start: {e}"))?;
    let reader = |mut pipe: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = pipe.read_to_end(&mut bytes);
            String::from_utf8_lossy(&bytes).into_owned()
        })
    };
    let out = reader(Box::new(child.stdout.take().expect("stdout")));
    let err = reader(Box::new(child.stderr.take().expect("stderr")));
    let deadline = Instant::now() + Duration::from_secs(COMMAND_SECONDS);
    let status = loop {
        if let Some(status) = child.try_wait().map_err(|e| e.to_string())? {
            break status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("still running after {COMMAND_SECONDS} s"));
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let code = status.code().unwrap_or(-1);
    Ok((code, out.join().expect("stdout reader"), err.join().expect("stderr reader")))
}

/// What the block must hold for this output: its lines, with `...` for lines left out.
fn expected_block(sample: &Sample, output: &str) -> Vec<String> {
    let lines: Vec<&str> = output.strip_suffix('\n').unwrap_or(output).split('\n').collect();
    let lines: Vec<&str> = if output.is_empty() { Vec::new() } else { lines };
    let n = lines.len();
    let head = sample.first.unwrap_or(if sample.last.is_some() { 0 } else { n }).min(n);
    let tail = sample.last.unwrap_or(0).min(n - head);
    let mut block: Vec<String> = lines[..head].iter().map(std::string::ToString::to_string).collect();
    if head + tail < n {
        block.push("...".into());
    }
    block.extend(lines[n - tail..].iter().map(std::string::ToString::to_string));
    block
}

#[test]
fn every_sample_output_is_what_the_command_prints() {
    let root = repo_root();
    let bless = std::env::var_os("MACH_VISION_BLESS").is_some();
    let (mut failures, mut checked) = (Vec::new(), 0);
    for file in doc_files(&root) {
        let name = file.strip_prefix(&root).expect("under the root").display().to_string();
        let text = fs::read_to_string(&file).expect("read the doc");
        let lines: Vec<&str> = text.lines().collect();
        let (found, problems) = samples(&lines);
        failures.extend(problems.into_iter().map(|p| format!("{name}: {p}")));
        let mut rewritten: Vec<String> = lines.iter().map(std::string::ToString::to_string).collect();
        // Later blocks first, so earlier indices stay valid while rewriting.
        for sample in found.iter().rev() {
            checked += 1;
            let at = format!("{name}:{}: `{}`", sample.marker + 1, sample.command);
            let (code, stdout, stderr) = match run(&root, &sample.command) {
                Ok(r) => r,
                Err(e) => {
                    failures.push(format!("{at}: {e}"));
                    continue;
                }
            };
            if code != sample.exit {
                failures.push(format!("{at}: exit status {code}, the marker says {} (stderr: {stderr})", sample.exit));
                continue;
            }
            let output = if sample.stream == Stream::Stdout { &stdout } else { &stderr };
            let mut want = expected_block(sample, output);
            let mut start = sample.start;
            let prompt = format!("$ {}", sample.command);
            if let Some(first) = lines.get(start).filter(|l| l.starts_with("$ ")) {
                if *first != prompt {
                    failures.push(format!("{at}: the block's first line {first:?} is not the marker's command"));
                    continue;
                }
                start += 1;
            }
            let have: Vec<&str> = lines[start..sample.end].to_vec();
            if have != want {
                let diff = (0..have.len().max(want.len()))
                    .find(|&k| have.get(k).copied() != want.get(k).map(String::as_str))
                    .unwrap_or(0);
                failures.push(format!(
                    "{at}: stale sample, first difference at block line {}:\n  doc:     {:?}\n  command: {:?}\n\
                     the command prints:\n{}\n",
                    diff + 1,
                    have.get(diff).copied().unwrap_or("(nothing)"),
                    want.get(diff).map(String::as_str).unwrap_or("(nothing)"),
                    want.join("\n")
                ));
                if bless {
                    rewritten.splice(start..sample.end, want.drain(..));
                }
            }
        }
        if bless {
            let mut new = rewritten.join("\n");
            new.push('\n');
            if new != text {
                fs::write(&file, new).expect("rewrite the doc");
                eprintln!("rewrote the samples of {name}");
            }
        }
    }
    assert!(checked > 0, "no samples found");
    if bless {
        return;
    }
    assert!(failures.is_empty(), "{} problem(s) with the docs' samples:\n\n{}", failures.len(), failures.join("\n\n"));
}

#[test]
fn readme_is_short() {
    let text = fs::read_to_string(repo_root().join("README.md")).expect("README.md");
    let lines: Vec<&str> = text.lines().collect();
    assert!(
        lines.len() <= README_MAX_LINES,
        "README.md has {} lines, at most {README_MAX_LINES}: move details to docs/",
        lines.len()
    );
    let (found, _) = samples(&lines);
    let in_sample = |i: usize| found.iter().any(|s| (s.start..s.end).contains(&i));
    let wide: Vec<String> = lines
        .iter()
        .enumerate()
        .filter(|(i, l)| !in_sample(*i) && l.chars().count() > README_MAX_WIDTH)
        .map(|(i, l)| format!("line {}: {} characters", i + 1, l.chars().count()))
        .collect();
    assert!(wide.is_empty(), "README.md lines over {README_MAX_WIDTH} characters:\n{}", wide.join("\n"));
}

/// GitHub's anchor for a heading: lower case, blanks to `-`, punctuation but `-`/`_` dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .chars()
        .filter_map(|c| match c {
            ' ' | '-' => Some('-'),
            '_' => Some('_'),
            c if c.is_alphanumeric() => Some(c.to_lowercase().next().unwrap_or(c)),
            _ => None,
        })
        .collect()
}

/// The anchors a Markdown file's headings make (a repeated heading gets `-1`, `-2`, …).
fn anchors(text: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut seen = std::collections::HashMap::<String, usize>::new();
    let mut in_fence = false;
    for line in text.lines() {
        if fence(line).is_some() {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        let h = line.trim_start_matches('#');
        if h.len() < line.len() && h.starts_with(' ') {
            let base = slug(h);
            let n = seen.entry(base.clone()).or_insert(0);
            out.push(if *n == 0 { base } else { format!("{base}-{n}") });
            *n += 1;
        }
    }
    out
}

/// The relative link targets of a Markdown text, outside code: `(line, target)`.
fn links(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut in_fence = false;
    for (n, line) in text.lines().enumerate() {
        if fence(line).is_some() {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        // Drop inline code spans, whose brackets are no links.
        let mut plain = String::new();
        for (k, part) in line.split('`').enumerate() {
            if k % 2 == 0 {
                plain.push_str(part);
            }
        }
        let mut rest = plain.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let Some(close) = after.find(')') else { break };
            let target = after[..close].split_whitespace().next().unwrap_or("").to_string();
            let external = ["http://", "https://", "mailto:"].iter().any(|p| target.starts_with(p));
            if !external && !target.is_empty() {
                out.push((n + 1, target));
            }
            rest = &after[close..];
        }
    }
    out
}

#[test]
fn every_relative_link_resolves() {
    let root = repo_root();
    let mut broken = Vec::new();
    for file in doc_files(&root) {
        let name = file.strip_prefix(&root).expect("under the root").display().to_string();
        let text = fs::read_to_string(&file).expect("read the doc");
        for (line, target) in links(&text) {
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let resolved = if path.is_empty() { file.clone() } else { file.parent().expect("folder").join(path) };
            if !resolved.exists() {
                broken.push(format!("{name}:{line}: {target}: no such file"));
                continue;
            }
            if let Some(anchor) = anchor {
                if resolved.extension().is_some_and(|e| e == "md") {
                    let target_text = fs::read_to_string(&resolved).expect("read the linked doc");
                    if !anchors(&target_text).iter().any(|a| a == anchor) {
                        broken.push(format!("{name}:{line}: {target}: no heading makes #{anchor}"));
                    }
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links in the docs:\n{}", broken.join("\n"));
}

#[test]
fn the_checker_sees_a_stale_sample_and_an_unmarked_one() {
    let doc = "intro\n<!-- output of: mach-vision x (first 2 lines, exit 1) -->\n```text\na\nb\n...\n```\n\n```text\nloose\n```\n";
    let lines: Vec<&str> = doc.lines().collect();
    let (found, problems) = samples(&lines);
    assert_eq!(found.len(), 1);
    assert_eq!(problems.len(), 1, "{problems:?}");
    let s = &found[0];
    assert_eq!((s.command.as_str(), s.first, s.last, s.exit), ("mach-vision x", Some(2), None, 1));
    assert_eq!(expected_block(s, "a\nb\nc\n"), ["a", "b", "..."]);
    assert_eq!(expected_block(s, "a\nb\n"), ["a", "b"]);
    assert_ne!(expected_block(s, "a\nB\nc\n"), lines[s.start..s.end].to_vec());
    let tail = Sample { first: Some(1), last: Some(1), ..found.into_iter().next().expect("one") };
    assert_eq!(expected_block(&tail, "a\nb\nc\nd\n"), ["a", "...", "d"]);
    assert_eq!(words(r#"mach-vision fit "a b.json" --json"#), ["mach-vision", "fit", "a b.json", "--json"]);
    assert_eq!(slug("JSON output of `run --json`"), "json-output-of-run---json");
}
