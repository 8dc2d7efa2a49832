//! The generated references under `docs/reference/`: `parameters.md` from the parameter tables
//! (vision-core's [`ParamSpec`]s and every registered camera driver's settings), `mcodes.md`
//! from vision-mcode's word table ([`vision_mcode::MCODES`]) with the refusals the parser and
//! each controller's dialect give, and the built-in world in `world.md` (whose keys are written
//! by hand and checked here against the simulator's world format).
//!
//! The tests compare the committed files with what the code renders now and fail, saying how
//! to regenerate, when they differ: `UPDATE_DOCS=1 cargo test -p vision-cli --bin mach-vision
//! reference` rewrites them.

use std::fmt::Write as _;
use std::path::PathBuf;

use vision_core::controller::CONTROLLERS;
use vision_core::{Access, Calibration, Config, ParamKind, ParamSpec, ParamValue, Params, Telemetry};
use vision_driver_sim::{Sim, World};
use vision_mcode::{McodeError, VisionCall, MCODES};

/// The command that rewrites the references.
const REGENERATE: &str = "UPDATE_DOCS=1 cargo test -p vision-cli --bin mach-vision reference";

/// Every parameter table with its values at their defaults: the core's, then each registered
/// driver's (what a profile load starts from).
fn all_params() -> Params {
    let sim = Sim::new(World::default_world()).expect("the built-in world");
    vision_host::cameras(Some(&sim)).params()
}

/// A value as a profile's TOML writes it.
fn toml_text(v: &ParamValue) -> String {
    match v {
        ParamValue::Bool(b) => b.to_string(),
        ParamValue::Int(i) => i.to_string(),
        ParamValue::Float(f) if f.fract() == 0.0 && f.abs() < 1e15 => format!("{f:.1}"),
        ParamValue::Float(f) => f.to_string(),
        ParamValue::Text(s) => format!("{s:?}"),
    }
}

/// The values a parameter accepts, in words.
fn range_text(spec: &ParamSpec) -> String {
    if !spec.range.is_empty() {
        return spec.range.to_string();
    }
    match spec.kind {
        ParamKind::YesNo => "true or false (also Yes/No, 1/0)".into(),
        ParamKind::Integer => "any integer".into(),
        ParamKind::Float => "any number".into(),
        ParamKind::Text => "any text".into(),
        ParamKind::Choice(words) => {
            format!("one of {}", words.iter().map(|w| format!("`{w}`")).collect::<Vec<_>>().join(", "))
        }
    }
}

/// A spec's description without the leading "`Name`: ".
fn description(spec: &ParamSpec) -> String {
    let doc = spec.doc.trim();
    let lead = format!("`{}`:", spec.name);
    let doc = doc.strip_prefix(&lead).unwrap_or(doc).trim();
    let mut chars = doc.chars();
    chars.next().map_or_else(String::new, |c| c.to_uppercase().chain(chars).collect())
}

