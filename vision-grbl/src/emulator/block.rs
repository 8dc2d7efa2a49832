//! STEP 3 and 4 of Grbl's `gc_execute_line` (gcode.c): check the parsed block, then update the
//! parser state and say what motion follows; and `mc_arc` (motion_control.c).

// Axis loops index several arrays at once, as gcode.c does.
#![expect(clippy::needless_range_loop, reason = "Axis loops index several arrays at once, as gcode.c does.")]

use super::canned;
use super::gcode::{AxisCommand, GcState, NonModal, Op, Parsed, Stored, INCH, MAX_N};
use super::status as st;

/// Checks `p` against the state and runs it. `Err` is Grbl's status code; on `Err` nothing
/// changed.
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    clippy::float_cmp,
    reason = "a change of offset at all, as Grbl compares it"
)]
pub(crate) fn check_and_run(
    p: Parsed,
    gc: &mut GcState,
    stored: &mut Stored,
    arc_tolerance: f64,
) -> Result<Vec<Op>, u8> {
    let Parsed { w, motion, plane, inches, incremental, inverse_time, coord_select, non_modal, .. } = p;
    let mut axis_command = p.axis_command;
    let axis_words = w.xyz.iter().any(Option::is_some);
    let mut used_r = false;
    let mut used_ijk = false;
    let mut used_lp = false;
    if axis_words && axis_command == AxisCommand::None {
        axis_command = AxisCommand::Motion;
    }
    if w.n.is_some_and(|n| n > MAX_N) {
        return Err(st::INVALID_LINE_NUMBER);
    }
    // [2/3] Feed rate mode and feed rate.
    let unit = if inches { INCH } else { 1.0 };
    let mut feed = w.f.map(|f| f * if inverse_time { 1.0 } else { unit });
    if inverse_time {
        if axis_command == AxisCommand::Motion && motion != 80 && motion != 0 && w.f.is_none() {
            return Err(st::UNDEFINED_FEED_RATE);
        }
    } else if !gc.inverse_time && feed.is_none() {
        feed = Some(gc.feed);
    }
    let feed = feed.unwrap_or(0.0);
    // [10] Dwell.
    if non_modal == NonModal::Dwell {
        if w.p.is_none() {
            return Err(st::VALUE_WORD_MISSING);
        }
        used_lp = true;
    }
    let (a0, a1, linear) = match plane {
        0 => (0, 1, 2),
        1 => (2, 0, 1),
        _ => (1, 2, 0),
    };
    let mut xyz: [f64; 3] = std::array::from_fn(|i| w.xyz[i].map_or(0.0, |v| v * unit));
    // [14] G43.1 takes Z alone.
    if axis_command == AxisCommand::ToolLength
        && p.tool_length == Some(true)
        && !(w.xyz[2].is_some() && w.xyz[0].is_none() && w.xyz[1].is_none())
    {
        return Err(st::G43_DYNAMIC_AXIS_ERROR);
    }
    // [15] Coordinate system selection.
    let mut block_coord = gc.coord_system;
    if let Some(c) = coord_select {
        if c != gc.coord_select {
            block_coord = stored.coords[c];
        }
    }
    let new_coord_select = coord_select.unwrap_or(gc.coord_select);
    // grblHAL G51: scale the axis words about an origin.
    let mut scale = gc.scale;
    if axis_command == AxisCommand::Scaling {
        if p.scaling == Some(true) {
            let factors: [f64; 3] = match (w.p, w.ijk) {
                (Some(f), _) => [f; 3],
                (None, ijk) if ijk.iter().any(Option::is_some) => std::array::from_fn(|i| ijk[i].unwrap_or(1.0)),
                _ => return Err(st::NO_AXIS_WORDS),
            };
            scale = Some((factors, xyz));
            used_lp = true;
            used_ijk = true;
        } else {
            scale = None;
        }
        axis_command = AxisCommand::None;
    } else if let Some((factors, origin)) = scale {
        if !incremental {
            for i in 0..3 {
                if w.xyz[i].is_some() {
                    xyz[i] = origin[i] + (xyz[i] - origin[i]) * factors[i];
                }
            }
        }
    }
    let mut coord_target = 0usize;
    let mut home_target = [0.0; 3];
    // [19] Non-modal actions.
    match non_modal {
        NonModal::SetCoord => {
            if !axis_words {
                return Err(st::NO_AXIS_WORDS);
            }
            if w.p.is_none() && w.l.is_none() {
                return Err(st::VALUE_WORD_MISSING);
            }
            let sel = w.p.unwrap_or(0.0).trunc() as usize;
            if sel > 6 {
                return Err(st::UNSUPPORTED_COORD_SYS);
            }
            let l = w.l.unwrap_or(0.0);
            if l != 20.0 && (l != 2.0 || w.r.is_some()) {
                return Err(st::UNSUPPORTED_COMMAND);
            }
            used_lp = true;
            coord_target = if sel > 0 { sel - 1 } else { new_coord_select };
            let mut data = stored.coords[coord_target];
            for i in 0..3 {
                if w.xyz[i].is_some() {
                    data[i] = if l == 20.0 {
                        let mut v = gc.position[i] - gc.coord_offset[i] - xyz[i];
                        if i == 2 {
                            v -= gc.tlo;
                        }
                        v
                    } else {
                        xyz[i]
                    };
                }
            }
            home_target = data;
        }
        NonModal::Offset => {
            if !axis_words {
                return Err(st::NO_AXIS_WORDS);
            }
            for i in 0..3 {
                xyz[i] = if w.xyz[i].is_some() {
                    let mut v = gc.position[i] - block_coord[i] - xyz[i];
                    if i == 2 {
                        v -= gc.tlo;
                    }
                    v
                } else {
                    gc.coord_offset[i]
                };
            }
        }
        _ => {
            if axis_command != AxisCommand::ToolLength && axis_words {
                for i in 0..3 {
                    if w.xyz[i].is_none() {
                        xyz[i] = gc.position[i];
                    } else if non_modal != NonModal::Absolute {
                        if incremental {
                            xyz[i] += gc.position[i];
                        } else {
                            xyz[i] += block_coord[i] + gc.coord_offset[i];
                            if i == 2 {
                                xyz[i] += gc.tlo;
                            }
                        }
                    }
                }
            }
            match non_modal {
                NonModal::Home(g30) => {
                    home_target = if g30 { stored.g30 } else { stored.g28 };
                    if axis_words {
                        for i in 0..3 {
                            if w.xyz[i].is_none() {
                                home_target[i] = gc.position[i];
                            }
                        }
                    } else {
                        axis_command = AxisCommand::None;
                    }
                }
                NonModal::Absolute if !(motion == 0 || motion == 1) => return Err(st::G53_INVALID_MOTION_MODE),
                _ => {}
            }
        }
    }
    // [20] Motion modes.
    let mut arc: Option<([f64; 3], f64, bool)> = None;
    let mut cycle = None;
    if motion == 80 {
        if axis_words {
            return Err(st::AXIS_WORDS_EXIST);
        }
    } else if axis_command == AxisCommand::Motion {
        if motion == 81 || motion == 82 {
            if feed == 0.0 {
                return Err(st::UNDEFINED_FEED_RATE);
            }
            let r_word = w.r.map(|r| {
                if incremental {
                    gc.position[2] + r * unit
                } else {
                    r * unit + block_coord[2] + gc.coord_offset[2] + gc.tlo
                }
            });
            used_r = true;
            cycle = Some(canned::resolve(r_word, w.xyz[2].map(|_| xyz[2]), gc.canned)?);
            if motion == 82 && w.p.is_none() {
                return Err(st::VALUE_WORD_MISSING);
            }
            used_lp = true;
        } else if motion == 0 || motion == 1 {
            if motion == 1 && feed == 0.0 {
                return Err(st::UNDEFINED_FEED_RATE);
            }
            if !axis_words {
                axis_command = AxisCommand::None;
            }
        } else {
            if feed == 0.0 {
                return Err(st::UNDEFINED_FEED_RATE);
            }
            if !axis_words {
                return Err(st::NO_AXIS_WORDS);
            }
            if w.xyz[a0].is_none() && w.xyz[a1].is_none() {
                return Err(st::NO_AXIS_WORDS_IN_PLANE);
            }
            let mut x = xyz[a0] - gc.position[a0];
            let mut y = xyz[a1] - gc.position[a1];
            let mut ijk = [0.0; 3];
            let radius;
            if let Some(r) = w.r {
                used_r = true;
                if xyz == gc.position {
                    return Err(st::INVALID_TARGET);
                }
                let mut r = r * unit;
                let h2 = 4.0 * r * r - x * x - y * y;
                if h2 < 0.0 {
                    return Err(st::ARC_RADIUS_ERROR);
                }
                let mut h = -h2.sqrt() / x.hypot(y);
                if motion == 3 {
                    h = -h;
                }
                if r < 0.0 {
                    h = -h;
                    r = -r;
                }
                ijk[a0] = 0.5 * (x - y * h);
                ijk[a1] = 0.5 * (y + x * h);
                radius = r;
            } else {
                if w.ijk[a0].is_none() && w.ijk[a1].is_none() {
                    return Err(st::NO_OFFSETS_IN_PLANE);
                }
                used_ijk = true;
                ijk = std::array::from_fn(|i| w.ijk[i].map_or(0.0, |v| v * unit));
                x -= ijk[a0];
                y -= ijk[a1];
                let target_r = x.hypot(y);
                radius = ijk[a0].hypot(ijk[a1]);
                // gcode.c: end radius off by more than 0.005 mm and either 0.5 mm or 0.1 %.
                let delta_r = (target_r - radius).abs();
                if delta_r > 0.005 && (delta_r > 0.5 || delta_r > 0.001 * radius) {
                    return Err(st::INVALID_TARGET);
                }
            }
            arc = Some((ijk, radius, motion == 2));
        }
    }
    // [0] Unused words.
    let unused = (w.ijk.iter().any(Option::is_some) && !used_ijk)
        || (w.r.is_some() && !used_r)
        || ((w.l.is_some() || w.p.is_some()) && !used_lp)
        || (axis_words
            && axis_command == AxisCommand::None
            && !matches!(non_modal, NonModal::SetCoord | NonModal::Offset | NonModal::Home(_))
            && p.axis_command != AxisCommand::Scaling);
    if unused {
        return Err(st::UNUSED_WORDS);
    }

    // STEP 4: execute.
    let mut ops = Vec::new();
    gc.inverse_time = inverse_time;
    gc.feed = feed;
    if let Some(s) = w.s {
        gc.speed = s;
    }
    if let Some(t) = w.t {
        gc.tool = t as u8;
    }
    gc.spindle = p.spindle;
    gc.mist = p.mist;
    gc.flood = p.flood;
    if non_modal == NonModal::Dwell {
        ops.push(Op::Sync);
        ops.push(Op::Dwell(w.p.unwrap_or(0.0)));
    }
    gc.plane = plane;
    gc.inches = inches;
    if axis_command == AxisCommand::ToolLength {
        let tlo = if p.tool_length == Some(true) { xyz[2] } else { 0.0 };
        if tlo != gc.tlo {
            gc.tlo = tlo;
            ops.extend([Op::Sync, Op::WcoChanged]);
        }
    }
    if new_coord_select != gc.coord_select {
        gc.coord_select = new_coord_select;
        gc.coord_system = block_coord;
        ops.extend([Op::Sync, Op::WcoChanged]);
    }
    gc.incremental = incremental;
    if let Some(v) = p.retract_to_r {
        gc.retract_to_r = v;
    }
    gc.scale = scale;
    match non_modal {
        NonModal::SetCoord => {
            // settings.c: EEPROM writes wait for the buffer (FORCE_BUFFER_SYNC_DURING_EEPROM_WRITE).
            ops.push(Op::Sync);
            stored.coords[coord_target] = home_target;
            if coord_target == gc.coord_select {
                gc.coord_system = home_target;
                ops.push(Op::WcoChanged);
            }
        }
        NonModal::Home(_) => {
            if axis_command != AxisCommand::None {
                ops.push(Op::Line(xyz, None));
            }
            ops.push(Op::Line(home_target, None));
            gc.position = home_target;
        }
        NonModal::SetHome(g30) => {
            ops.push(Op::Sync);
            if g30 {
                stored.g30 = gc.position;
            } else {
                stored.g28 = gc.position;
            }
        }
        NonModal::Offset => {
            gc.coord_offset = xyz;
            ops.extend([Op::Sync, Op::WcoChanged]);
        }
        NonModal::ResetOffset => {
            gc.coord_offset = [0.0; 3];
            ops.extend([Op::Sync, Op::WcoChanged]);
        }
        _ => {}
    }
    gc.motion = motion;
    if motion != 80 && axis_command == AxisCommand::Motion {
        let rate = |length: f64| if inverse_time { feed * length } else { feed };
        if let Some(c) = cycle {
            let dwell = if motion == 82 { w.p } else { None };
            let retract = p.retract_to_r.unwrap_or(gc.retract_to_r);
            let (moves, end) = canned::hole(c, gc.position, (xyz[0], xyz[1]), feed, dwell, retract);
            ops.extend(moves);
            xyz = end;
            gc.canned = (Some(c.r), Some(c.z));
        }
        match (motion, arc) {
            (81 | 82, _) => {}
            (0, _) => ops.push(Op::Line(xyz, None)),
            (_, Some((ijk, radius, cw))) => {
                let arc = Arc {
                    position: gc.position,
                    target: xyz,
                    offset: ijk,
                    radius,
                    axes: (a0, a1, linear),
                    clockwise: cw,
                };
                let points = arc.points(arc_tolerance);
                let total = arc_length(gc.position, &points);
                let r = rate(total.max(1e-9));
                ops.extend(points.into_iter().map(|p| Op::Line(p, Some(r))));
            }
            _ => {
                let d: f64 = (0..3).map(|i| (xyz[i] - gc.position[i]).powi(2)).sum::<f64>().sqrt();
                let r = if inverse_time { feed * d } else { feed };
                ops.push(Op::Line(xyz, Some(r)));
            }
        }
        gc.position = xyz;
    }
    // [21] Program flow.
    if let Some(flow) = p.flow {
        ops.push(Op::Sync);
        if flow == 0 {
            ops.push(Op::Pause);
        } else {
            gc.motion = 1;
            gc.plane = 0;
            gc.incremental = false;
            gc.inverse_time = false;
            gc.coord_select = 0;
            gc.coord_system = stored.coords[0];
            gc.spindle = 5;
            gc.mist = false;
            gc.flood = false;
            ops.extend([Op::WcoChanged, Op::Message("Pgm End")]);
        }
    }
    Ok(ops)
}

