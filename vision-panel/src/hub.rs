//! [`PanelHandle`]: where a camera loop or a run hands its views to the page. Publishing takes a
//! lock held only to swap a pointer (never during a client's I/O), so a stalled browser never
//! holds up the caller.

use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, MutexGuard, OnceLock};
use std::time::Duration;

use vision_driver_camera::server::{encode, Encoding};

use crate::View;

/// How many of the last views are kept, so the frame the page asked for by number is still
/// there when its request arrives.
pub(crate) const KEEP: usize = 4;

/// A published view, numbered, with its PNG encoded once, on the first request for it.
#[derive(Debug)]
pub(crate) struct Entry {
    pub(crate) seq: u64,
    pub(crate) view: View,
    png: OnceLock<Option<Arc<Vec<u8>>>>,
}

impl Entry {
    /// The frame as PNG; `None` without a frame or when it cannot be encoded.
    pub(crate) fn png(&self) -> Option<Arc<Vec<u8>>> {
        self.png
            .get_or_init(|| {
                let frame = self.view.frame.as_ref()?;
                encode(frame, Encoding::Png).ok().map(|(bytes, _)| Arc::new(bytes))
            })
            .clone()
    }
}

#[derive(Debug, Default)]
struct Latest {
    seq: u64,
    kept: VecDeque<Arc<Entry>>,
    closed: bool,
}

#[derive(Debug, Default)]
struct Hub {
    latest: Mutex<Latest>,
    changed: Condvar,
}

/// A handle on a panel's views: cheap to clone and to send to another thread.
#[derive(Debug, Clone, Default)]
pub struct PanelHandle {
    hub: Arc<Hub>,
}

impl PanelHandle {
    /// Shows `view` on every page from now on; returns its number. Never waits on a client.
    pub fn publish(&self, view: View) -> u64 {
        let mut latest = self.lock();
        latest.seq += 1;
        let entry = Arc::new(Entry { seq: latest.seq, view, png: OnceLock::new() });
        latest.kept.push_back(entry);
        while latest.kept.len() > KEEP {
            latest.kept.pop_front();
        }
        let seq = latest.seq;
        drop(latest);
        self.hub.changed.notify_all();
        seq
    }

    /// The number of the last view published (0 before any).
    #[must_use]
    pub fn seq(&self) -> u64 {
        self.lock().seq
    }

    fn lock(&self) -> MutexGuard<'_, Latest> {
        // Every write is a whole-value update: a poisoned lock still holds a consistent state.
        self.hub.latest.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// The last view.
    pub(crate) fn latest(&self) -> Option<Arc<Entry>> {
        self.lock().kept.back().cloned()
    }

    /// View `seq`, while it is kept.
    pub(crate) fn get(&self, seq: u64) -> Option<Arc<Entry>> {
        self.lock().kept.iter().find(|e| e.seq == seq).cloned()
    }

    /// The last view once it is newer than `seq`, waiting up to `wait`; `None` when none came
    /// or the panel closed.
    pub(crate) fn after(&self, seq: u64, wait: Duration) -> Option<Arc<Entry>> {
        let latest = self.lock();
        let (latest, _) = self
            .hub
            .changed
            .wait_timeout_while(latest, wait, |l| l.seq <= seq && !l.closed)
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if latest.closed {
            return None;
        }
        latest.kept.back().filter(|e| e.seq > seq).cloned()
    }

    /// Whether the panel has closed.
    pub(crate) fn closed(&self) -> bool {
        self.lock().closed
    }

    /// Wakes every event stream to end it.
    pub(crate) fn close(&self) {
        self.lock().closed = true;
        self.hub.changed.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_views_are_kept_by_number_and_a_waiter_gets_the_newest() {
        let handle = PanelHandle::default();
        assert!(handle.latest().is_none());
        for _ in 0..KEEP + 2 {
            handle.publish(View::default());
        }
        assert_eq!(handle.seq(), 6);
        assert!(handle.get(2).is_none(), "dropped");
        assert_eq!(handle.get(3).map(|e| e.seq), Some(3));
        assert_eq!(handle.after(5, Duration::ZERO).map(|e| e.seq), Some(6));
        assert!(handle.after(6, Duration::from_millis(10)).is_none());
        let other = handle.clone();
        let waiter = std::thread::spawn(move || other.after(6, Duration::from_secs(10)).map(|e| e.seq));
        std::thread::sleep(Duration::from_millis(20));
        handle.publish(View::default());
        assert_eq!(waiter.join().expect("joined"), Some(7));
        handle.close();
        assert!(handle.after(0, Duration::from_secs(10)).is_none(), "closed: no wait");
    }
}
