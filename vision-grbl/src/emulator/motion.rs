//! The planner and the stepper, in time: a queue of straight blocks run with a trapezoidal speed
//! profile, integrated in fixed time steps.
//!
//! After Grbl's `planner.c`: a block's nominal speed and acceleration are limited per axis
//! (`limit_value_by_axis_maximum`), the speed at a junction by the junction deviation `$11`
//! (`plan_buffer_line`), and a backward pass over the queue makes the last block end at rest
//! (`planner_recalculate`). The stepper is simplified to a speed integrated every
//! [`STEP_S`] of simulated time: it accelerates at the block's acceleration up to the nominal
//! speed, and brakes in time for the next junction's speed. A feed hold brakes at the current
//! block's acceleration, across blocks if it must.

use std::collections::VecDeque;

/// Simulated time per integration step (s).
pub(crate) const STEP_S: f64 = 0.001;

/// One straight move in the queue (mm, mm/s, mm/s²).
#[derive(Debug, Clone)]
pub(crate) struct Block {
    start: [f64; 3],
    unit: [f64; 3],
    length: f64,
    nominal: f64,
    accel: f64,
    /// Square of the highest speed allowed at this block's start (mm²/s²), from the junction.
    max_entry_sqr: f64,
    /// Square of the planned speed at this block's start after the backward pass (mm²/s²).
    entry_sqr: f64,
}

/// Per-axis limits that shape a block (mm/min and mm/s² as Grbl's `$110`–`$122` hold them).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Limits {
    /// `$110`–`$112` (mm/min).
    pub(crate) max_rate: [f64; 3],
    /// `$120`–`$122` (mm/s²).
    pub(crate) accel: [f64; 3],
    /// `$11` (mm).
    pub(crate) junction_deviation: f64,
}

/// The queue and the tool's motion along it.
#[derive(Debug)]
pub(crate) struct Motion {
    blocks: VecDeque<Block>,
    capacity: usize,
    /// Distance travelled into the front block (mm).
    s: f64,
    /// Current speed (mm/s).
    v: f64,
    /// Where the tool is when the queue is empty (mm, machine).
    rest: [f64; 3],
    holding: bool,
    /// Unit vector of the last queued block, for the next junction.
    last_unit: Option<[f64; 3]>,
    last_nominal: f64,
}

fn limit_by_axis(max: [f64; 3], unit: [f64; 3]) -> f64 {
    let mut limit = f64::INFINITY;
    for i in 0..3 {
        if unit[i] != 0.0 {
            limit = limit.min(max[i] / unit[i].abs());
        }
    }
    limit
}

impl Motion {
    /// An empty planner of `capacity` blocks with the tool at `position`.
    pub(crate) fn new(capacity: usize, position: [f64; 3]) -> Self {
        Self {
            blocks: VecDeque::new(),
            capacity: capacity.max(1),
            s: 0.0,
            v: 0.0,
            rest: position,
            holding: false,
            last_unit: None,
            last_nominal: 0.0,
        }
    }

    /// Free planner blocks.
    pub(crate) fn available(&self) -> usize {
        self.capacity - self.blocks.len().min(self.capacity)
    }

    /// Whether no block is queued.
    pub(crate) fn is_empty(&self) -> bool {
        self.blocks.is_empty()
    }

    /// Current speed (mm/min).
    pub(crate) fn rate_mm_per_min(&self) -> f64 {
        self.v * 60.0
    }

    /// Whether a hold has brought the tool to rest.
    pub(crate) fn hold_complete(&self) -> bool {
        self.holding && self.v == 0.0
    }

    /// Starts a feed hold (`!`, M0): the tool brakes and queued blocks wait.
    pub(crate) fn hold(&mut self) {
        self.holding = true;
    }

    /// Ends a feed hold (`~`).
    pub(crate) fn resume(&mut self) {
        self.holding = false;
    }

    /// Drops every block and stops where the tool is (a reset kills the steppers).
    pub(crate) fn kill(&mut self) {
        self.rest = self.position();
        self.blocks.clear();
        self.s = 0.0;
        self.v = 0.0;
        self.holding = false;
        self.last_unit = None;
    }

    /// Puts the tool at `position` with nothing queued (after homing).
    pub(crate) fn set_position(&mut self, position: [f64; 3]) {
        self.kill();
        self.rest = position;
    }

    /// The tool's position (mm, machine).
    pub(crate) fn position(&self) -> [f64; 3] {
        match self.blocks.front() {
            Some(b) => std::array::from_fn(|i| b.start[i] + b.unit[i] * self.s),
            None => self.rest,
        }
    }

    /// The end of the last queued block, where the next block starts (mm, machine).
    fn planned_end(&self) -> [f64; 3] {
        match self.blocks.back() {
            Some(b) => std::array::from_fn(|i| b.start[i] + b.unit[i] * b.length),
            None => self.rest,
        }
    }

