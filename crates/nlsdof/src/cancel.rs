//! Cooperative cancellation of long computations.
//!
//! A [`Cancel`] is a read-only view of a flag that the caller owns and may
//! set from another thread (a Ctrl-C handler, a Python binding that polls
//! for signals, a GUI's stop button). The long loops of the library — the
//! nodes of an exponent landscape, the Levenberg–Marquardt iterations, the
//! starts of a multistart search, the steps of a profile, the samples of a
//! simulation — poll it, stop early when it is set, and their entry points
//! then return a typed *interrupted* error ([`Interrupted`]) instead of a
//! result: nothing partial is ever returned.
//!
//! The library has no signal handling of its own; it only reads the flag.
//! Polling is a relaxed atomic load, so a computation that is not cancelled
//! gives bit for bit the result it gives without a flag.
//!
//! ```
//! use std::sync::atomic::{AtomicBool, Ordering};
//! use nlsdof::cancel::Cancel;
//! static STOP: AtomicBool = AtomicBool::new(false);
//! let cancel = Cancel::new(&STOP);
//! assert!(cancel.check().is_ok());
//! STOP.store(true, Ordering::Relaxed);
//! assert!(cancel.is_cancelled());
//! assert!(cancel.check().is_err());
//! assert!(Cancel::NEVER.check().is_ok());
//! ```

use std::sync::atomic::{AtomicBool, Ordering};

/// A flag the long loops poll (module docs). `Copy`, so it travels inside
/// option structs ([`crate::identification::LmOptions::cancel`]); the flag
/// is `'static` (a `static`, or one leaked and reused by the caller).
/// Options that differ only in their flag compare equal: the flag is not
/// part of what is computed.
#[derive(Clone, Copy, Default)]
pub struct Cancel(Option<&'static AtomicBool>);

impl Cancel {
    /// Never cancelled (the default).
    pub const NEVER: Cancel = Cancel(None);

    /// Cancelled once `flag` is set (`true`).
    pub fn new(flag: &'static AtomicBool) -> Self {
        Cancel(Some(flag))
    }

    /// Whether the flag is set.
    #[inline]
    pub fn is_cancelled(self) -> bool {
        match self.0 {
            Some(f) => f.load(Ordering::Relaxed),
            None => false,
        }
    }

    /// `Err(Interrupted)` once the flag is set.
    #[inline]
    pub fn check(self) -> Result<(), Interrupted> {
        if self.is_cancelled() {
            Err(Interrupted)
        } else {
            Ok(())
        }
    }
}

impl PartialEq for Cancel {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for Cancel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            None => f.write_str("Cancel::NEVER"),
            Some(_) => write!(f, "Cancel(cancelled: {})", self.is_cancelled()),
        }
    }
}

/// The computation was cancelled through its [`Cancel`] flag before it
/// finished; no result was produced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("interrupted: the computation was cancelled before it finished (no result)")]
pub struct Interrupted;