/// One table of the reference: its heading, what it is, where it lives, and its parameters with
/// their defaults (`None` for telemetry: not stored).
struct Part {
    heading: String,
    intro: String,
    table: String,
    specs: Vec<(&'static ParamSpec, Option<ParamValue>)>,
}

fn parts() -> Vec<Part> {
    let params = all_params();
    let stored = |specs: &'static [ParamSpec]| {
        specs.iter().map(|s| (s, Some(params.get(s.name).expect("a stored parameter")))).collect::<Vec<_>>()
    };
    let mut parts = vec![
        Part {
            heading: "Configuration".into(),
            intro: "The operator's settings: the camera driver, the image, re-centring, the working-distance \
                    checks, the camera tool, the pound-variable block and the fit's quality gates."
                .into(),
            table: "[vision]".into(),
            specs: stored(Config::SPECS),
        },
        Part {
            heading: "Calibration".into(),
            intro: "Written by M283 as one unit (K with its units and date, the axis flags, the optical centre, \
                    and the record of what it calibrated with, which M280–M282 check before they use K). Edit \
                    them by hand only to clear a calibration (set K11..K22 to 0)."
                .into(),
            table: "[vision]".into(),
            specs: stored(Calibration::SPECS),
        },
    ];
    for driver in params.drivers_settings() {
        let table = driver.table();
        parts.push(Part {
            heading: format!("Camera driver settings: `[{table}]`"),
            intro: format!(
                "The {table} driver's own settings, in the profile's `[{table}]` table (a profile may also \
                 hold them in `[vision]`, as the manual writes them; a save moves them here)."
            ),
            table: format!("[{table}]"),
            specs: driver.specs().map(|s| (s, driver.get(s.name).cloned())).collect(),
        });
    }
    let telemetry = Telemetry::default();
    parts.push(Part {
        heading: "Telemetry (read-only)".into(),
        intro: "What the last operation measured and emitted: written by the Vision module after each M-code, \
                shown on the host's DRO and in `mach-vision run`'s report, never stored in the profile and never \
                read back to decide anything. Setting one is refused. The value shown is the one before any \
                M-code ran."
            .into(),
        table: "not stored".into(),
        specs: Telemetry::SPECS.iter().map(|s| (s, telemetry.get(s.name))).collect(),
    });
    parts
}

/// `docs/reference/parameters.md`.
fn parameters_md() -> String {
    let parts = parts();
    let mut md = String::new();
    md.push_str("# Parameter reference\n\n");
    md.push_str(&format!(
        "<!-- Generated from the code's parameter tables (vision-core `params/`, the camera drivers' \
         `settings.rs`); do not edit by hand. Regenerate: {REGENERATE} -->\n\n"
    ));
    md.push_str(
        "Every parameter of the Vision profile (the TOML file `mach-vision run --profile`, Mach4 and \
         LinuxCNC load), and the read-only telemetry. Names are case-insensitive. A profile holds the \
         core's parameters in `[vision]` and each camera driver's in its own table; a key that is not \
         listed here, or a value outside its range, is refused when the profile loads, naming the key. \
         A key the file leaves out takes its default. Every stored parameter may be edited by the \
         operator; \"written by\" says what writes it in normal use.\n\n\
         Units: `in` is inches (25.4 mm per inch; the value is converted when the program runs in \
         G21), `Cal_Units` is the unit of `VisionCal_Units`, \"current units\" the program's G20/G21 \
         unit, `px` native camera pixels.\n\n",
    );
    for part in &parts {
        let count = part.specs.len();
        md.push_str(&format!("- [{}](#{}) — {count} parameters\n", part.heading, anchor(&part.heading)));
    }
    for part in &parts {
        md.push_str(&format!("\n## {}\n\n{}\n\n", part.heading, part.intro));
        md.push_str("| Key | Table | Default | Unit | Written by |\n|---|---|---|---|---|\n");
        for (spec, default) in &part.specs {
            let default = default.as_ref().map_or_else(String::new, |v| format!("`{}`", toml_text(v)));
            let unit = if spec.unit.is_empty() { "—" } else { spec.unit };
            let table = if part.table.starts_with('[') { format!("`{}`", part.table) } else { part.table.clone() };
            md.push_str(&format!(
                "| [`{}`](#{}) | {table} | {default} | {unit} | {} |\n",
                spec.name,
                spec.name.to_ascii_lowercase(),
                spec.writer
            ));
        }
        for (spec, default) in &part.specs {
            md.push_str(&format!("\n### {}\n\n", spec.name));
            let access = match spec.access {
                Access::Config => "",
                Access::Telemetry => " (read-only)",
            };
            let mut facts = match spec.access {
                Access::Config => format!("Table `{}`", part.table),
                Access::Telemetry => "Not stored".to_string(),
            };
            if let Some(v) = default {
                let _ = write!(facts, " · default `{}`", toml_text(v));
            }
            if !spec.unit.is_empty() {
                let _ = write!(facts, " · unit {}", spec.unit);
            }
            if spec.access == Access::Config {
                let _ = write!(facts, " · must be {}", range_text(spec));
            }
            let _ = write!(facts, " · written by {}{access}", spec.writer);
            md.push_str(&format!("{facts}.\n\n{}\n", description(spec)));
        }
    }
    md
}