    /// Queues a move to `target` at `rate` (mm/min; `None` is a rapid). Returns false when the
    /// queue is full; a move too short to step is dropped, as Grbl drops a zero-step block.
    pub(crate) fn push(&mut self, target: [f64; 3], rate: Option<f64>, limits: &Limits) -> bool {
        if self.blocks.len() >= self.capacity {
            return false;
        }
        let start = self.planned_end();
        let delta: [f64; 3] = std::array::from_fn(|i| target[i] - start[i]);
        let length = (delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2]).sqrt();
        if !(length > 1e-9) {
            return true;
        }
        let unit: [f64; 3] = std::array::from_fn(|i| delta[i] / length);
        let rapid = limit_by_axis(limits.max_rate, unit) / 60.0;
        let accel = limit_by_axis(limits.accel, unit);
        let nominal = match rate {
            Some(r) if r > 0.0 => (r / 60.0).min(rapid),
            _ => rapid,
        };
        // planner.c: the junction deviation sets the speed through the corner.
        let max_entry_sqr = match (self.last_unit, self.blocks.is_empty() && self.v == 0.0) {
            (Some(prev), false) => {
                let cos_theta = -(prev[0] * unit[0] + prev[1] * unit[1] + prev[2] * unit[2]);
                let junction = if cos_theta > 0.999_999 {
                    0.0
                } else if cos_theta < -0.999_999 {
                    f64::INFINITY
                } else {
                    let sin_half = (0.5 * (1.0 - cos_theta)).sqrt();
                    accel * limits.junction_deviation * sin_half / (1.0 - sin_half)
                };
                junction.min(nominal * nominal).min(self.last_nominal * self.last_nominal)
            }
            _ => 0.0,
        };
        self.blocks.push_back(Block { start, unit, length, nominal, accel, max_entry_sqr, entry_sqr: 0.0 });
        self.last_unit = Some(unit);
        self.last_nominal = nominal;
        self.recalculate();
        true
    }

    /// The backward pass: the last block ends at rest, every entry is reachable by braking.
    fn recalculate(&mut self) {
        let mut exit_sqr = 0.0;
        for b in self.blocks.iter_mut().rev() {
            b.entry_sqr = b.max_entry_sqr.min(exit_sqr + 2.0 * b.accel * b.length);
            exit_sqr = b.entry_sqr;
        }
    }

    /// Advances the simulation by one step of [`STEP_S`].
    pub(crate) fn step(&mut self) {
        let mut dt = STEP_S;
        while dt > 0.0 {
            let Some(front) = self.blocks.front() else {
                self.v = 0.0;
                return;
            };
            let exit_sqr = self.blocks.get(1).map_or(0.0, |b| b.entry_sqr);
            if self.holding {
                self.v = (self.v - front.accel * dt).max(0.0);
                if self.v == 0.0 {
                    return;
                }
            } else {
                let remaining = (front.length - self.s).max(0.0);
                let allowed = (exit_sqr + 2.0 * front.accel * remaining).sqrt().min(front.nominal);
                self.v = (self.v + front.accel * dt).min(allowed);
                if self.v <= 0.0 {
                    // Already at the end at rest: step onto the next block.
                    self.v = 0.0;
                }
            }
            let travel = self.v * dt;
            let remaining = front.length - self.s;
            if travel < remaining && !(self.v == 0.0 && remaining <= 1e-9) {
                self.s += travel;
                if self.v == 0.0 {
                    // Braked to rest short of the end (numerical); creep the rest.
                    self.s = (self.s + front.accel * dt * dt).min(front.length);
                }
                return;
            }
            // The block ends within this step.
            let used = if self.v > 0.0 { remaining / self.v } else { dt };
            dt -= used.min(dt);
            if let Some(done) = self.blocks.pop_front() {
                self.rest = std::array::from_fn(|i| done.start[i] + done.unit[i] * done.length);
            }
            self.s = 0.0;
            if self.blocks.is_empty() {
                self.v = 0.0;
                self.last_unit = None;
                return;
            }
        }
    }
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;

    const LIMITS: Limits = Limits { max_rate: [6000.0; 3], accel: [100.0; 3], junction_deviation: 0.01 };

    fn run_until_empty(m: &mut Motion) -> f64 {
        let mut t = 0.0;
        while !m.is_empty() && t < 100.0 {
            m.step();
            t += STEP_S;
        }
        t
    }

    #[test]
    fn a_long_move_takes_the_trapezoid_time() {
        let mut m = Motion::new(15, [0.0; 3]);
        assert!(m.push([100.0, 0.0, 0.0], Some(3000.0), &LIMITS));
        // 50 mm/s at 100 mm/s²: 0.5 s up, 0.5 s down (25 mm), 75 mm cruise (1.5 s): 2.5 s.
        let t = run_until_empty(&mut m);
        assert!((t - 2.5).abs() < 0.02, "{t}");
        assert_eq!(m.position(), [100.0, 0.0, 0.0]);
    }

    #[test]
    fn collinear_blocks_keep_their_speed_through_the_junction() {
        let mut m = Motion::new(15, [0.0; 3]);
        for i in 1..=10 {
            assert!(m.push([f64::from(i) * 10.0, 0.0, 0.0], Some(3000.0), &LIMITS));
        }
        let t = run_until_empty(&mut m);
        assert!((t - 2.5).abs() < 0.03, "{t}");
    }

    #[test]
    fn the_queue_refuses_a_block_past_capacity_and_a_hold_stops_the_tool() {
        let mut m = Motion::new(2, [0.0; 3]);
        assert!(m.push([10.0, 0.0, 0.0], Some(600.0), &LIMITS));
        assert!(m.push([20.0, 0.0, 0.0], Some(600.0), &LIMITS));
        assert!(!m.push([30.0, 0.0, 0.0], Some(600.0), &LIMITS));
        assert_eq!(m.available(), 0);
        for _ in 0..200 {
            m.step();
        }
        m.hold();
        for _ in 0..200 {
            m.step();
        }
        assert!(m.hold_complete());
        let held = m.position();
        m.step();
        assert_eq!(m.position(), held);
        m.resume();
        run_until_empty(&mut m);
        assert_eq!(m.position(), [20.0, 0.0, 0.0]);
    }
}
