//! `mach-vision locate`: find the fiducial mark in image files with `vision-locate`.
//!
//! Each image (PNG, JPEG, PGM/PPM, BMP; 8- or 16-bit gray, colour converted to luma) gets one
//! line: the mark's centre in native pixels ((0, 0) = centre of the top-left pixel, y down),
//! its size and score, or why there is none. Exit 0 when every image has its mark, 1 when one
//! has none, 2 on bad input (also a path that is not a regular file, and a damaged image).
//! A name that could be mistaken for output is quoted in the text lines ([`shown`]).
//!
//! Bounds: every file's header is read first, and an image over 100 megapixels, or one whose
//! search would take more than the finder's 1 GiB ([`vision_locate::MAX_SEARCH_BYTES`]: a
//! small `--diameter` on a large image searches it in small blocks), is refused before any is
//! decoded (exit 2). The images are then decoded, searched and dropped one at a time.
//!
//! With `--profile`, each found mark is also given undistorted: the profile's lens
//! (`VisionLensK1`…`VisionLensFocalPx`, about the optical centre `res/2 + PxCenterOffset`)
//! undone as M281's pixel chain undoes it, still in locate's pixels. A profile that cannot be
//! read, or whose lens folds over its image, is refused (exit 2); with a lens, so is an image
//! whose size is not the profile's `VisionCameraResX` × `VisionCameraResY` (the lens is
//! centred on that image).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, ValueEnum};
use serde_json::json;
use vision_core::{Params, ProfileStore};
use vision_driver_camera::decode::{decode_grey, DecodeError, GreySamples};
use vision_driver_camera::file::open_regular;
use vision_driver_sim::Sim;
use vision_locate::{
    locate, GrayImage, Located, MarkKind, MarkSpec, NotFoundReason, Pixels, Polarity, SpecError, MIN_DIAMETER_PX,
};
use vision_math::show::number;
use vision_math::{Matrix2, PixelChain, Point2, Remap, Vector2};

use crate::{image_size, world, Failure};

/// Arguments of `mach-vision locate`.
#[derive(Debug, Args)]
pub(crate) struct LocateArgs {
    /// The mark's shape.
    #[arg(long, value_parser = mark_kind(), default_value_t = MarkKind::Dot)]
    mark: MarkKind,
    /// Expected size in image pixels: a dot's or ring's outer diameter, a cross's bar length.
    #[arg(long, allow_negative_numbers = true)]
    diameter: f64,
    /// Accepted size deviation in percent (0 < PCT < 100).
    #[arg(long, default_value_t = 25.0, allow_negative_numbers = true)]
    tolerance: f64,
    /// Dark mark on a light ground, or light on dark.
    #[arg(long, value_enum, default_value_t = PolarityArg::Dark)]
    polarity: PolarityArg,
    /// One JSON object per image (one per line) instead of the readable lines.
    #[arg(long)]
    json: bool,
    /// A Vision profile whose lens (and optical centre and resolution) undistorts each found
    /// mark: JSON gains `distorted` and `undistorted`, a text line ` undistorted (x, y)` when
    /// the profile has a lens. Read only.
    #[arg(long, value_name = "P.toml")]
    profile: Option<PathBuf>,
    /// Image files.
    #[arg(required = true)]
    images: Vec<PathBuf>,
}

