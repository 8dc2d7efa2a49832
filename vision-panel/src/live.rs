//! [`observe`]: one look through a camera driver, as M281 takes it — a frame searched by the
//! driver (its search window, its mark settings) — turned into a [`View`].

use std::sync::Arc;

use vision_core::{Calibration, ParamValue, Params};
use vision_driver_camera::{FrameDriver, FrameSource, Polarity};
use vision_math::{PixelChain, Vector2};

use crate::view::{MachineOffset, Mark, Spec, View};

/// Triggers `driver` once and describes what it saw. `params` gives K, the remap and the
/// optical centre (for the offset in machine units, when K is set) and the calibration shown.
pub fn observe<S: FrameSource>(driver: &mut FrameDriver<S>, params: &Params) -> View {
    let source = driver.source().describe();
    let mut view = View { source, params: calibration(params), spec: spec(driver), ..View::default() };
    let reading = match driver.measure() {
        Ok(r) => r,
        Err(e) => {
            view.why_ng = Some(format!("the camera: {e}"));
            return view;
        }
    };
    let Some(frame) = driver.last_frame() else { return view };
    let (w, h) = (f64::from(frame.width()), f64::from(frame.height()));
    let pct = driver.config().mark.search_radius_pct;
    view.search_radius_px = (pct < 100.0).then(|| pct.max(0.0) / 100.0 * w.min(h) / 2.0);
    if reading.found() {
        // The driver's native pixels (corner origin) → locate's pixel centres.
        view.mark = Some(Mark {
            x: reading.x_px - 0.5,
            y: reading.y_px - 0.5,
            diameter: reading.width_px,
            score: reading.score,
        });
        view.offset_px = Some((reading.x_px - w / 2.0, reading.y_px - h / 2.0));
        let centre = Vector2::new(params.px_center_offset_x(), params.px_center_offset_y());
        // The lens undone before K, as M281 does (a lens that folds over the frame: no offset).
        let chain = PixelChain::new(params.cal_k(), params.remap(), Vector2::new(w, h), centre)
            .and_then(|c| params.calibration.lens().map_or(Ok(c), |lens| c.with_lens(lens)));
        if let Ok(chain) = chain {
            let d = chain.delta(vision_math::Point2::new(reading.x_px, reading.y_px));
            let unit = params.cal_units().short_name().to_string();
            view.offset_machine = Some(MachineOffset { x: d.x, y: d.y, unit });
        }
    } else {
        view.why_ng = Some(driver.last_miss().map_or_else(|| "no mark".to_string(), |m| m.reason.clone()));
    }
    view.frame = Some(Arc::new(frame.clone()));
    view
}

fn spec<S: FrameSource>(driver: &FrameDriver<S>) -> Option<Spec> {
    let mark = &driver.config().mark;
    Some(Spec {
        kind: mark.kind.name().to_string(),
        polarity: if mark.polarity == Polarity::Dark { "dark" } else { "light" }.to_string(),
        diameter_px: mark.diameter_px?,
        tolerance_pct: mark.tolerance_pct,
    })
}

/// The calibration parameters (K, offset, centre, date, …), by name, as the profile writes
/// them: the page's read-only calibration table.
#[must_use]
pub fn calibration(params: &Params) -> Vec<(String, String)> {
    Calibration::SPECS
        .iter()
        .filter_map(|s| {
            let value = match params.get(s.name).ok()? {
                ParamValue::Text(t) => t,
                other => other.to_string(),
            };
            Some((s.name.to_string(), value))
        })
        .collect()
}

