//! A run's timing: the cycle time planned as the program streams, and the alignment time.

use vision_path::{Limits, PlanConfig, Setpoints};

use super::report::Step;
use super::Runner;

/// Setpoint period of the cycle-time planning, seconds.
const CYCLE_PERIOD_S: f64 = 0.001;

impl Runner {
    /// The planner's set-up for the world's machine: a 1 ms period within `machine.max_speed` /
    /// `max_accel`, from `start` (machine units).
    pub(super) fn plan_config(&self, start: vision_path::Xyz) -> PlanConfig {
        let world = self.sim.world();
        let (speed, accel) = world.machine.motion_limits(world.unit);
        PlanConfig::new(Limits::uniform(accel, speed, accel), CYCLE_PERIOD_S, start)
    }
}

/// The most planner items `run` keeps per program for the alignment time (about 16 MB); the
/// items past them are planned as they stream, not kept.
const MAX_KEPT_ITEMS: usize = 100_000;

/// The first [`MAX_KEPT_ITEMS`] items of a program, and the lowest line of those not kept.
#[derive(Default)]
pub(super) struct KeptItems {
    items: Vec<vision_path::Item>,
    /// The lowest source line among the items not kept, if any was not.
    lowest_dropped: Option<usize>,
}

impl KeptItems {
    pub(super) fn push(&mut self, item: &vision_path::Item) {
        if self.items.len() < MAX_KEPT_ITEMS {
            self.items.push(item.clone());
        } else {
            let line = item.line();
            self.lowest_dropped = Some(self.lowest_dropped.map_or(line, |l| l.min(line)));
        }
    }

    /// Every item of the lines up to `last`, or `None` when some of them were not kept.
    fn through(&self, last: usize) -> Option<Vec<vision_path::Item>> {
        if self.lowest_dropped.is_some_and(|l| l <= last) {
            return None;
        }
        Some(self.items.iter().filter(|i| i.line() <= last).cloned().collect())
    }
}

/// The time from the last M280 that an M282 follows to that M282 (the motion, settles and
/// re-centring of the alignment), seconds: the plan up to the M282's line minus the plan before
/// the M280's. `Ok(None)` without such a pair or when the motion cannot be planned; `Err` with
/// the reason when the items before the M282 were too many to keep.
pub(super) fn alignment_time(config: &PlanConfig, kept: &KeptItems, steps: &[Step]) -> Result<Option<f64>, String> {
    // The last M280 that an M282 follows, and that M282.
    let mut begin = None;
    let mut pair = None;
    for step in steps {
        match step {
            Step::Begin { line, .. } => begin = Some(*line),
            Step::Fit { line, .. } => {
                if let Some(b) = begin.take() {
                    pair = Some((b, *line));
                }
            }
            _ => {}
        }
    }
    let Some((begin, fit)) = pair else { return Ok(None) };
    let until = |last: u32| -> Result<Option<f64>, String> {
        let prefix = kept.through(last as usize).ok_or_else(|| {
            format!("not computed: the program made more than {MAX_KEPT_ITEMS} moves and other motion items, some before line {fit}'s M282")
        })?;
        Ok(plan_time(config, prefix).ok())
    };
    let (Some(to_fit), Some(before)) = (until(fit)?, until(begin.saturating_sub(1))?) else { return Ok(None) };
    Ok(Some(to_fit - before))
}

/// The time the motion (moves, dwells, calibration settles) of `items` takes, seconds.
fn plan_time(config: &PlanConfig, items: impl IntoIterator<Item = vision_path::Item>) -> Result<f64, String> {
    let stream = Setpoints::from_items(config, items).map_err(|e| e.to_string())?;
    stream.run_to_end().map(|s| s.cycle_time).map_err(|e| e.to_string())
}

/// Items sent to the planner together (one channel message).
const PLAN_BATCH: usize = 1024;

