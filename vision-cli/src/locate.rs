//! `mach-vision locate`: find the fiducial mark in image files with `vision-locate`.
//!
//! Each image (PNG, JPEG, PGM/PPM, BMP; 8- or 16-bit gray, colour converted to luma) gets one
//! line: the mark's centre in native pixels ((0, 0) = centre of the top-left pixel, y down),
//! its size and score, or why there is none. Exit 0 when every image has its mark, 1 when one
//! has none, 2 on bad input.
//!
//! Bounds: every file's header is read first, and an image over 100 megapixels, or one whose
//! search would take more than the finder's 1 GiB ([`vision_locate::MAX_SEARCH_BYTES`]: a
//! small `--diameter` on a large image searches it in small blocks), is refused before any is
//! decoded (exit 2). The images are then decoded, searched and dropped one at a time.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use serde_json::json;
use vision_locate::{locate, GrayImage, Located, MarkKind, MarkSpec, NotFoundReason, Pixels, Polarity};

use crate::{image_size, Failure};

/// Arguments of `mach-vision locate`.
#[derive(Debug, Args)]
pub(crate) struct LocateArgs {
    /// The mark's shape.
    #[arg(long, value_enum, default_value_t = MarkArg::Dot)]
    mark: MarkArg,
    /// Expected size in image pixels: a dot's or ring's outer diameter, a cross's bar length.
    #[arg(long)]
    diameter: f64,
    /// Accepted size deviation in percent (0 < PCT < 100).
    #[arg(long, default_value_t = 25.0)]
    tolerance: f64,
    /// Dark mark on a light ground, or light on dark.
    #[arg(long, value_enum, default_value_t = PolarityArg::Dark)]
    polarity: PolarityArg,
    /// One JSON object per image (one per line) instead of the readable lines.
    #[arg(long)]
    json: bool,
    /// Image files.
    #[arg(required = true)]
    images: Vec<PathBuf>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum MarkArg {
    /// A filled disc.
    Dot,
    /// A circular ring.
    Ring,
    /// Two perpendicular bars.
    Cross,
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

fn read_image(path: &std::path::Path) -> Result<(usize, usize, Samples), Failure> {
    let img = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| Failure::Input(format!("cannot read image {}: {e}", path.display())))?
        .decode()
        .map_err(|e| {
            Failure::Input(format!("cannot decode image {}: {e} — use PNG, JPEG, PGM or BMP", path.display()))
        })?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    // 16-bit sources keep their depth; everything else is 8-bit luma (colour → Rec. 709 luma).
    let samples = match img.color() {
        image::ColorType::L16 | image::ColorType::La16 | image::ColorType::Rgb16 | image::ColorType::Rgba16 => {
            Samples::Sixteen(img.into_luma16().into_raw())
        }
        _ => Samples::Eight(img.into_luma8().into_raw()),
    };
    Ok((w, h, samples))
}

pub(crate) fn run(args: &LocateArgs) -> Result<String, Failure> {
    let kind = match args.mark {
        MarkArg::Dot => MarkKind::Dot,
        MarkArg::Ring => MarkKind::Ring,
        MarkArg::Cross => MarkKind::Cross,
    };
    let polarity = match args.polarity {
        PolarityArg::Dark => Polarity::DarkOnLight,
        PolarityArg::Light => Polarity::LightOnDark,
    };
    let spec = MarkSpec::new(kind, args.diameter, args.tolerance / 100.0, polarity)
        .map_err(|e| Failure::Input(format!("--diameter {} --tolerance {}: {e}", args.diameter, args.tolerance)))?;
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
        let view =
            GrayImage::new(w, h, pixels).map_err(|e| Failure::Input(format!("image {}: {e}", path.display())))?;
        let located = locate(&view, &spec).map_err(|e| Failure::Input(e.to_string()))?;
        let name = path.display().to_string();
        match located {
            Located::Found(m) => {
                if args.json {
                    let mut o = json!({"file": name, "found": true, "x": m.x, "y": m.y, "diameter": m.diameter, "score": m.score});
                    if let Some(a) = m.angle {
                        o["angle_deg"] = json!(a.to_degrees());
                    }
                    writeln!(out, "{o}").expect("writing to a String");
                } else {
                    let angle = m.angle.map(|a| format!(" angle={:.3}°", a.to_degrees())).unwrap_or_default();
                    writeln!(
                        out,
                        "{name}: found x={:.4} y={:.4} diameter={:.3}{angle} score={:.4}",
                        m.x, m.y, m.diameter, m.score
                    )
                    .expect("writing to a String");
                }
            }
            Located::NotFound(why) => {
                missing.push(name.clone());
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
                    writeln!(out, "{name}: not found: {why}").expect("writing to a String");
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
