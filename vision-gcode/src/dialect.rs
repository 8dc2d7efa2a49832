//! Where the controllers differ: each [`Dialect`] (the name a user picks) maps to one
//! [`DialectRules`] constant in [`Dialect::rules`], and the interpreter asks the rules, never
//! the name. A new controller is one more constant and one more arm in that table; adding a
//! rule makes the compiler ask every constant for its value (each states every rule).

use crate::geom::Xyz;
pub use crate::parse::CommentRule;

/// Whose rules apply where the controllers differ: the user-facing name of a
/// [`DialectRules`] constant (command line, world file, controller).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Dialect {
    /// Seed 002's MachineMotion path following ([`DialectRules::MACHINEMOTION`]). The default.
    #[default]
    MachineMotion,
    /// Mach4, the alignment plug-in's controller ([`DialectRules::MACH4`]).
    Mach4,
    /// LinuxCNC 2.9 ([`DialectRules::LINUXCNC`]).
    LinuxCnc,
    /// Grbl 1.1 behind a host that runs the program ([`DialectRules::GRBL`]).
    Grbl,
}

impl Dialect {
    /// Every dialect.
    pub const ALL: [Dialect; 4] = [Dialect::MachineMotion, Dialect::Mach4, Dialect::LinuxCnc, Dialect::Grbl];

    /// Its rules: the one table from a name to what it decides.
    #[must_use]
    pub const fn rules(self) -> &'static DialectRules {
        match self {
            Dialect::MachineMotion => &DialectRules::MACHINEMOTION,
            Dialect::Mach4 => &DialectRules::MACH4,
            Dialect::LinuxCnc => &DialectRules::LINUXCNC,
            Dialect::Grbl => &DialectRules::GRBL,
        }
    }

    /// Its name on the command line: `machinemotion`, `mach4`, `linuxcnc`, `grbl`.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Dialect::MachineMotion => "machinemotion",
            Dialect::Mach4 => "mach4",
            Dialect::LinuxCnc => "linuxcnc",
            Dialect::Grbl => "grbl",
        }
    }

    /// The dialect called `name` ([`Dialect::name`]), if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Dialect> {
        Dialect::ALL.into_iter().find(|d| d.name() == name)
    }

    /// The highest numbered parameter ([`DialectRules::last_parameter`]).
    #[must_use]
    pub const fn last_parameter(self) -> u32 {
        self.rules().last_parameter
    }

    /// The tool offset the placement subtracts from a work point (X, Y) and adds (Z), from the
    /// tool table's entry `table` ([`DialectRules::applied_tool_offset`]).
    #[must_use]
    pub fn applied_tool_offset(self, table: Xyz) -> Xyz {
        self.rules().applied_tool_offset(table)
    }
}

/// Which parts of a tool's table offset a step takes into the applied offset; the others keep
/// their applied value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OffsetParts {
    /// X, Y and the length (Z).
    Whole,
    /// X and Y; the length stays.
    Xy,
    /// The length (Z); X and Y stay.
    Length,
    /// None: the applied offset stays.
    Nothing,
}

impl OffsetParts {
    /// The applied offset after taking these parts of `offset` into `applied` (machine units).
    #[must_use]
    pub const fn take(self, applied: Xyz, offset: Xyz) -> Xyz {
        match self {
            OffsetParts::Whole => offset,
            OffsetParts::Xy => Xyz::new(offset.x, offset.y, applied.z),
            OffsetParts::Length => Xyz::new(applied.x, applied.y, offset.z),
            OffsetParts::Nothing => applied,
        }
    }
}