/// The cycle-time planner running beside the interpreter: the interpreter pushes events and the
/// planner pulls items, so the two meet at a bounded channel, the planner on a thread of its
/// own (a few batches in flight, never the whole program).
pub(super) struct StreamedPlan {
    batch: Vec<vision_path::Item>,
    sender: Option<std::sync::mpsc::SyncSender<Vec<vision_path::Item>>>,
    /// The planner's thread, or why it could not start.
    thread: Result<std::thread::JoinHandle<Result<f64, String>>, String>,
}

impl StreamedPlan {
    pub(super) fn start(config: PlanConfig) -> StreamedPlan {
        let (sender, receiver) = std::sync::mpsc::sync_channel::<Vec<vision_path::Item>>(4);
        let thread = std::thread::Builder::new()
            .name("cycle-time planner".into())
            .spawn(move || plan_time(&config, receiver.into_iter().flatten()))
            .map_err(|e| format!("the path planner could not start: {e}"));
        let sender = thread.is_ok().then_some(sender);
        StreamedPlan { batch: Vec::with_capacity(PLAN_BATCH), sender, thread }
    }

    pub(super) fn push(&mut self, item: vision_path::Item) {
        self.batch.push(item);
        if self.batch.len() >= PLAN_BATCH {
            self.send();
        }
    }

    fn send(&mut self) {
        let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(PLAN_BATCH));
        // A planner that stopped early (a path it cannot plan) has its answer: the rest is not
        // needed.
        if let Some(sender) = &self.sender {
            if sender.send(batch).is_err() {
                self.sender = None;
            }
        }
    }

    /// The cycle time of everything pushed, seconds, or why there is none.
    pub(super) fn finish(mut self) -> Result<f64, String> {
        self.send();
        self.sender = None;
        self.thread?.join().unwrap_or_else(|_| Err("the path planner stopped unexpectedly".to_string()))
    }
}

#[cfg(test)]
mod tests {
    use vision_path::{Item, PathMode, Rate, Segment, Shape, Xyz};

    use super::*;

    /// A tiny feed move at `line`, from x0 to x1 (inches).
    fn step(line: usize, x0: f64, x1: f64) -> Item {
        Item::Move(Segment {
            line,
            start: Xyz::new(x0, 0.0, 0.0),
            end: Xyz::new(x1, 0.0, 0.0),
            shape: Shape::Line,
            rate: Rate::Feed(60.0),
            mode: PathMode::ExactStop,
        })
    }

    #[test]
    fn kept_items_stop_at_the_bound_and_know_which_lines_are_whole() {
        let mut kept = KeptItems::default();
        // Line 1 first, then lines 2.. past the bound, then line 3 again (a loop).
        kept.push(&step(1, 0.0, 0.001));
        for i in 0..MAX_KEPT_ITEMS + 10 {
            let line = 2 + i / 1000;
            kept.push(&step(line, 0.0, 0.0));
        }
        kept.push(&step(3, 0.0, 0.0));
        assert_eq!(kept.items.len(), MAX_KEPT_ITEMS, "no more than the bound is held");
        let last_kept_line = kept.items.last().map(Item::line).expect("items");
        assert_eq!(kept.lowest_dropped, Some(3), "the loop's line 3 was dropped");
        assert_eq!(kept.through(2).map(|v| v.len()), Some(1001));
        assert!(kept.through(3).is_none());
        assert!(kept.through(last_kept_line).is_none());
    }

    #[test]
    fn the_streamed_plan_agrees_with_planning_the_items_whole() {
        let config = PlanConfig::new(Limits::uniform(10.0, 5.0, 10.0), CYCLE_PERIOD_S, Xyz::ZERO);
        // Over two batches, to and fro.
        let items: Vec<Item> = (0..PLAN_BATCH + 7)
            .map(|i| if i % 2 == 0 { step(i + 1, 0.0, 0.01) } else { step(i + 1, 0.01, 0.0) })
            .collect();
        let mut streamed = StreamedPlan::start(config);
        for item in &items {
            streamed.push(item.clone());
        }
        let whole = plan_time(&config, items).expect("plans");
        assert_eq!(streamed.finish(), Ok(whole));
        assert!(whole > 0.0);
    }
}
