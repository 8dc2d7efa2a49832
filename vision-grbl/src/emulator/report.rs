//! The text of Grbl's reports (report.c): numbers, `$G`, `$#`, `$I`.

use super::gcode::{GcState, Stored};
use super::Flavour;

/// `printFloat`: fixed decimals, and no minus sign on zero.
pub(crate) fn num(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].bytes().all(|b| b == b'0' || b == b'.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// `report_util_axis_values`: three coordinates, 3 decimals (mm).
pub(crate) fn axes(v: [f64; 3]) -> String {
    format!("{},{},{}", num(v[0], 3), num(v[1], 3), num(v[2], 3))
}

/// `$G`: `report_gcode_modes`.
pub(crate) fn gcode_modes(gc: &GcState) -> String {
    let mut out = format!(
        "[GC:G{} G{} G{} G{} G{} G{}",
        gc.motion,
        gc.coord_select + 54,
        gc.plane + 17,
        if gc.inches { 20 } else { 21 },
        if gc.incremental { 91 } else { 90 },
        if gc.inverse_time { 93 } else { 94 },
    );
    out.push_str(&format!(" M{}", gc.spindle));
    match (gc.mist, gc.flood) {
        (false, false) => out.push_str(" M9"),
        (mist, flood) => {
            if mist {
                out.push_str(" M7");
            }
            if flood {
                out.push_str(" M8");
            }
        }
    }
    out.push_str(&format!(" T{} F{} S{}]\r\n", gc.tool, num(gc.feed, 0), num(gc.speed, 0)));
    out
}

/// `$#`: `report_ngc_parameters`.
pub(crate) fn ngc_parameters(gc: &GcState, stored: &Stored) -> String {
    let mut out = String::new();
    for (i, c) in stored.coords.iter().enumerate() {
        out.push_str(&format!("[G{}:{}]\r\n", 54 + i, axes(*c)));
    }
    out.push_str(&format!("[G28:{}]\r\n[G30:{}]\r\n", axes(stored.g28), axes(stored.g30)));
    out.push_str(&format!(
        "[G92:{}]\r\n[TLO:{}]\r\n[PRB:0.000,0.000,0.000:0]\r\n",
        axes(gc.coord_offset),
        num(gc.tlo, 3)
    ));
    out
}

/// `$I`: `report_build_info`, the planner blocks and receive buffer in `[OPT:]`.
pub(crate) fn build_info(flavour: Flavour, m7: bool, blocks: usize, rx: usize) -> String {
    match flavour {
        Flavour::Grbl => {
            format!("[VER:1.1h.20190830:]\r\n[OPT:V{},{blocks},{rx}]\r\n", if m7 { "M" } else { "" })
        }
        Flavour::GrblHal => format!(
            "[VER:1.1f.20260817:]\r\n[OPT:VN{}L,{blocks},{rx},3,0]\r\n[FIRMWARE:grblHAL]\r\n",
            if m7 { "M" } else { "" }
        ),
    }
}

/// The welcome line after a power-up or a reset (`report_init_message`).
pub(crate) fn welcome(flavour: Flavour) -> &'static str {
    match flavour {
        Flavour::Grbl => "\r\nGrbl 1.1h ['$' for help]\r\n",
        Flavour::GrblHal => "\r\nGrblHAL 1.1f ['$' or '$HELP' for help]\r\n",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_like_print_float() {
        assert_eq!(num(-0.0001, 3), "0.000");
        assert_eq!(num(-1.25, 3), "-1.250");
        assert_eq!(axes([1.0, -2.0, 0.0]), "1.000,-2.000,0.000");
    }

    #[test]
    fn modes_print_the_defaults() {
        let gc = GcState::new([0.0; 3], &Stored::default());
        assert_eq!(gcode_modes(&gc), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\n");
    }
}