/// The behaviours in which the controllers' G-code differs, one named rule each. The
/// sources behind each value are in the repository's `docs/gcode-interpreter.md`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DialectRules {
    /// Where a `(` comment ends: seed 002 nests parentheses (its manual writes
    /// `( Corners at (+/- 2.5, +/- 4.0) inch )`), Mach4 nests when the line balances, LinuxCNC
    /// ends at the first `)` and refuses a `(` inside, Grbl ends at the first `)`.
    pub comments: CommentRule,
    /// The highest parameter number: LinuxCNC 2.9's 5601 (`RS274NGC_MAX_PARAMETERS` is 5602,
    /// indices below it); 9999 for Mach4 and seed 002, the range the pound-variable block of
    /// the seed's profile assumes (no source gives Mach4 a smaller one).
    pub last_parameter: u32,
    /// LinuxCNC's read-only named parameters (`#<_x>`, `#<_metric>`, …) exist and mirror the
    /// state.
    pub named_predefined_parameters: bool,
    /// G68/G69 rotation and G51/G50 scaling exist (Mach and Fanuc codes); LinuxCNC has
    /// neither and refuses them.
    pub rotation_and_scale_codes: bool,
    /// G52, the local shift, exists; Grbl has none (`error:20`).
    pub local_shift_code: bool,
    /// Why a code the dialect lacks is refused (G68/G51 without
    /// [`DialectRules::rotation_and_scale_codes`], G52 without
    /// [`DialectRules::local_shift_code`]), naming the controller; empty where none is refused.
    pub missing_code_note: &'static str,
    /// Each coordinate system has an XY rotation (`G10 L2 R`, parameter #5210 + 20·n):
    /// LinuxCNC. Elsewhere only `R0` is accepted and does nothing.
    pub rotated_systems: bool,
    /// The polar words `@` (distance) and `^` (angle) replace X/Y in G17: LinuxCNC.
    pub polar_words: bool,
    /// A program must end with M2/M30 or a closing `%`: LinuxCNC's rs274 refuses a file that
    /// just stops ("File ended with no percent sign or program end"); Mach4 and seed 002 run it.
    pub program_end_required: bool,
    /// A `%` line after the program began that does not close a `%`-opened program is an
    /// error (LinuxCNC); elsewhere it is ignored.
    pub percent_inside_refused: bool,
    /// G92 sets the offset of the axes it does not name to zero (seed 002); Mach4 and
    /// LinuxCNC keep it.
    pub g92_zeroes_unnamed_axes: bool,
    /// G52 and G92 share one offset (#5211–#5213) added to the program point before the
    /// system's rotation and worked out from the current point, never from the machine
    /// position (LinuxCNC's `convert_axis_offsets`). Elsewhere G52 is a separate local shift.
    pub g52_shares_g92_offset: bool,
    /// The interpreter keeps its own current point and moves it by each change of offset
    /// (G10, G43, G53, G54–G59, G92.1), as LinuxCNC's rs274 does, instead of re-reading it
    /// from the machine position. The two differ after a rotation change with a G92/G52
    /// offset in force, and the next G28 leg or incremental move starts from rs274's.
    pub carries_current_point: bool,
    /// A written origin parameter of the active system takes effect only when the system is
    /// selected again from another one or set by G10 (rs274 2.9's `convert_coordinate_system`
    /// reloads only on a change); in Mach4 and seed 002 at once, and selecting the active
    /// system again reloads it.
    pub origin_reloads_on_system_change: bool,
    /// G28/G30 with axis words read the stored position in the current system and give the
    /// named program axes of the waypoint its coordinates (LinuxCNC's `convert_home`: in a
    /// rotated system homing X alone moves the machine's Y too); elsewhere the named machine
    /// axes go to the stored machine position.
    pub home_axes_in_current_system: bool,
    /// Every G94/G95 sets the feed rate to 0, so a feed move needs a new F (LinuxCNC);
    /// elsewhere only a change of mode does, since F then means another thing.
    pub feed_mode_always_zeroes_feed: bool,
    /// `M3`/`M4`/`M5 A<device>` writes an output even without `P` (seed 002's explicit
    /// `A<device> P<port>` form, whose P it then asks for); elsewhere a lone A is the rotary
    /// axis.
    pub lone_a_selects_output: bool,
    /// A tool's X/Y table offset is added to a programmed point, as its length is
    /// (LinuxCNC: `machine = … + tool`); elsewhere it is subtracted (the offset is where the
    /// tool sits from the spindle).
    pub tool_xy_offset_added: bool,
    /// What `M6` applies of the new tool's offset: all of it in seed 002 (no G43); its X/Y in
    /// Mach4 (the manual selects the camera with `T98 M6` alone and expects its optical axis
    /// on the commanded point, SPEC §5); nothing in LinuxCNC (G43 applies it).
    pub tool_change_applies: OffsetParts,
    /// What `G43`/`G43.1`/`G49` apply: the length only in Mach4 (X/Y come from M6), all of it
    /// elsewhere.
    pub tool_length_applies: OffsetParts,
    /// What a new table entry of the loaded tool (a host's tool write, M283's offset) changes
    /// in the applied offset at once: its X/Y in Mach4 (the length waits for G43), all of it
    /// elsewhere.
    pub table_write_applies: OffsetParts,
}

impl DialectRules {
    /// Seed 002's MachineMotion path following: comments nest, G92 zeroes the axes it does
    /// not name, tool offsets apply from `M6` on, `M3 A1` is an output.
    pub const MACHINEMOTION: DialectRules = DialectRules {
        comments: CommentRule::Nested,
        last_parameter: 9999,
        named_predefined_parameters: false,
        rotation_and_scale_codes: true,
        local_shift_code: true,
        missing_code_note: "",
        rotated_systems: false,
        polar_words: false,
        program_end_required: false,
        percent_inside_refused: false,
        g92_zeroes_unnamed_axes: true,
        g52_shares_g92_offset: false,
        carries_current_point: false,
        origin_reloads_on_system_change: false,
        home_axes_in_current_system: false,
        feed_mode_always_zeroes_feed: false,
        lone_a_selects_output: true,
        tool_xy_offset_added: false,
        tool_change_applies: OffsetParts::Whole,
        tool_length_applies: OffsetParts::Whole,
        table_write_applies: OffsetParts::Whole,
    };

