//! `mach-vision fit`: one least-squares fit from JSON, as a report or as JSON.
//!
//! Input schema: `{"commanded": [[x, y], ...], "observed": [[x, y], ...]}` (machine units; the
//! i-th observed point is where the i-th commanded mark was found).

use std::fmt::Write as _;
use std::io::Read as _;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use serde::{Deserialize, Serialize};
use vision_math::{Fit, Model, Point2};

use crate::terminal::{is_terminal, Stream};
use crate::Failure;

/// Arguments of `mach-vision fit`.
#[derive(Debug, Args)]
pub(crate) struct FitArgs {
    /// The transform model.
    #[arg(long, value_enum, default_value_t = ModelArg::Rectangle)]
    model: ModelArg,
    /// Print one JSON object instead of the readable report.
    #[arg(long)]
    json: bool,
    /// JSON input file; standard input when omitted or `-`.
    file: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum ModelArg {
    /// Shift + rotation.
    Rigid,
    /// Shift + rotation + uniform scale (M280 P3).
    Similarity,
    /// Shift + rotation + X and Y scale, no shear (M280 P4, the default).
    Rectangle,
    /// Shift + full 2x2 matrix (has shear; no G-code).
    Affine,
}

impl From<ModelArg> for Model {
    fn from(m: ModelArg) -> Model {
        match m {
            ModelArg::Rigid => Model::Rigid,
            ModelArg::Similarity => Model::Similarity,
            ModelArg::Rectangle => Model::Rectangle,
            ModelArg::Affine => Model::Affine,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Input {
    commanded: Vec<[f64; 2]>,
    observed: Vec<[f64; 2]>,
}

/// The JSON report: every parameter, the residuals, the RMS and the emitted G-code.
#[derive(Debug, Serialize)]
struct Report {
    model: &'static str,
    points: usize,
    theta_deg: f64,
    theta_rad: f64,
    scale: [f64; 2],
    shear: f64,
    /// `o = linear · n + offset`.
    linear: [[f64; 2]; 2],
    offset: [f64; 2],
    commanded_centroid: [f64; 2],
    observed_centroid: [f64; 2],
    /// G52 X Y.
    shift: Option<[f64; 2]>,
    /// G68 X Y.
    center: Option<[f64; 2]>,
    residuals: Vec<[f64; 2]>,
    residual_lengths: Vec<f64>,
    rms: f64,
    max_residual: f64,
    gcode: Option<Vec<String>>,
}

/// Runs the subcommand and returns the text to print.
pub(crate) fn run(args: &FitArgs) -> Result<String, Failure> {
    let text = read_input(args.file.as_ref())?;
    // serde would read the struct from a bare array too; the schema is an object.
    if !text.trim_start().starts_with('{') {
        return Err(Failure::Input(
            "input is not valid fit JSON: expected an object {\"commanded\": [[x, y], ...], \"observed\": [[x, y], ...]}"
                .into(),
        ));
    }
    let input: Input =
        serde_json::from_str(&text).map_err(|e| Failure::Input(format!("input is not valid fit JSON: {e}")))?;
    let commanded: Vec<Point2<f64>> = input.commanded.iter().map(|p| Point2::new(p[0], p[1])).collect();
    let observed: Vec<Point2<f64>> = input.observed.iter().map(|p| Point2::new(p[0], p[1])).collect();
    let model = Model::from(args.model);
    let fit = model.fit(&commanded, &observed).map_err(|e| Failure::Input(e.to_string()))?;
    let report = report(&fit, &commanded, &observed)?;
    if args.json {
        let mut s = serde_json::to_string_pretty(&report).map_err(|e| Failure::Input(e.to_string()))?;
        s.push('\n');
        Ok(s)
    } else {
        Ok(render(&report, &commanded, &observed))
    }
}

fn read_input(file: Option<&PathBuf>) -> Result<String, Failure> {
    match file {
        Some(path) if path.as_os_str() != "-" => {
            std::fs::read_to_string(path).map_err(|e| Failure::Input(format!("cannot read {}: {e}", path.display())))
        }
        _ => {
            if file.is_none() && is_terminal(Stream::Stdin) {
                // Not left waiting in silence for input the person may not know is wanted.
                crate::terminal::show(&format!(
                    "mach-vision fit: reading the JSON from standard input — type or paste it, then press {} \
                     (or give a file: mach-vision fit FILE.json)",
                    if cfg!(windows) { "Ctrl-Z and Enter" } else { "Ctrl-D" }
                ));
            }
            let mut s = String::new();
            std::io::stdin()
                .read_to_string(&mut s)
                .map_err(|e| Failure::Input(format!("cannot read standard input: {e}")))?;
            Ok(s)
        }
    }
}

fn report(fit: &Fit, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Report, Failure> {
    let residuals = fit.residuals(commanded, observed);
    let t = &fit.transform;
    let chain = t.chain();
    let gcode = match &chain {
        Some(c) => {
            let commands = vision_core::controller::modal_commands(c).map_err(|e| Failure::Input(e.to_string()))?;
            let mach4 = &vision_core::controller::Mach4;
            Some(vision_mcode::lines(mach4, &commands).map_err(|e| Failure::Input(e.to_string()))?)
        }
        None => None,
    };
    let l = t.linear();
    let off = t.offset();
    Ok(Report {
        model: t.model.name(),
        points: fit.len,
        theta_deg: t.theta_deg(),
        theta_rad: t.theta_rad(),
        scale: [t.scale.x, t.scale.y],
        shear: t.shear,
        linear: [[l[(0, 0)], l[(0, 1)]], [l[(1, 0)], l[(1, 1)]]],
        offset: [off.x, off.y],
        commanded_centroid: [t.commanded_centroid.x, t.commanded_centroid.y],
        observed_centroid: [t.observed_centroid.x, t.observed_centroid.y],
        shift: chain.map(|c| [c.shift.x, c.shift.y]),
        center: chain.map(|c| [c.center.x, c.center.y]),
        residual_lengths: residuals.iter().map(vision_math::Vector2::norm).collect(),
        residuals: residuals.iter().map(|r| [r.x, r.y]).collect(),
        rms: fit.rms,
        max_residual: fit.max_residual,
        gcode,
    })
}

fn render(r: &Report, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> String {
    let mut s = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(s, "{} fit of {} marks", r.model, r.points);
    let _ = writeln!(s, "  rotation   {:+.6} deg ({:+.9} rad)", r.theta_deg, r.theta_rad);
    let _ = writeln!(s, "  scale      X {:.8}  Y {:.8}", r.scale[0], r.scale[1]);
    if r.model == Model::Affine.name() {
        let _ = writeln!(s, "  shear      {:+.8}", r.shear);
    }
    if let (Some(shift), Some(center)) = (r.shift, r.center) {
        let _ = writeln!(s, "  shift      X {:+.6}  Y {:+.6}  (G52)", shift[0], shift[1]);
        let _ = writeln!(s, "  centre     X {:+.6}  Y {:+.6}  (G68, commanded centroid)", center[0], center[1]);
    }
    let _ = writeln!(s, "  residual   RMS {:.6}  max {:.6}", r.rms, r.max_residual);
    let _ = writeln!(s);
    let _ = writeln!(s, "  mark   commanded X   commanded Y    observed X    observed Y     residual");
    for (i, ((n, o), d)) in commanded.iter().zip(observed).zip(&r.residual_lengths).enumerate() {
        let _ = writeln!(s, "  {:>4} {:>13.6} {:>13.6} {:>13.6} {:>13.6} {:>12.6}", i + 1, n.x, n.y, o.x, o.y, d);
    }
    let _ = writeln!(s);
    match &r.gcode {
        Some(lines) => {
            let _ = writeln!(s, "  G-code (M282):");
            for line in lines {
                let _ = writeln!(s, "    {line}");
            }
        }
        None => {
            let _ = writeln!(s, "  no G-code: shear cannot be expressed with G51/G68/G52; use the rectangle model");
        }
    }
    s
}