fn arc_length(start: [f64; 3], points: &[[f64; 3]]) -> f64 {
    let mut prev = start;
    let mut total = 0.0;
    for p in points {
        total += (0..3).map(|i| (p[i] - prev[i]).powi(2)).sum::<f64>().sqrt();
        prev = *p;
    }
    total
}

/// An arc as `mc_arc` takes it: offset from the start to the centre, radius, plane axes.
struct Arc {
    position: [f64; 3],
    target: [f64; 3],
    offset: [f64; 3],
    radius: f64,
    axes: (usize, usize, usize),
    clockwise: bool,
}

impl Arc {
    /// The segment ends, the target last (motion_control.c, `mc_arc`).
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "a segment count, floored, non-negative and capped"
    )]
    fn points(&self, tolerance: f64) -> Vec<[f64; 3]> {
        const EPSILON: f64 = 5e-7;
        let (a0, a1, lin) = self.axes;
        let c0 = self.position[a0] + self.offset[a0];
        let c1 = self.position[a1] + self.offset[a1];
        let (r0, r1) = (-self.offset[a0], -self.offset[a1]);
        let (t0, t1) = (self.target[a0] - c0, self.target[a1] - c1);
        let mut travel = (r0 * t1 - r1 * t0).atan2(r0 * t0 + r1 * t1);
        if self.clockwise {
            if travel >= -EPSILON {
                travel -= std::f64::consts::TAU;
            }
        } else if travel <= EPSILON {
            travel += std::f64::consts::TAU;
        }
        let denom = (tolerance * (2.0 * self.radius - tolerance)).max(1e-12).sqrt();
        let segments = ((0.5 * travel * self.radius).abs() / denom).floor().min(100_000.0) as usize;
        let mut out = Vec::with_capacity(segments + 1);
        if segments > 1 {
            let theta = travel / segments as f64;
            let dl = (self.target[lin] - self.position[lin]) / segments as f64;
            let start_angle = r1.atan2(r0);
            let rad = r0.hypot(r1);
            for k in 1..segments {
                let a = start_angle + theta * k as f64;
                let mut p = self.position;
                p[a0] = c0 + rad * a.cos();
                p[a1] = c1 + rad * a.sin();
                p[lin] = self.position[lin] + dl * k as f64;
                out.push(p);
            }
        }
        out.push(self.target);
        out
    }
}