    /// Mach4: G92 keeps the axes it does not name, a tool's X/Y offset applies from `M6` and
    /// its length from `G43`, comments end at the balancing `)` when the line has one.
    pub const MACH4: DialectRules = DialectRules {
        comments: CommentRule::Mach4,
        last_parameter: 9999,
        named_predefined_parameters: false,
        rotation_and_scale_codes: true,
        local_shift_code: true,
        missing_code_note: "",
        rotated_systems: false,
        polar_words: false,
        program_end_required: false,
        percent_inside_refused: false,
        g92_zeroes_unnamed_axes: false,
        g52_shares_g92_offset: false,
        carries_current_point: false,
        origin_reloads_on_system_change: false,
        home_axes_in_current_system: false,
        feed_mode_always_zeroes_feed: false,
        lone_a_selects_output: false,
        tool_xy_offset_added: false,
        tool_change_applies: OffsetParts::Xy,
        tool_length_applies: OffsetParts::Length,
        table_write_applies: OffsetParts::Xy,
    };

    /// LinuxCNC 2.9's rs274: no G68/G51, rotated systems, polar words, its own current point,
    /// G52 on the G92 offset, tool offsets (added, X/Y too) from G43 only, comments end at the
    /// first `)`, a program ends with M2/M30 or `%`.
    pub const LINUXCNC: DialectRules = DialectRules {
        comments: CommentRule::Rs274,
        last_parameter: 5601,
        named_predefined_parameters: true,
        rotation_and_scale_codes: false,
        local_shift_code: true,
        missing_code_note: "Mach and Fanuc codes LinuxCNC does not have",
        rotated_systems: true,
        polar_words: true,
        program_end_required: true,
        percent_inside_refused: true,
        g92_zeroes_unnamed_axes: false,
        g52_shares_g92_offset: true,
        carries_current_point: true,
        origin_reloads_on_system_change: true,
        home_axes_in_current_system: true,
        feed_mode_always_zeroes_feed: true,
        lone_a_selects_output: false,
        tool_xy_offset_added: true,
        tool_change_applies: OffsetParts::Nothing,
        tool_length_applies: OffsetParts::Whole,
        table_write_applies: OffsetParts::Whole,
    };

    /// Grbl 1.1, the program run by the host (subroutines, expressions, parameters and cycles
    /// expanded there): no G68/G51 and no G52 (`error:20`; the sender applies M282's
    /// alignment), comments end at the first `)` (a `(` inside is text), G92 keeps the axes
    /// it does not name, no rotated systems or polar words, no program end needed, `%` ignored.
    /// The firmware has no tool table: the host keeps it and, since M6 never reaches the firmware,
    /// applies the new tool's X/Y at M6 and its length at G43, as Mach4 does. Parameters go to
    /// 9999 (the host's table), no named predefined ones, F is zeroed only by a change of feed
    /// mode, `A` is never an output: Mach4's rules but for the comments and the missing codes.
    pub const GRBL: DialectRules = DialectRules {
        comments: CommentRule::FirstClose,
        rotation_and_scale_codes: false,
        local_shift_code: false,
        missing_code_note:
            "codes Grbl does not have (error:20 on the firmware); M282 applies the alignment in the sender",
        ..DialectRules::MACH4
    };

