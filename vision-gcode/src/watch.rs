//! [`PositionWatch`]: a read-only, shared view of an interpreter's machine position.
//!
//! Something outside a running program sometimes needs to know where the machine is — a
//! simulated camera fired from inside an M-code handler, while the interpreter is borrowed.
//! Rather than mirror the position from the motion events (a second copy that can drift: a
//! host's `set_machine_position` emits no event), the interpreter itself publishes its position
//! into a shared cell at the one place its state is committed. It is the only writer; a watch
//! can only read. Nothing is published until a watch is asked for, so a plain interpreter pays
//! one branch per line.

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use crate::geom::Xyz;

/// The machine (spindle) position of one interpreter, machine units, as of its last committed
/// line or host operation. Clones read the same cell.
#[derive(Debug, Clone)]
pub struct PositionWatch {
    cell: Arc<Mutex<Xyz>>,
}

impl PositionWatch {
    /// The machine position now, machine units.
    #[must_use]
    pub fn get(&self) -> Xyz {
        *lock(&self.cell)
    }
}

/// The interpreter's end: it publishes to the watch, if one was asked for. A clone of the
/// interpreter is an independent machine ("where would this move go?"), so it publishes
/// nothing: cloning the publisher detaches it.
#[derive(Debug, Default)]
pub(crate) struct Publisher(Option<Arc<Mutex<Xyz>>>);

impl Clone for Publisher {
    fn clone(&self) -> Publisher {
        Publisher(None)
    }
}

impl Publisher {
    /// Publishes `machine` to the watch, if there is one.
    pub(crate) fn publish(&self, machine: Xyz) {
        if let Some(cell) = &self.0 {
            *lock(cell) = machine;
        }
    }

    /// The watch (created on first use), holding `machine`.
    pub(crate) fn watch(&mut self, machine: Xyz) -> PositionWatch {
        let cell = self.0.get_or_insert_with(|| Arc::new(Mutex::new(machine)));
        *lock(cell) = machine;
        PositionWatch { cell: Arc::clone(cell) }
    }
}

/// Every write is one assignment, so a poisoned cell still holds a whole position.
fn lock(cell: &Mutex<Xyz>) -> MutexGuard<'_, Xyz> {
    cell.lock().unwrap_or_else(PoisonError::into_inner)
}
