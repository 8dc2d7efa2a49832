//! Look-ahead velocity planning over a bounded window of pieces.
//!
//! Between two stops the path is a run of tangent-continuous pieces. Each junction has a
//! speed cap (the smaller of its neighbours' caps). The planner must always be able to stop
//! at the end of what it has read, so it plans backwards from a stop at the window's end:
//! `b_k = min(cap_k, √(b_{k+1}² + 2·a_k·L_k))`, and forwards from the known entry speed:
//! `v_{k+1} = min(b_{k+1}, √(v_k² + 2·a_k·L_k))`.
//!
//! How far ahead is enough: a piece's backward speed no longer depends on the (assumed)
//! stop at the window's end once the window beyond it is long enough to brake from the
//! highest cap (`Σ 2·a·L ≥ cap²`). The planner computes the backward pass twice — with a
//! stop at the window's end and with an unbounded end — and releases exactly the pieces
//! where both agree. It reads until the window beyond its first piece could brake from twice
//! the highest cap (so about half the window is released per pass: amortised O(1) per piece),
//! until a real stop, or until the window holds `lookahead` pieces; a full window releases
//! its first half on the stop-at-the-end plan, which is always feasible (only slower).

use std::collections::VecDeque;

use crate::input::Item;
use crate::shaper::{Marker, Piece, Shaped, Shaper};
use crate::PathError;

/// A piece with its planned entry and exit speeds, or a stop.
#[expect(clippy::large_enum_variant, reason = "Pieces are the common case; boxing them would allocate once per piece.")]
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Ready {
    Piece { piece: Piece, v0: f64, v1: f64 },
    Stop(Marker),
}

struct Slot {
    piece: Piece,
    /// Cap at the junction where the piece starts, units/s.
    entry_cap: f64,
    /// Backward-planned entry speed, units/s.
    b: f64,
}

pub(crate) struct Lookahead<I> {
    shaper: Shaper<I>,
    window: VecDeque<Slot>,
    closing: Option<Marker>,
    ready: VecDeque<Ready>,
    /// Planned speed at the start of the window's first piece.
    entry: f64,
    capacity: usize,
    input_done: bool,
}

impl<I: Iterator<Item = Result<Item, PathError>>> Lookahead<I> {
    pub(crate) fn new(shaper: Shaper<I>, capacity: usize) -> Lookahead<I> {
        Lookahead {
            shaper,
            window: VecDeque::new(),
            closing: None,
            ready: VecDeque::new(),
            entry: 0.0,
            capacity,
            input_done: false,
        }
    }

    /// The next piece (with final entry and exit speeds) or stop.
    // Its one caller is the sampler's `next`; left to itself LLVM stopped inlining it there
    // once the 3-vector came from vision-gcode, which cost 1 % of the instructions (and a copy
    // of every piece) on a dense G64 spiral.
    #[inline]
    pub(crate) fn next(&mut self) -> Option<Ready> {
        loop {
            if let Some(r) = self.ready.pop_front() {
                return Some(r);
            }
            if self.window.is_empty() && self.closing.is_none() && self.input_done {
                return None;
            }
            self.fill();
            self.release();
        }
    }

    fn fill(&mut self) {
        let (mut reach, mut cap2) = self.window_reach();
        while self.closing.is_none() && !self.input_done && self.window.len() < self.capacity {
            if self.window.len() >= 2 && reach >= 2.0 * cap2 {
                break;
            }
            match self.shaper.next() {
                Some(Shaped::Piece(piece)) => {
                    // The window empties only at a stop (otherwise at least one piece stays
                    // after a release): its last piece is the one before this, if any since
                    // the stop.
                    let entry_cap = self.window.back().map_or(0.0, |prev| prev.piece.v_cap.min(piece.v_cap));
                    if !self.window.is_empty() {
                        reach += 2.0 * piece.accel * piece.curve.len();
                    }
                    cap2 = cap2.max(piece.v_cap * piece.v_cap);
                    self.window.push_back(Slot { piece, entry_cap, b: 0.0 });
                }
                Some(Shaped::Stop(marker)) => self.closing = Some(marker),
                None => self.input_done = true,
            }
        }
    }

    /// `Σ 2·a·L` over the window after its first piece, and the largest cap², over the window.
    fn window_reach(&self) -> (f64, f64) {
        let reach = self.window.iter().skip(1).map(|s| 2.0 * s.piece.accel * s.piece.curve.len()).sum();
        let cap2 = self.window.iter().map(|s| s.piece.v_cap * s.piece.v_cap).fold(0.0, f64::max);
        (reach, cap2)
    }