/// A heading's GitHub anchor.
fn anchor(heading: &str) -> String {
    heading
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// A word as a program writes it (`P3`, `Q0.5`).
fn word(letter: char, v: f64) -> String {
    format!("{letter}{}", vision_math::show::number(v))
}

/// The refusal of M-code `m` with `words`, as the session reports it (through `controller`'s
/// dialect first), or `None` when accepted.
fn refusal(controller: &dyn vision_core::Controller, m: u32, words: &[(char, f64)]) -> Option<String> {
    match controller.manual_words(m, words) {
        Err(e) => Some(McodeError::from(e).to_string()),
        Ok(words) => VisionCall::parse(m, &words).err().map(|e| e.to_string()),
    }
}

/// A line of a program as the reference quotes it.
fn line(m: u32, words: &[(char, f64)]) -> String {
    let mut text = format!("M{m}");
    for (l, v) in words {
        text.push(' ');
        text.push_str(&word(*l, *v));
    }
    text
}

/// `docs/reference/mcodes.md`.
fn mcodes_md() -> String {
    let mach4 = CONTROLLERS[0];
    let mut md = String::new();
    md.push_str("# M-code reference\n\n");
    md.push_str(&format!(
        "<!-- Generated from vision-mcode's word table (MCODES) and the parser's own refusals; do not edit \
         by hand. Regenerate: {REGENERATE} -->\n\n"
    ));
    md.push_str(
        "The Vision M-codes M280–M284, the words each takes and the values of each word. A word's value may \
         be an expression or a #variable; letters may be written in either case. Every word must be one the \
         M-code takes, given at most once, with a finite value; otherwise the line is refused before \
         anything moves or changes, with the message shown. What each M-code does is in the \
         [calibration](../calibration.md) and [alignment](../alignment.md) guides; what they refuse while \
         they run is [at the end](#refusals-while-an-m-code-runs); the parameters they read are in \
         [parameters.md](parameters.md).\n\n",
    );
    md.push_str("| M-code | Does | Words |\n|---|---|---|\n");
    for spec in MCODES {
        let words: Vec<String> = spec.words.iter().map(|w| format!("`{}`", w.letter)).collect();
        md.push_str(&format!("| [M{}](#m{}) | {} | {} |\n", spec.m, spec.m, spec.title, words.join(", ")));
    }
    for spec in MCODES {
        md.push_str(&format!("\n## M{}\n\n{}.\n\n", spec.m, capitalised(spec.title)));
        md.push_str("| Word | Values |\n|---|---|\n");
        for w in spec.words {
            md.push_str(&format!("| `{}` | {} |\n", w.letter, w.values));
        }
        if spec.m == 283 {
            let sheets: Vec<String> = vision_core::CAL_SHEETS
                .iter()
                .map(|s| format!("{} ({}, {} dots of {} in)", s.id, s.name, s.dots_in.len(), s.mark_diameter_in))
                .collect();
            md.push_str(&format!(
                "\nThe sheets `C` walks: {}. `mach-vision sheet N` draws sheet N to print.\n",
                sheets.join("; ")
            ));
        }
        md.push_str("\nRefused (the message the operator sees):\n\n");
        // The table's refused values, then how any line goes wrong: two words of an M-code that
        // takes one of them, none of them, a letter it does not take, a word twice, a NaN.
        let mut examples: Vec<Vec<(char, f64)>> = Vec::new();
        for w in spec.words {
            examples.extend(w.refused.iter().map(|v| vec![(w.letter, *v)]));
        }
        let table_examples = examples.len();
        if let [a, b] = spec.words {
            examples.push(vec![(a.letter, 1.0), (b.letter, 1.0)]);
            examples.push(vec![]);
        }
        let first = spec.words.first().map_or('P', |w| w.letter);
        examples.push(vec![('X', 1.0)]);
        examples.push(vec![(first, 1.0), (first, 1.0)]);
        examples.push(vec![(first, f64::NAN)]);
        for (i, words) in examples.iter().enumerate() {
            let shown = if words.iter().any(|(_, v)| v.is_nan()) {
                format!("M{} {}[#1/0]", spec.m, first)
            } else {
                line(spec.m, words)
            };
            match refusal(mach4, spec.m, words) {
                Some(message) => md.push_str(&format!("- `{shown}` → {message}\n")),
                None => {
                    assert!(i >= table_examples, "MCODES: M{} lists {shown} as refused, but it is accepted", spec.m);
                }
            }
        }
    }
    md.push_str(
        "\n## Per controller\n\nThe words are the manual's on every controller except where a controller's \
         G-code gives the letter another meaning. How each writes the sheet calibration, and what its \
         dialect refuses:\n\n",
    );
    md.push_str("| Controller (`--dialect`, world `machine.dialect`) | Sheet calibration |\n|---|---|\n");
    for c in &CONTROLLERS {
        md.push_str(&format!("| `{}` | `{}` |\n", c.name(), c.sheet_calibration()));
    }
    md.push('\n');
    for c in &CONTROLLERS {
        let probes: [&[(char, f64)]; 3] = [&[('C', 1.0)], &[('P', 1.5)], &[('P', 1.0), ('Q', 0.25)]];
        for words in probes {
            if let Err(e) = c.manual_words(283, words) {
                md.push_str(&format!("- `{}`: `{}` → {}\n", c.name(), line(283, words), McodeError::from(e)));
            }
        }
    }
    md.push_str(&format!(
        "\nA number outside M280–M284 is not a Vision M-code: `M279` → {}\n",
        VisionCall::parse(279, &[]).expect_err("not vision")
    ));
    md.push_str(
        "\n## Refusals while an M-code runs\n\nA line whose words are accepted may still be refused by \
         the Vision module: every kind of refusal, what gives it, and its message with example values \
         (the parts in the example that name a tool, a value or a reason are the case's own). A refused \
         M-code changes nothing: no parameter, no alignment, no tool offset (a move it made before the \
         refusal is not undone; M283 leaves K, the axis flags and the tool offset as they were). The \
         message also goes to the `VisionLastStatus` telemetry.\n\n| Given by | Message (example) |\n|---|---|\n",
    );
    for e in vision_core::VisionError::examples() {
        md.push_str(&format!("| {} | {} |\n", e.given_by(), e.to_string().replace('|', "\\|")));
    }
    md
}

fn capitalised(s: &str) -> String {
    let mut chars = s.chars();
    chars.next().map_or_else(String::new, |c| c.to_uppercase().chain(chars).collect())
}

/// The marker lines around the generated built-in world in `world.md`.
const WORLD_BEGIN: &str = "<!-- begin: the built-in world, generated from vision-driver-sim's default_world.toml; \
                           regenerate: UPDATE_DOCS=1 cargo test -p vision-cli --bin mach-vision reference -->";
const WORLD_END: &str = "<!-- end: the built-in world -->";

/// `world.md` with its generated block (the built-in world's file) brought up to date.
fn world_md(current: &str) -> Result<String, String> {
    let (head, rest) = current.split_once(WORLD_BEGIN).ok_or("world.md has no begin marker")?;
    let (_, tail) = rest.split_once(WORLD_END).ok_or("world.md has no end marker")?;
    Ok(format!(
        "{head}{WORLD_BEGIN}\n\n```toml\n{}```\n\n{WORLD_END}{tail}",
        vision_driver_sim::world::DEFAULT_WORLD_TOML
    ))
}

/// `docs/reference/NAME`.
fn doc_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../docs/reference").join(name)
}

