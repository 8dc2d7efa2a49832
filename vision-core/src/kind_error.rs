//! One shape for a failure the core reacts to by its kind while keeping the other side's own
//! error whole: a camera driver's ([`DriverError`](crate::DriverError)) and a host machine's
//! ([`MachineError`](crate::MachineError)).

use std::error::Error;
use std::fmt;
use std::sync::Arc;

/// The common kinds of one side's failures ([`crate::DriverErrorKind`],
/// [`crate::MachineErrorKind`]).
pub trait Kind: Copy + Eq + fmt::Debug + 'static {
    /// The error's name in `Debug` output (`DriverError`).
    const NAME: &'static str;
    /// What `Display` writes before the cause (`machine: `); empty: the cause's words as they are.
    const PREFIX: &'static str;
}

/// A failure of kind `K` and its cause, kept whole: the driver's or host's own typed error.
///
/// Like [`std::io::Error`], the wrapper is transparent: [`Error::source`] is the cause's own
/// source, so a report that walks the chain does not print its text twice. The cause is shared
/// ([`Arc`]) so errors stay `Clone`; two errors are equal when their kinds and texts are, which
/// is what a caller or a test can observe.
#[derive(Clone)]
pub struct KindError<K> {
    kind: K,
    source: Arc<dyn Error + Send + Sync>,
}

impl<K: Kind> KindError<K> {
    /// An error of `kind` caused by `source`: the other side's typed error, or a message
    /// (`&str`/`String`) for one without.
    pub fn new(kind: K, source: impl Into<Box<dyn Error + Send + Sync>>) -> Self {
        KindError { kind, source: Arc::from(source.into()) }
    }

    /// The same error as a `kind` (a bridge that knows better what a failed call meant).
    #[must_use]
    pub fn with_kind(self, kind: K) -> Self {
        KindError { kind, ..self }
    }

    /// The common kind.
    #[must_use]
    pub fn kind(&self) -> K {
        self.kind
    }

    /// The cause: the other side's own error.
    #[must_use]
    pub fn get_ref(&self) -> &(dyn Error + Send + Sync + 'static) {
        &*self.source
    }

    /// The cause as `E`, when it is one.
    #[must_use]
    pub fn downcast_ref<E: Error + 'static>(&self) -> Option<&E> {
        self.source.downcast_ref::<E>()
    }
}

impl<K: Kind> fmt::Debug for KindError<K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct(K::NAME).field("kind", &self.kind).field("source", &self.source).finish()
    }
}

impl<K: Kind> fmt::Display for KindError<K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if K::PREFIX.is_empty() {
            fmt::Display::fmt(&self.source, f)
        } else {
            write!(f, "{}{}", K::PREFIX, self.source)
        }
    }
}

impl<K: Kind> PartialEq for KindError<K> {
    fn eq(&self, other: &Self) -> bool {
        self.kind == other.kind && self.to_string() == other.to_string()
    }
}

impl<K: Kind> Eq for KindError<K> {}

impl<K: Kind> Error for KindError<K> {
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        self.source.source()
    }
}

#[cfg(test)]
mod tests {
    use crate::{DriverError, DriverErrorKind, MachineError, MachineErrorKind};

    #[test]
    fn each_side_keeps_its_name_and_its_words() {
        let driver = DriverError::new(DriverErrorKind::Timeout, "no answer");
        let machine = MachineError::new(MachineErrorKind::Stopped, "feed hold");
        assert_eq!((driver.to_string(), machine.to_string()), ("no answer".into(), "machine: feed hold".into()));
        assert_eq!(format!("{driver:?}"), "DriverError { kind: Timeout, source: \"no answer\" }");
        assert_eq!(format!("{machine:?}"), "MachineError { kind: Stopped, source: \"feed hold\" }");
        assert_eq!(format!("{driver:>12}"), "   no answer", "the cause's own formatting, flags and all");
        let e = machine.clone().with_kind(MachineErrorKind::Communication);
        assert_eq!(e.kind(), MachineErrorKind::Communication);
        assert_ne!(e, machine, "the kind is part of what is compared");
        assert_eq!(e, MachineError::new(MachineErrorKind::Communication, "feed hold"));
        assert_eq!(e.get_ref().to_string(), "feed hold");
    }
}