    #[expect(clippy::float_cmp, reason = "settled when the pass leaves the value exactly unchanged")]
    fn release(&mut self) {
        let closed = self.closing.is_some() || self.input_done;
        // Backward pass: `b` assumes a stop at the window's end, `free` an unbounded end.
        let (mut b, mut free) = (0.0f64, f64::INFINITY);
        let mut settled = None;
        for k in (0..self.window.len()).rev() {
            let slot = &mut self.window[k];
            let reach = 2.0 * slot.piece.accel * slot.piece.curve.len();
            b = slot.entry_cap.min((b * b + reach).sqrt());
            free = slot.entry_cap.min((free * free + reach).sqrt());
            slot.b = b;
            if settled.is_none() && k >= 1 && b == free {
                settled = Some(k);
            }
        }
        let count = if closed {
            self.window.len()
        } else if let Some(k) = settled {
            k
        } else if self.window.len() >= self.capacity {
            self.window.len() / 2
        } else {
            1
        }
        .min(self.window.len());
        for _ in 0..count {
            let Some(slot) = self.window.pop_front() else { break };
            let v0 = self.entry;
            let exit_cap = self.window.front().map_or(0.0, |next| next.b);
            let v1 = exit_cap.min((v0 * v0 + 2.0 * slot.piece.accel * slot.piece.curve.len()).sqrt());
            self.entry = v1;
            self.ready.push_back(Ready::Piece { piece: slot.piece, v0, v1 });
        }
        if closed && self.window.is_empty() {
            if let Some(marker) = self.closing.take() {
                self.ready.push_back(Ready::Stop(marker));
            }
            self.entry = 0.0;
        }
    }
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;
    use vision_gcode::{PathMode, Rate};

    use crate::input::{Segment, Shape};
    use crate::limits::Limits;
    use vision_gcode::Xyz;

    fn straight_line_in_pieces(n: usize, step: f64, feed: f64) -> Vec<Result<Item, PathError>> {
        (0..n)
            .map(|i| {
                Ok(Item::Move(Segment {
                    line: i + 1,
                    start: [i as f64 * step, 0.0, 0.0].into(),
                    end: [(i + 1) as f64 * step, 0.0, 0.0].into(),
                    shape: Shape::Line,
                    rate: Rate::Feed(feed),
                    mode: PathMode::ExactStop,
                }))
            })
            .collect()
    }

    fn plan_all(items: Vec<Result<Item, PathError>>, capacity: usize) -> Vec<Ready> {
        let shaper = Shaper::new(items.into_iter(), Limits::uniform(1000.0, 500.0, 1000.0), Xyz::ZERO);
        let mut la = Lookahead::new(shaper, capacity);
        std::iter::from_fn(|| la.next()).collect()
    }

    fn speeds(ready: &[Ready]) -> Vec<(f64, f64)> {
        ready.iter().filter_map(|r| if let Ready::Piece { v0, v1, .. } = r { Some((*v0, *v1)) } else { None }).collect()
    }

    #[test]
    fn collinear_pieces_cruise_through_and_stop_only_at_the_end() {
        // 100 pieces of 1 unit at F6000 (100 units/s); braking from 100 at 1000 takes 5 units.
        let ready = plan_all(straight_line_in_pieces(100, 1.0, 6000.0), 8192);
        let v = speeds(&ready);
        assert_eq!(v.len(), 100);
        assert_eq!(v[0].0, 0.0);
        assert_eq!(v[99].1, 0.0);
        assert!(v[50].0 == 100.0 && v[50].1 == 100.0, "{:?}", v[50]);
        for w in v.windows(2) {
            assert_eq!(w[0].1, w[1].0, "speeds must join");
        }
        for (a, b) in &v {
            assert!((b * b - a * a).abs() <= 2.0 * 1000.0 * 1.0 + 1e-9);
        }
        assert!(matches!(ready.last(), Some(Ready::Stop(Marker::End { .. }))));
    }

    #[test]
    fn a_small_window_only_slows_the_path_never_breaks_it() {
        let full = speeds(&plan_all(straight_line_in_pieces(200, 0.05, 6000.0), 8192));
        let small = speeds(&plan_all(straight_line_in_pieces(200, 0.05, 6000.0), 8));
        assert_eq!(full.len(), small.len());
        for ((a0, a1), (b0, b1)) in full.iter().zip(&small) {
            assert!(b0 <= a0 && b1 <= a1);
            assert!((b1 * b1 - b0 * b0).abs() <= 2.0 * 1000.0 * 0.05 + 1e-9);
        }
        assert_eq!(small.last().map(|v| v.1), Some(0.0));
    }

    #[test]
    fn memory_stays_bounded_on_a_long_program() {
        let items = (0..200_000usize).map(|i| {
            Ok(Item::Move(Segment {
                line: i + 1,
                start: [i as f64 * 0.01, 0.0, 0.0].into(),
                end: [(i + 1) as f64 * 0.01, 0.0, 0.0].into(),
                shape: Shape::Line,
                rate: Rate::Feed(6000.0),
                mode: PathMode::ExactStop,
            }))
        });
        let shaper = Shaper::new(items, Limits::uniform(1000.0, 500.0, 1000.0), Xyz::ZERO);
        let mut la = Lookahead::new(shaper, 64);
        let mut peak = 0;
        let mut n = 0;
        while let Some(r) = la.next() {
            peak = peak.max(la.window.len() + la.ready.len());
            n += usize::from(matches!(r, Ready::Piece { .. }));
        }
        assert_eq!(n, 200_000);
        assert!(peak <= 128, "window + ready peaked at {peak}");
    }
}
