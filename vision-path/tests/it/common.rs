//! Shared helpers: program builders and an independent model of the programmed path.
#![expect(unreachable_pub, reason = "helpers shared by the test modules, public to them")]

use std::f64::consts::{PI, TAU};

use vision_path::{
    ArcShape, Item, PathError, PathMode, PlanConfig, Rate, Segment, Setpoint, Setpoints, Shape, Step, Xyz,
};

/// `PROPTEST_CASES` overrides a property's default case count (for deeper local runs).
pub fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

pub const PLANES: [Xyz; 3] = [Xyz::new(0.0, 0.0, 1.0), Xyz::new(0.0, 1.0, 0.0), Xyz::new(1.0, 0.0, 0.0)];

/// Builds a continuous program segment by segment.
pub struct Program {
    pub items: Vec<Item>,
    pub pos: Xyz,
    pub line: usize,
    pub mode: PathMode,
}

impl Program {
    pub fn new(start: Xyz, mode: PathMode) -> Program {
        Program { items: Vec::new(), pos: start, line: 0, mode }
    }

    fn next_line(&mut self) -> usize {
        self.line += 1;
        self.line
    }

    pub fn line_to(&mut self, end: Xyz, rate: Rate) -> &mut Program {
        let line = self.next_line();
        self.items.push(Item::Move(Segment { line, start: self.pos, end, shape: Shape::Line, rate, mode: self.mode }));
        self.pos = end;
        self
    }

    /// An arc about `centre` in the plane with normal `PLANES[plane]`, sweeping `angle`
    /// radians (positive = counter-clockwise), rising `rise` along the normal.
    pub fn arc(&mut self, plane: usize, centre: Xyz, angle: f64, rise: f64, rate: Rate) -> &mut Program {
        self.spiral(plane, centre, angle, rise, 1.0, rate)
    }

    /// [`Program::arc`] whose end radius is `grow` times its start radius (a spiral, as
    /// rounded G-code makes them).
    pub fn spiral(&mut self, plane: usize, centre: Xyz, angle: f64, rise: f64, grow: f64, rate: Rate) -> &mut Program {
        let n = PLANES[plane];
        let axis = if angle >= 0.0 { n } else { neg(n) };
        let r = sub(self.pos, centre);
        let r_par = dot(r, n);
        let r_perp = sub(r, scale(n, r_par));
        let e2 = cross(axis, r_perp);
        let a = angle.abs();
        let rotated = scale(add(scale(r_perp, a.cos()), scale(e2, a.sin())), grow);
        let end = add(add(centre, rotated), scale(n, r_par + rise));
        let line = self.next_line();
        self.items.push(Item::Move(Segment {
            line,
            start: self.pos,
            end,
            shape: Shape::Arc(ArcShape { centre, normal: n, sweep: angle }),
            rate,
            mode: self.mode,
        }));
        self.pos = end;
        self
    }

    /// A spiral in the XY plane (G17) that leaves the current point exactly along the unit
    /// in-plane direction `u` (its radial drift included), with radius `r0` → `r1`, sweeping
    /// `angle` radians (positive = counter-clockwise).
    pub fn tangent_spiral(&mut self, u: Xyz, r0: f64, r1: f64, angle: f64, rate: Rate) -> &mut Program {
        let axis = if angle >= 0.0 { PLANES[0] } else { neg(PLANES[0]) };
        // The start tangent is t·r0 + ρ̂·k_r (t = axis × ρ̂): ρ̂ is `u` turned by β − π/2.
        let beta = ((r1 - r0) / angle.abs()).atan2(r0);
        let radial = sub(scale(u, beta.sin()), scale(cross(axis, u), beta.cos()));
        let centre = sub(self.pos, scale(radial, r0));
        self.spiral(0, centre, angle, 0.0, r1 / r0, rate)
    }