/// `--mark`: the finder's [`MarkKind`], listed in the help as clap lists an enum's values.
fn mark_kind() -> impl TypedValueParser<Value = MarkKind> {
    let help = |kind: MarkKind| match kind {
        MarkKind::Dot => "A filled disc",
        MarkKind::Ring => "A circular ring",
        MarkKind::Cross => "Two perpendicular bars",
    };
    PossibleValuesParser::new(MarkKind::ALL.map(|k| PossibleValue::new(k.name()).help(help(k))))
        .try_map(|word| word.parse::<MarkKind>())
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum PolarityArg {
    /// Dark mark on a light ground.
    Dark,
    /// Light mark on a dark ground.
    Light,
}

/// A decoded image: its samples at its own depth.
enum Samples {
    Eight(Vec<u8>),
    Sixteen(Vec<u16>),
}

/// Reads and decodes `path` with the camera driver's bounded decoder
/// ([`vision_driver_camera::decode`]): only a regular file is opened (a FIFO or a device is
/// refused unread, without blocking), the size is checked from the header first, a cut-short
/// JPEG is refused as damaged, 16-bit samples are scaled by their range.
fn read_image(path: &std::path::Path) -> Result<(usize, usize, Samples), Failure> {
    let name = shown(path);
    let file = open_regular(path).map_err(|e| Failure::Input(format!("cannot read image {name}: {e}")))?;
    let grey = decode_grey(std::io::BufReader::new(file), u32::MAX).map_err(|e| {
        Failure::Input(match e {
            DecodeError::Damaged(why) => format!("image {name} is damaged: {why} — copy or save it again, whole"),
            DecodeError::TooLarge { .. } => format!("image {name}: {e} — crop or scale it down"),
            _ => format!("cannot decode image {name}: {e} — use PNG, JPEG, PGM or BMP"),
        })
    })?;
    let (w, h) = (grey.width() as usize, grey.height() as usize);
    let samples = match grey.into_samples() {
        GreySamples::Eight(p) => Samples::Eight(p),
        GreySamples::Sixteen(p) => Samples::Sixteen(p),
    };
    Ok((w, h, samples))
}

/// A file name as the text output prints it: as it is, unless it could be mistaken for output
/// (a control character such as a newline, a `"`, a `: `, leading or trailing white space, or
/// nothing at all); then quoted and escaped as a Rust string literal (`"a.png\nb"`).
fn shown(path: &std::path::Path) -> String {
    let name = path.display().to_string();
    let ambiguous = name.is_empty()
        || name.chars().any(|c| c.is_control() || c == '"')
        || name.contains(": ")
        || name.starts_with(char::is_whitespace)
        || name.ends_with(char::is_whitespace);
    if ambiguous {
        format!("{name:?}")
    } else {
        name
    }
}

/// The checked mark spec, or the option's fault in the option's own units (the tolerance is a
/// percentage here, a fraction in [`MarkSpec`]); numbers through the one formatter.
fn spec_of(args: &LocateArgs, kind: MarkKind, polarity: Polarity) -> Result<MarkSpec, Failure> {
    MarkSpec::new(kind, args.diameter, args.tolerance / 100.0, polarity).map_err(|e| {
        let diameter = number(args.diameter);
        Failure::Input(match e {
            SpecError::Diameter(_) => {
                format!("--diameter {diameter}: not a positive number — give the mark's size in image pixels")
            }
            SpecError::DiameterTooSmall(_) => format!(
                "--diameter {diameter}: below the {} px the finder can measure — zoom in or print a larger mark",
                number(MIN_DIAMETER_PX)
            ),
            SpecError::Tolerance(_) => format!(
                "--tolerance {}: not a percentage between 0 and 100 (exclusive) — e.g. 25 for ±25 %",
                number(args.tolerance)
            ),
            other => format!("--diameter {diameter} --tolerance {}: {other}", number(args.tolerance)),
        })
    })
}

/// The pixel chain of `profile` that undoes its lens, K and the remap left out (locate has no
/// machine units): `None` without `--profile`.
fn lens_chain(profile: Option<&Path>) -> Result<Option<PixelChain>, Failure> {
    let Some(path) = profile else { return Ok(None) };
    let name = shown(path);
    if !path.is_file() {
        return Err(Failure::Input(format!("no profile {name}: --profile reads one")));
    }
    let input = |e: &dyn std::fmt::Display| Failure::Input(format!("profile {name}: {e}"));
    // Loaded as `run` and `panel` load one: the registry's drivers (the simulated camera's
    // among them) give the defaults, so any profile they save reads here.
    let sim = Sim::new(world::load(None)?).map_err(|e| input(&e))?;
    let registry = vision_host::cameras(Some(&sim));
    // The store's errors name the file themselves.
    let params: Params =
        ProfileStore::new(path).with_defaults(registry.params()).load().map_err(|e| Failure::Input(e.to_string()))?;
    let resolution = Vector2::new(params.camera_res_x() as f64, params.camera_res_y() as f64);
    let centre = Vector2::new(params.px_center_offset_x(), params.px_center_offset_y());
    let chain = PixelChain::new(Matrix2::identity(), Remap::IDENTITY, resolution, centre).map_err(|e| input(&e))?;
    match params.calibration.lens() {
        Some(lens) => chain.with_lens(lens).map(Some).map_err(|e| input(&e)),
        None => Ok(Some(chain)),
    }
}

/// The mark at locate's pixel (`x`, `y`) with `chain`'s lens undone, in locate's pixels. The
/// chain's native pixels have their origin at the top-left pixel's corner, locate's at its
/// centre: half a pixel apart.
fn undistorted(chain: &PixelChain, x: f64, y: f64) -> (f64, f64) {
    let native = Point2::new(x + 0.5, y + 0.5);
    let ideal = chain.undistorted(native) - chain.centred(Point2::origin());
    (ideal.x - 0.5, ideal.y - 0.5)
}

pub(crate) fn run(args: &LocateArgs) -> Result<String, Failure> {
    let chain = lens_chain(args.profile.as_deref())?;
    let kind = args.mark;
    let polarity = match args.polarity {
        PolarityArg::Dark => Polarity::DarkOnLight,
        PolarityArg::Light => Polarity::LightOnDark,
    };
    let spec = spec_of(args, kind, polarity)?;
    // Every file's header is read and sized first: a bad path or an image too large to search
    // fails the whole call (exit 2) before any work. Then one image at a time is decoded,
    // searched and dropped: memory holds one image, not all of them.
    for path in &args.images {
        image_size::check_image_size(path, &spec)?;
    }
    let mut out = String::new();
    let mut missing = Vec::new();
    for path in &args.images {
        let (w, h, samples) = read_image(path)?;
        let pixels = match &samples {
            Samples::Eight(p) => Pixels::Gray8(p),
            Samples::Sixteen(p) => Pixels::Gray16(p),
        };
        let view = GrayImage::new(w, h, pixels).map_err(|e| Failure::Input(format!("image {}: {e}", shown(path))))?;
        if let Some(c) = chain.as_ref().filter(|c| c.lens().is_some()) {
            let res = c.resolution();
            if (w as f64, h as f64) != (res.x, res.y) {
                return Err(Failure::Input(format!(
                    "image {} is {w} x {h} px, but the profile's camera is {} x {} px (VisionCameraResX/ResY): \
                     its lens is centred on that image",
                    shown(path),
                    res.x,
                    res.y
                )));
            }
        }
        let located = locate(&view, &spec).map_err(|e| Failure::Input(e.to_string()))?;
        // JSON escapes the name itself; the text lines quote it when it could be mistaken.
        let name = path.display().to_string();
        let text_name = shown(path);
        match located {
            Located::Found(m) => {
                if args.json {
                    let mut o = json!({"file": name, "found": true, "x": m.x, "y": m.y, "diameter": m.diameter, "score": m.score});
                    if let Some(a) = m.angle {
                        o["angle_deg"] = json!(a.to_degrees());
                    }
                    if let Some(c) = &chain {
                        let (ux, uy) = undistorted(c, m.x, m.y);
                        o["distorted"] = json!({"x": m.x, "y": m.y});
                        o["undistorted"] = json!({"x": ux, "y": uy});
                    }
                    writeln!(out, "{o}").expect("writing to a String");
                } else {
                    let angle = m.angle.map(|a| format!(" angle={:.3}°", a.to_degrees())).unwrap_or_default();
                    let ideal = match chain.as_ref().filter(|c| c.lens().is_some()) {
                        Some(c) => {
                            let (ux, uy) = undistorted(c, m.x, m.y);
                            format!(" undistorted ({ux:.4}, {uy:.4})")
                        }
                        None => String::new(),
                    };
                    writeln!(
                        out,
                        "{text_name}: found x={:.4} y={:.4} diameter={:.3}{angle} score={:.4}{ideal}",
                        m.x, m.y, m.diameter, m.score
                    )
                    .expect("writing to a String");
                }
            }
            Located::NotFound(why) => {
                missing.push(text_name.clone());
                if args.json {
                    let mut o =
                        json!({"file": name, "found": false, "reason": reason_code(&why), "message": why.to_string()});
                    match why {
                        NotFoundReason::SeveralCandidates { count } => o["count"] = json!(count),
                        NotFoundReason::SizeOutOfRange { diameter, min, max } => {
                            o["diameter"] = json!(diameter);
                            (o["min"], o["max"]) = (json!(min), json!(max));
                        }
                        NotFoundReason::OtherSize { about, min, max } => {
                            o["about"] = json!(about);
                            (o["min"], o["max"]) = (json!(min), json!(max));
                        }
                        NotFoundReason::Cluttered { limit } => o["limit"] = json!(limit),
                        _ => {}
                    }
                    writeln!(out, "{o}").expect("writing to a String");
                } else {
                    writeln!(out, "{text_name}: not found: {why}").expect("writing to a String");
                }
            }
        }
    }
    if missing.is_empty() {
        Ok(out)
    } else {
        Err(Failure::RunWithReport {
            output: out,
            message: format!("no mark in {} of {} images: {}", missing.len(), args.images.len(), missing.join(", ")),
        })
    }
}

/// The stable, machine-readable name of a reason.
fn reason_code(why: &NotFoundReason) -> &'static str {
    match why {
        NotFoundReason::NoCandidate => "no_candidate",
        NotFoundReason::SeveralCandidates { .. } => "several_candidates",
        NotFoundReason::Clipped => "clipped",
        NotFoundReason::SizeOutOfRange { .. } => "size_out_of_range",
        NotFoundReason::OtherSize { .. } => "other_size",
        NotFoundReason::Cluttered { .. } => "cluttered",
    }
}
