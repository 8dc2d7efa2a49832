//! Helpers shared by the integration tests.

use vision_gcode::{Event, Rate};

/// The straight moves of `events`: (rapid?, end) in machine coordinates.
#[must_use]
pub(crate) fn moves(events: &[Event]) -> Vec<(bool, [f64; 3])> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Linear(m) => Some((m.rate == Rate::Rapid, m.end.to_array())),
            _ => None,
        })
        .collect()
}