    /// A G2/G3 in the XY plane (G17) to `end` about `centre`, exactly as programmed: less
    /// than a full turn (a full circle when the ends coincide), as the interpreter sweeps it.
    pub fn g17_arc_to(&mut self, end: Xyz, centre: Xyz, clockwise: bool, rate: Rate) -> &mut Program {
        let a0 = (self.pos.y - centre.y).atan2(self.pos.x - centre.x);
        let a1 = (end.y - centre.y).atan2(end.x - centre.x);
        let mut sweep = if clockwise { a0 - a1 } else { a1 - a0 };
        if sweep <= 0.0 {
            sweep += TAU;
        }
        let sweep = if clockwise { -sweep } else { sweep };
        let line = self.next_line();
        self.items.push(Item::Move(Segment {
            line,
            start: self.pos,
            end,
            shape: Shape::Arc(ArcShape { centre, normal: Xyz::new(0.0, 0.0, 1.0), sweep }),
            rate,
            mode: self.mode,
        }));
        self.pos = end;
        self
    }

    pub fn item(&mut self, f: impl FnOnce(usize) -> Item) -> &mut Program {
        let line = self.next_line();
        self.items.push(f(line));
        self
    }
}

/// A planned program: its setpoints and its events.
pub struct Run {
    pub setpoints: Vec<Setpoint>,
    pub events: Vec<vision_path::TimedEvent>,
}

pub fn run(config: &PlanConfig, items: &[Item]) -> Run {
    collect(Setpoints::from_items(config, items.to_vec()).expect("valid config"), "the program is valid")
}

/// Every step of `steps`, setpoints and events apart; an error panics with `context` (the
/// program's text, say).
pub fn collect(steps: impl Iterator<Item = Result<Step, PathError>>, context: &str) -> Run {
    let mut run = Run { setpoints: Vec::new(), events: Vec::new() };
    for step in steps {
        match step.unwrap_or_else(|e| panic!("{e}\n{context}")) {
            Step::Setpoint(s) => run.setpoints.push(s),
            Step::Event(e) => run.events.push(e),
        }
    }
    run
}

// The test's own vector arithmetic, component by component (not the crate's `Xyz` methods).
pub fn dot(a: Xyz, b: Xyz) -> f64 {
    a.x * b.x + a.y * b.y + a.z * b.z
}
pub fn add(a: Xyz, b: Xyz) -> Xyz {
    Xyz::new(a.x + b.x, a.y + b.y, a.z + b.z)
}
pub fn sub(a: Xyz, b: Xyz) -> Xyz {
    Xyz::new(a.x - b.x, a.y - b.y, a.z - b.z)
}
pub fn scale(a: Xyz, k: f64) -> Xyz {
    Xyz::new(a.x * k, a.y * k, a.z * k)
}
pub fn neg(a: Xyz) -> Xyz {
    scale(a, -1.0)
}
pub fn cross(a: Xyz, b: Xyz) -> Xyz {
    Xyz::new(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x)
}
pub fn norm(a: Xyz) -> f64 {
    dot(a, a).sqrt()
}
pub fn unit(a: Xyz) -> Xyz {
    scale(a, 1.0 / norm(a))
}

/// The rotation axis (counter-clockwise positive), the start radius vector (in the plane) and
/// the sweep (radians, ≥ 0) of an arc segment.
fn arc_axis_sweep(seg: &Segment, arc: &ArcShape) -> (Xyz, Xyz, f64) {
    let n = unit(arc.normal);
    let axis = if arc.sweep < 0.0 { neg(n) } else { n };
    (axis, radius_vector(seg.start, arc, axis), arc.sweep.abs())
}

/// The in-plane radius vector of `p` about the arc's centre.
fn radius_vector(p: Xyz, arc: &ArcShape, axis: Xyz) -> Xyz {
    let r = sub(p, arc.centre);
    sub(r, scale(axis, dot(r, axis)))
}

/// The unit tangent of a segment at its start (`at_end = false`) or end.
pub fn tangent(seg: &Segment, at_end: bool) -> Xyz {
    match seg.shape {
        Shape::Line => unit(sub(seg.end, seg.start)),
        Shape::Arc(arc) => {
            // The radius changes linearly with the angle (a spiral when the ends differ).
            let (axis, rs, sweep) = arc_axis_sweep(seg, &arc);
            let re = radius_vector(seg.end, &arc, axis);
            let r = if at_end { re } else { rs };
            let rise = dot(sub(seg.end, seg.start), axis);
            let along = scale(cross(axis, unit(r)), norm(r) * sweep);
            let t = add(add(along, scale(unit(r), norm(re) - norm(rs))), scale(axis, rise));
            unit(t)
        }
    }
}