/// Compares `docs/reference/NAME` with `generated`, or rewrites it under `UPDATE_DOCS=1`.
fn check_or_update(name: &str, generated: &str) {
    let path = doc_path(name);
    if std::env::var_os("UPDATE_DOCS").is_some_and(|v| v == "1") {
        std::fs::write(&path, generated).expect("write the reference");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != generated {
        let at = committed.lines().zip(generated.lines()).position(|(a, b)| a != b).map_or_else(
            || "its length".to_string(),
            |i| {
                format!(
                    "line {}: committed {:?}, generated {:?}",
                    i + 1,
                    committed.lines().nth(i),
                    generated.lines().nth(i)
                )
            },
        );
        panic!(
            "docs/reference/{name} is out of date with the code's tables (first difference at {at}); \
             regenerate it with `{REGENERATE}` and commit it, after writing the new entry's doc"
        );
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser as _;

    use super::*;

    #[test]
    fn parameters_md_is_generated_from_the_tables() {
        check_or_update("parameters.md", &parameters_md());
    }

    #[test]
    fn mcodes_md_is_generated_from_the_word_table() {
        check_or_update("mcodes.md", &mcodes_md());
    }

    /// Every key a profile saved after example 1's sheet calibration holds, as `(table, key)`.
    fn calibrated_profile_keys() -> Vec<(String, String)> {
        let dir = std::env::temp_dir().join(format!("mach-vision-reference-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        let profile = dir.join("calibrated.toml");
        let program = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/programs/01-calibrate-sheet.nc");
        let cli = crate::Cli::try_parse_from([
            "mach-vision".as_ref(),
            "run".as_ref(),
            program.as_os_str(),
            "--profile".as_ref(),
            profile.as_os_str(),
        ])
        .expect("the command line");
        let crate::Command::Run(args) = cli.command else { unreachable!("a run") };
        crate::run::run(&args).map_err(|e| format!("{e:?}")).expect("example 1 calibrates");
        let text = std::fs::read_to_string(&profile).expect("the saved profile");
        let _ = std::fs::remove_dir_all(&dir);
        let file: toml::Table = text.parse().expect("TOML");
        let mut keys = Vec::new();
        for (table, entries) in &file {
            let entries = entries.as_table().expect("a profile holds tables");
            keys.extend(entries.keys().map(|k| (format!("[{table}]"), k.clone())));
        }
        keys
    }

    #[test]
    fn every_key_of_a_calibrated_profile_is_in_parameters_md() {
        let md = std::fs::read_to_string(doc_path("parameters.md")).expect("docs/reference/parameters.md");
        let keys = calibrated_profile_keys();
        // What M283 writes is there: the calibration and its record.
        for written in
            ["VisionCal_K11", "VisionCal_ResX", "VisionCal_Driver", "VisionCal_ToolOffsetX", "VisionCal_Mark"]
        {
            assert!(keys.iter().any(|(_, k)| k == written), "the profile holds {written}");
        }
        let missing: Vec<String> = keys
            .iter()
            .filter(|(table, key)| {
                !md.contains(&format!("\n### {key}\n"))
                    || !md.contains(&format!("| [`{key}`](#{}) | `{table}` |", key.to_ascii_lowercase()))
            })
            .map(|(table, key)| format!("{table} {key}"))
            .collect();
        assert!(
            missing.is_empty(),
            "docs/reference/parameters.md does not document {missing:?}; regenerate it: {REGENERATE}"
        );
    }

    /// Every key path of a world in which every optional key is given (arrays of tables by
    /// their key: `camera.job.id`).
    fn world_keys() -> Vec<String> {
        use vision_driver_sim::world::ImageLook;
        let mut world = World::default_world();
        world.camera.focus_z = Some(0.0);
        world.camera.reference_working_distance = Some(6.0);
        world.camera.distortion = Some([-0.1, 0.0, 0.0, 0.0, 0.0]);
        world.camera.image = Some(ImageLook { focus_distance: Some(6.0), ..ImageLook::default() });
        for job in &mut world.camera.jobs {
            job.noise_px = Some(0.1);
            job.margin_px = Some(30.0);
        }
        world.machine.camera_table_offset = Some([-3.25, 1.75]);
        world.machine.max_speed = Some(8.0);
        world.machine.max_accel = Some(20.0);
        for f in &mut world.fixtures {
            f.diameter = Some(0.5);
            f.center = Some([0.0, 0.0]);
        }
        assert!(!world.camera.jobs.is_empty() && !world.machine.tools.is_empty() && !world.fixtures.is_empty());
        let text = world.to_toml().expect("TOML");
        let value: toml::Table = text.parse().expect("TOML");
        let mut keys = Vec::new();
        walk("", &toml::Value::Table(value), &mut keys);
        keys.sort();
        keys.dedup();
        keys
    }

    fn walk(at: &str, v: &toml::Value, keys: &mut Vec<String>) {
        match v {
            toml::Value::Table(t) => {
                for (k, v) in t {
                    let path = if at.is_empty() { k.clone() } else { format!("{at}.{k}") };
                    keys.push(path.clone());
                    walk(&path, v, keys);
                }
            }
            toml::Value::Array(items) if items.iter().all(toml::Value::is_table) => {
                for item in items {
                    walk(at, item, keys);
                }
            }
            _ => {}
        }
    }

    #[test]
    fn every_world_key_is_in_world_md_and_every_key_there_exists() {
        let md = std::fs::read_to_string(doc_path("world.md")).expect("docs/reference/world.md");
        let keys = world_keys();
        assert!(keys.len() > 50, "{keys:?}");
        let missing: Vec<&String> = keys.iter().filter(|k| !md.contains(&format!("| `{k}` |"))).collect();
        assert!(missing.is_empty(), "docs/reference/world.md has no row for {missing:?}: add one");
        // Every documented key is one the format has.
        let documented: Vec<&str> =
            md.lines().filter_map(|l| l.strip_prefix("| `")?.split_once("` |").map(|(k, _)| k)).collect();
        let stale: Vec<&&str> = documented.iter().filter(|k| !keys.iter().any(|key| key == *k)).collect();
        assert!(stale.is_empty(), "docs/reference/world.md documents keys the world has not: {stale:?}");
    }

    /// The grammar probed letter by letter, not read from its table: a letter it does not refuse
    /// as unknown is a word, and its M-code's section of mcodes.md must list it.
    #[test]
    fn every_word_the_parser_takes_is_in_mcodes_md() {
        let md = std::fs::read_to_string(doc_path("mcodes.md")).expect("docs/reference/mcodes.md");
        let mut words = 0;
        for m in vision_mcode::VISION_MCODES {
            let section = md.split(&format!("\n## M{m}\n")).nth(1).expect("a section per M-code");
            let section = section.split("\n## ").next().unwrap_or(section);
            for letter in 'A'..='Z' {
                let taken = [0.0, 1.0, 2.0, 3.0, 4.0, 0.5, 1000.0]
                    .iter()
                    .any(|v| !matches!(VisionCall::parse(m, &[(letter, *v)]), Err(McodeError::UnknownWord { .. })));
                if taken {
                    words += 1;
                    assert!(
                        section.contains(&format!("| `{letter}` |")),
                        "mcodes.md: M{m} takes {letter}, undocumented"
                    );
                }
            }
        }
        assert_eq!(words, MCODES.iter().map(|s| s.words.len()).sum::<usize>());
    }

    #[test]
    fn world_md_shows_the_built_in_world() {
        let current = std::fs::read_to_string(doc_path("world.md")).expect("docs/reference/world.md");
        check_or_update("world.md", &world_md(&current).expect("the markers"));
    }
}