/// One calibration as a line of the page's history: K, the camera tool's offset and the pixel
/// centre, each value as `value` gives it by manual name (`?` for one it has not), and the lens
/// when it has one (`VisionLensFocalPx` above 0): each coefficient ± its 1σ, 5 decimals.
#[must_use]
pub fn calibration_line(value: &dyn Fn(&str) -> Option<String>) -> String {
    let v = |name: &str| value(name).unwrap_or_else(|| "?".to_string());
    let number = |name: &str| value(name).and_then(|t| t.parse::<f64>().ok()).filter(|x| x.is_finite());
    let lens = match number("VisionLensFocalPx").filter(|f| *f > 0.0) {
        Some(focal) => {
            let each: Vec<String> = ["K1", "K2", "P1", "P2"]
                .iter()
                .map(|c| {
                    let shown = |n: Option<f64>| n.map_or_else(|| "?".to_string(), |x| format!("{x:.5}"));
                    let (k, sigma) = (number(&format!("VisionLens{c}")), number(&format!("VisionLens{c}Sigma")));
                    format!("{} {} ± {}", c.to_lowercase(), shown(k), shown(sigma))
                })
                .collect();
            format!(" · lens {} (f {focal:.0} px)", each.join(", "))
        }
        None => String::new(),
    };
    format!(
        "K {} {} {} {} {u}/px · tool offset X{} Y{} {u} · centre {} {} px{lens}",
        v("VisionCal_K11"),
        v("VisionCal_K12"),
        v("VisionCal_K21"),
        v("VisionCal_K22"),
        v("VisionCal_ToolOffsetX"),
        v("VisionCal_ToolOffsetY"),
        v("VisionPxCenterOffsetX"),
        v("VisionPxCenterOffsetY"),
        u = v("VisionCal_Units"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use vision_driver_camera::{CameraConfig, CameraError, Frame, Source};
    use vision_locate::render::{render, Depth, PlacedMark, Scene, Shape};
    use vision_locate::OwnedPixels;

    /// A 200×160 frame for each trigger, with a 24 px dark dot centred at pixel centre `.0`.
    struct Dot(Option<(f64, f64)>);

    impl FrameSource for Dot {
        fn frame(&mut self) -> Result<Frame, CameraError> {
            let shape = Shape::Dot { diameter: 24.0 };
            let marks = self.0.iter().map(|&(x, y)| PlacedMark { shape, x, y, reflectance: 0.1 }).collect();
            let scene = Scene { marks, blur_sigma: 0.8, ..Scene::blank(200, 160, Depth::Eight) };
            let OwnedPixels::Gray8(pixels) = render(&scene).expect("scene").into_pixels() else { unreachable!() };
            Ok(Frame::new(200, 160, pixels).expect("frame"))
        }
        fn describe(&self) -> String {
            "a drawn dot".into()
        }
    }

    fn driver(at: Option<(f64, f64)>) -> FrameDriver<Dot> {
        let config = CameraConfig::new(Source::Files("unused".into()), 24.0);
        FrameDriver::new(config, Dot(at)).expect("driver")
    }

    #[test]
    fn a_found_mark_is_in_locate_pixels_with_its_offset_through_k() {
        let mut params = Params::default();
        params.set_cal_k(vision_math::Matrix2::new(0.01, 0.0, 0.0, -0.01)).expect("K");
        let view = observe(&mut driver(Some((120.5, 60.5))), &params);
        let mark = view.mark.expect("found");
        assert!((mark.x - 120.5).abs() < 0.1 && (mark.y - 60.5).abs() < 0.1, "{mark:?}");
        let (dx, dy) = view.offset_px.expect("offset");
        assert!((dx - 21.0).abs() < 0.1 && (dy + 19.0).abs() < 0.1, "{dx} {dy}");
        let m = view.offset_machine.expect("K is set");
        assert!((m.x - 0.21).abs() < 1e-3 && (m.y - 0.19).abs() < 1e-3, "{m:?}");
        assert_eq!(view.frame.map(|f| f.width()), Some(200));
        assert!(view.why_ng.is_none());
    }

    #[test]
    fn the_offset_in_machine_units_undoes_the_profiles_lens() {
        let mut params = Params::default();
        params.set_cal_k(vision_math::Matrix2::new(0.01, 0.0, 0.0, -0.01)).expect("K");
        let lens = vision_math::Lens::new([-0.1, 0.01, 0.002, -0.001], 150.0).expect("lens");
        params.calibration = params.calibration.with_lens(Some((lens, [0.0; 4]))).expect("lens");
        let view = observe(&mut driver(Some((160.5, 40.5))), &params);
        let (mark, m) = (view.mark.expect("found"), view.offset_machine.expect("K is set"));
        let centred = vision_math::Vector2::new(mark.x + 0.5 - 100.0, mark.y + 0.5 - 80.0);
        let want = vision_math::Matrix2::new(0.01, 0.0, 0.0, -0.01) * lens.undistort(centred);
        // Within what the chain's fitted chord steps are exact to, 0.01 in/px.
        let tolerance = 0.01 * vision_math::lens::FIELD_TOLERANCE_PX;
        assert!((m.x - want.x).abs() < tolerance && (m.y - want.y).abs() < tolerance, "{m:?} vs {want}");
        assert!((m.x - 0.01 * centred.x).abs() > 0.005, "the lens moves this mark by over half a pixel");
    }

    #[test]
    fn no_mark_says_why_and_no_k_gives_no_machine_offset() {
        let view = observe(&mut driver(None), &Params::default());
        assert!(view.mark.is_none() && view.offset_machine.is_none());
        assert!(view.why_ng.expect("a reason").contains("no"), "the finder's reason");
        assert!(view.frame.is_some(), "the frame is shown even without a mark");
    }
}

#[cfg(test)]
mod history_tests {
    use super::calibration_line;

    #[test]
    fn a_calibration_reads_as_one_line_with_what_it_lacks_marked() {
        let value = |name: &str| match name {
            "VisionCal_K11" | "VisionCal_K22" => Some("0.00203".to_string()),
            "VisionCal_K12" | "VisionCal_K21" => Some("0".to_string()),
            "VisionCal_ToolOffsetX" => Some("-3.25".to_string()),
            "VisionCal_ToolOffsetY" => Some("1.75".to_string()),
            "VisionCal_Units" => Some("in".to_string()),
            "VisionPxCenterOffsetX" => Some("0.4".to_string()),
            _ => None,
        };
        assert_eq!(
            calibration_line(&value),
            "K 0.00203 0 0 0.00203 in/px · tool offset X-3.25 Y1.75 in · centre 0.4 ? px"
        );
        let lens = |name: &str| match name {
            "VisionLensFocalPx" => Some("2956.2".to_string()),
            "VisionLensK1" => Some("-0.100213".to_string()),
            "VisionLensK1Sigma" => Some("0.0012".to_string()),
            "VisionLensP2" => Some("-0.001".to_string()),
            other => value(other),
        };
        assert!(
            calibration_line(&lens).ends_with(
                "centre 0.4 ? px · lens k1 -0.10021 ± 0.00120, k2 ? ± ?, p1 ? ± ?, p2 -0.00100 ± ? (f 2956 px)"
            ),
            "{}",
            calibration_line(&lens)
        );
        // No lens (a focal length of 0): nothing added.
        let none = |name: &str| if name == "VisionLensFocalPx" { Some("0".to_string()) } else { lens(name) };
        assert!(calibration_line(&none).ends_with("centre 0.4 ? px"));
    }
}