/// Distance from `p` to a line or a planar (non-helical) arc segment (for a spiral: from the
/// radius at `p`'s angle).
pub fn distance(p: Xyz, seg: &Segment) -> f64 {
    match seg.shape {
        Shape::Line => {
            let d = sub(seg.end, seg.start);
            let t = (dot(sub(p, seg.start), d) / dot(d, d)).clamp(0.0, 1.0);
            norm(sub(p, add(seg.start, scale(d, t))))
        }
        Shape::Arc(arc) => {
            let (axis, rs, sweep) = arc_axis_sweep(seg, &arc);
            let r1 = norm(radius_vector(seg.end, &arc, axis));
            let e1 = unit(rs);
            let e2 = cross(axis, e1);
            let h = dot(sub(p, seg.start), axis);
            let vp = radius_vector(p, &arc, axis);
            let mut phi = dot(vp, e2).atan2(dot(vp, e1));
            if phi < 0.0 {
                phi += TAU;
            }
            if phi <= sweep {
                let r = norm(rs) + (r1 - norm(rs)) * phi / sweep;
                (h * h + (norm(vp) - r).powi(2)).sqrt()
            } else {
                norm(sub(p, seg.start)).min(norm(sub(p, seg.end)))
            }
        }
    }
}

pub fn segments(items: &[Item]) -> Vec<&Segment> {
    items.iter().filter_map(|i| if let Item::Move(s) = i { Some(s) } else { None }).collect()
}

/// The largest `|Δ²p|` of consecutive setpoints (path, and per axis), machine units.
pub fn worst_second_difference(setpoints: &[Setpoint]) -> (f64, [f64; 3]) {
    let mut worst = (0.0f64, [0.0f64; 3]);
    for w in setpoints.windows(3) {
        let dd = sub(sub(w[2].position, w[1].position), sub(w[1].position, w[0].position));
        worst.0 = worst.0.max(norm(dd));
        for (w, d) in worst.1.iter_mut().zip(dd.to_array()) {
            *w = w.max(d.abs());
        }
    }
    worst
}

/// How many times the path comes to rest strictly between its start and its end: runs of
/// consecutive setpoints with zero velocity, leaving out the run it starts with and the run it
/// ends with. An event or a dwell is one run (an event next to a dwell at the same point shares
/// it), and so is every corner the planner stops at.
pub fn interior_rests(setpoints: &[Setpoint]) -> usize {
    let at_rest: Vec<bool> = setpoints.iter().map(|s| s.velocity == Xyz::ZERO).collect();
    let first = at_rest.iter().position(|r| !r).unwrap_or(at_rest.len());
    let last = at_rest.iter().rposition(|r| !r).map_or(first, |i| i + 1);
    (first..last).filter(|&i| at_rest[i] && !at_rest[i - 1]).count()
}

/// The most times `items` may come to rest inside the path (see [`interior_rests`]) if the
/// planner blends every corner its documented rules say it blends: each dwell and event is a
/// stop, and so is each corner that is G61 or `G64 P0`, a reversal, or touches an arc (a
/// biarc blend that does not fit is a stop). A G64 corner between two lines (with P > 0 or no
/// P) is always blended, so it adds nothing.
pub fn allowed_rests(items: &[Item]) -> usize {
    let mut allowed = 0;
    let mut prev: Option<&Segment> = None;
    for item in items {
        match item {
            Item::Move(s) if s.shape == Shape::Line && s.start == s.end => {} // no motion: dropped
            Item::Move(s) => {
                if prev.is_some_and(|p| !always_blended(p, s)) {
                    allowed += 1;
                }
                prev = Some(s);
            }
            Item::End { .. } => {}
            Item::Dwell { .. } | Item::Event { .. } => {
                allowed += 1;
                prev = None;
            }
        }
    }
    allowed
}

/// Whether the corner at the end of `a` into `b` passes at rate under the planner's rules: a
/// blend between two lines (governed by `a`'s mode) that is not a reversal.
fn always_blended(a: &Segment, b: &Segment) -> bool {
    let (u, w) = (tangent(a, true), tangent(b, false));
    let turn = norm(cross(u, w)).atan2(dot(u, w));
    let lines = a.shape == Shape::Line && b.shape == Shape::Line;
    let blends = matches!(a.mode, PathMode::Blend { tolerance } if tolerance != Some(0.0));
    lines && blends && turn < PI - 1e-5
}