    /// The tool offset the placement subtracts from a work point (X, Y) and adds (Z), from the
    /// tool table's entry `table` (machine units): the entry itself, with X/Y negated where
    /// [`DialectRules::tool_xy_offset_added`]. Its own inverse.
    #[must_use]
    pub const fn applied_tool_offset(&self, table: Xyz) -> Xyz {
        if self.tool_xy_offset_added {
            Xyz::new(-table.x, -table.y, table.z)
        } else {
            table
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::{Path, PathBuf};

    #[test]
    fn offset_parts_take_their_parts_and_keep_the_rest() {
        let (applied, offset) = (Xyz::new(1.0, 2.0, 3.0), Xyz::new(-4.0, 5.0, 6.0));
        assert_eq!(OffsetParts::Whole.take(applied, offset), offset);
        assert_eq!(OffsetParts::Xy.take(applied, offset), Xyz::new(-4.0, 5.0, 3.0));
        assert_eq!(OffsetParts::Length.take(applied, offset), Xyz::new(1.0, 2.0, 6.0));
        assert_eq!(OffsetParts::Nothing.take(applied, offset), applied);
    }

    #[test]
    fn every_dialect_has_its_own_rules_and_name() {
        for (i, a) in Dialect::ALL.into_iter().enumerate() {
            assert_eq!(Dialect::from_name(a.name()), Some(a));
            for b in Dialect::ALL.into_iter().skip(i + 1) {
                assert_ne!(a.rules(), b.rules(), "{} and {} are one dialect", a.name(), b.name());
                assert_ne!(a.name(), b.name());
            }
        }
        assert_eq!(Dialect::from_name("fanuc"), None);
    }

    #[test]
    fn the_highest_parameter_is_the_largest_dialects() {
        assert_eq!(crate::params::MAX_PARAMETER, 9999);
        assert!(Dialect::ALL.iter().all(|d| d.last_parameter() <= crate::params::MAX_PARAMETER));
    }

    #[test]
    fn the_applied_tool_offset_is_its_own_inverse() {
        let table = Xyz::new(0.5, -0.25, 1.5);
        for d in Dialect::ALL {
            assert_eq!(d.applied_tool_offset(d.applied_tool_offset(table)), table, "{}", d.name());
        }
        assert_eq!(Dialect::LinuxCnc.applied_tool_offset(table), Xyz::new(-0.5, 0.25, 1.5));
        assert_eq!(Dialect::Mach4.applied_tool_offset(table), table);
    }

    /// The `.rs` files under `dir`, recursively.
    fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for path in entries.flatten().map(|e| e.path()) {
            if path.is_dir() {
                rust_files(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }

    /// Where `code` (one line, comments removed) names a dialect to compare or match on: a
    /// variant (`Dialect::` and a CamelCase name, not a constant like `ALL`) or `dialect ==` /
    /// `!=`.
    fn names_a_dialect(code: &str) -> bool {
        let variant = code.match_indices("Dialect::").any(|(i, _)| {
            let before = code[..i].chars().next_back();
            let name: String =
                code[i + "Dialect::".len()..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            let camel = name.starts_with(char::is_uppercase) && name.chars().any(char::is_lowercase);
            !before.is_some_and(|c| c.is_alphanumeric() || c == '_') && camel
        });
        let lower = code.to_lowercase();
        variant || ["dialect ==", "dialect !=", "== dialect", "!= dialect"].iter().any(|p| lower.contains(p))
    }

    #[test]
    fn the_name_detector_finds_comparisons_and_matches_only() {
        assert!(names_a_dialect("if self.cfg.dialect == Dialect::LinuxCnc {"));
        assert!(names_a_dialect("Dialect::Mach4 | Dialect::LinuxCnc => offset,"));
        assert!(names_a_dialect("(dialect != crate::Dialect::LinuxCnc)"));
        assert!(names_a_dialect("if config.dialect == other {"));
        assert!(!names_a_dialect("Dialect::from_name(controller.dialect())"));
        assert!(!names_a_dialect("dialect: Dialect::default(),"));
        assert!(!names_a_dialect("DialectArg::Mach4"));
        assert!(!names_a_dialect("for d in crate::Dialect::ALL {"));
        assert!(!names_a_dialect("if self.cfg.rules().polar_words {"));
    }

    /// Issue 35: no code outside this table compares or matches a dialect by name; it asks the
    /// rules. Tests (a crate's `tests/`, a file's `mod tests`) may name dialects.
    #[test]
    fn no_library_code_outside_the_rules_table_names_a_dialect() {
        let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("workspace root");
        let mut files = Vec::new();
        for krate in std::fs::read_dir(workspace).expect("workspace").flatten() {
            rust_files(&krate.path().join("src"), &mut files);
        }
        assert!(files.len() > 50, "found only {} library files under {}", files.len(), workspace.display());
        let table = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/dialect.rs");
        let mut found = Vec::new();
        let test_module = |f: &Path| f.components().any(|c| c.as_os_str() == "tests");
        for file in files.iter().filter(|f| **f != table && !test_module(f.strip_prefix(workspace).unwrap_or(f))) {
            let text = std::fs::read_to_string(file).expect("readable source");
            // A file's own `#[cfg(test)] mod tests { … }` ends it.
            let library = match text.find("\nmod tests {") {
                Some(m) => &text[..text[..m].rfind("#[cfg(test)]").unwrap_or(m)],
                None => &text[..],
            };
            for (n, line) in library.lines().enumerate() {
                let code = line.split("//").next().unwrap_or("");
                if names_a_dialect(code) {
                    found.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
                }
            }
        }
        assert!(
            found.is_empty(),
            "ask the dialect's rules (vision_gcode::DialectRules) instead:\n{}",
            found.join("\n")
        );
    }
}
