//! Long calls that Ctrl-C can stop and a progress bar can follow.
//!
//! [`run`] runs the work on a worker thread with the GIL released and
//! keeps the calling thread in a loop that wakes at least every
//! [`POLL`]: it runs Python's signal handlers (`py.check_signals()`, so
//! Ctrl-C raises `KeyboardInterrupt`) and hands the progress the worker
//! reported to the `progress=` argument (a callable, or a tqdm bar for
//! `progress=True`). A `KeyboardInterrupt`, or any exception the progress
//! callable raises, sets the work's [`Cancel`] flag: the library's long
//! loops poll it and stop within one model evaluation, and the call raises
//! that exception. Nothing partial is returned. A call that is not
//! interrupted computes exactly what it computes without this layer.

use nlsdof::cancel::Cancel;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;

/// How often the calling thread looks for signals and progress.
pub const POLL: Duration = Duration::from_millis(20);

/// Stack of the worker thread (that of a main thread: the library was
/// written for it).
const WORKER_STACK: usize = 16 << 20;

/// Cancellation flags: leaked once and reused, one per call running at the
/// same time (the library's [`Cancel`] holds a `'static` flag).
static POOL: Mutex<Vec<&'static AtomicBool>> = Mutex::new(Vec::new());

/// A flag of the pool, returned (cleared) when dropped.
struct Flag(&'static AtomicBool);

impl Flag {
    fn take() -> Self {
        let pooled = POOL.lock().ok().and_then(|mut p| p.pop());
        Flag(pooled.unwrap_or_else(|| Box::leak(Box::new(AtomicBool::new(false)))))
    }
}

impl Drop for Flag {
    fn drop(&mut self) {
        self.0.store(false, Ordering::Relaxed);
        if let Ok(mut p) = POOL.lock() {
            p.push(self.0);
        }
    }
}

/// One progress report: the stage, steps done, steps in the stage.
#[derive(Debug, Clone, PartialEq)]
struct Event {
    stage: String,
    done: usize,
    total: usize,
}

#[derive(Default)]
struct Events {
    /// Stages that ended since the last drain (their last count).
    finished: Vec<Event>,
    current: Option<Event>,
    /// `current` changed since the last drain.
    dirty: bool,
}

/// What the worker reports (from any thread): stages and their steps.
#[derive(Default)]
pub struct Reporter {
    events: Mutex<Events>,
}

impl Reporter {
    /// A stage of `total` steps begins.
    pub fn stage(&self, name: &str, total: usize) {
        if let Ok(mut e) = self.events.lock() {
            if let Some(c) = e.current.take() {
                e.finished.push(c);
            }
            e.current = Some(Event {
                stage: name.to_string(),
                done: 0,
                total,
            });
            e.dirty = true;
        }
    }

    /// One more step of the current stage is done.
    pub fn step(&self) {
        if let Ok(mut e) = self.events.lock() {
            if let Some(c) = e.current.as_mut() {
                c.done += 1;
                e.dirty = true;
            }
        }
    }

    /// `done` of `total` steps of the current stage are done.
    pub fn at(&self, done: usize, total: usize) {
        if let Ok(mut e) = self.events.lock() {
            if let Some(c) = e.current.as_mut() {
                c.done = done;
                c.total = total;
                e.dirty = true;
            }
        }
    }

    /// The identification's progress ([`nlsdof::identification::identify`]).
    pub fn identify(&self, p: nlsdof::identification::IdentifyProgress) {
        use nlsdof::identification::IdentifyProgress;
        match p {
            IdentifyProgress::Stage { name, steps } => self.stage(name, steps),
            IdentifyProgress::Step => self.step(),
        }
    }

    fn drain(&self) -> Vec<Event> {
        let Ok(mut e) = self.events.lock() else {
            return Vec::new();
        };
        let mut out = std::mem::take(&mut e.finished);
        if e.dirty {
            out.extend(e.current.clone());
            e.dirty = false;
        }
        out
    }
}

/// Where progress goes: nowhere, a callable, a tqdm bar, or plain lines on
/// `sys.stderr` (`progress=True` without tqdm).
enum Sink<'py> {
    Off,
    Call(Bound<'py, PyAny>),
    Tqdm {
        class: Bound<'py, PyAny>,
        what: String,
        bar: Option<(String, Bound<'py, PyAny>)>,
    },
    Text {
        what: String,
        last: Option<String>,
    },
}

impl<'py> Sink<'py> {
    /// `progress=`: None/False (off), True (a tqdm bar, `tqdm.auto`; plain
    /// lines on stderr without tqdm), or a callable `f(stage, done, total)`.
    fn new(py: Python<'py>, progress: Option<&Bound<'py, PyAny>>, what: &str) -> PyResult<Self> {
        let Some(p) = progress.filter(|p| !p.is_none()) else {
            return Ok(Sink::Off);
        };
        if let Ok(b) = p.cast::<pyo3::types::PyBool>() {
            if !b.is_true() {
                return Ok(Sink::Off);
            }
            return Ok(match py.import("tqdm.auto") {
                Ok(m) => Sink::Tqdm {
                    class: m.getattr("tqdm")?,
                    what: what.to_string(),
                    bar: None,
                },
                Err(_) => Sink::Text {
                    what: what.to_string(),
                    last: None,
                },
            });
        }
        if p.is_callable() {
            return Ok(Sink::Call(p.clone()));
        }
        Err(PyTypeError::new_err(format!(
            "progress must be None, a bool or a callable progress(stage, done, total), not {}",
            p.get_type().name()?
        )))
    }

    fn send(&mut self, py: Python<'py>, events: Vec<Event>) -> PyResult<()> {
        for ev in events {
            match self {
                Sink::Off => {}
                Sink::Call(f) => {
                    f.call1((ev.stage.as_str(), ev.done, ev.total))?;
                }
                Sink::Tqdm { class, what, bar } => {
                    let desc = format!("{what}: {}", ev.stage);
                    if bar.as_ref().map_or(true, |(d, _)| *d != desc) {
                        if let Some((_, old)) = bar.take() {
                            old.call_method0("close")?;
                        }
                        let kw = pyo3::types::PyDict::new(py);
                        kw.set_item("total", ev.total)?;
                        kw.set_item("desc", &desc)?;
                        kw.set_item("leave", false)?;
                        *bar = Some((desc, class.call((), Some(&kw))?));
                    }
                    if let Some((_, b)) = bar.as_ref() {
                        b.setattr("total", ev.total)?;
                        b.setattr("n", ev.done)?;
                        b.call_method0("refresh")?;
                    }
                }
                Sink::Text { what, last } => {
                    let line = format!("{what}: {} {}/{}", ev.stage, ev.done, ev.total);
                    if last.as_deref() != Some(line.as_str()) {
                        let err = py.import("sys")?.getattr("stderr")?;
                        err.call_method1("write", (format!("\r{line}\x1b[K"),))?;
                        err.call_method0("flush")?;
                        *last = Some(line);
                    }
                }
            }
        }
        Ok(())
    }

    fn finish(&mut self, py: Python<'py>) -> PyResult<()> {
        match self {
            Sink::Tqdm { bar, .. } => {
                if let Some((_, b)) = bar.take() {
                    b.call_method0("close")?;
                }
            }
            Sink::Text { last, .. } if last.is_some() => {
                let err = py.import("sys")?.getattr("stderr")?;
                err.call_method1("write", ("\r\x1b[K",))?;
                err.call_method0("flush")?;
            }
            _ => {}
        }
        Ok(())
    }
}

/// Runs `work(cancel, reporter)` with the GIL released on a worker thread,
/// Ctrl-C and `progress=` handled as the module docs say. `what` names the
/// call in the bar (e.g. the model).
pub fn run<T, F>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    what: &str,
    work: F,
) -> PyResult<T>
where
    T: Send,
    F: FnOnce(Cancel, &Reporter) -> T + Send,
{
    let mut sink = Sink::new(py, progress, what)?;
    let flag = Flag::take();
    let cancel = Cancel::new(flag.0);
    let reporter = Reporter::default();
    let done = (Mutex::new(false), Condvar::new());
    std::thread::scope(|s| {
        let (rep, fin) = (&reporter, &done);
        /// Tells the poller the worker ended, also when it unwinds.
        struct Finished<'a>(&'a (Mutex<bool>, Condvar));
        impl Drop for Finished<'_> {
            fn drop(&mut self) {
                if let Ok(mut d) = self.0 .0.lock() {
                    *d = true;
                }
                self.0 .1.notify_all();
            }
        }
        let handle = std::thread::Builder::new()
            .name("nlsdof-work".into())
            .stack_size(WORKER_STACK)
            .spawn_scoped(s, move || {
                let _finished = Finished(fin);
                work(cancel, rep)
            })
            .map_err(|e| PyValueError::new_err(format!("cannot start a worker thread: {e}")))?;
        let mut raised: Option<PyErr> = None;
        loop {
            let finished = py.detach(|| {
                let Ok(d) = fin.0.lock() else { return true };
                match fin.1.wait_timeout_while(d, POLL, |d| !*d) {
                    Ok((d, _)) => *d,
                    Err(_) => true,
                }
            });
            if raised.is_none() {
                let r = py
                    .check_signals()
                    .and_then(|()| sink.send(py, reporter.drain()));
                if let Err(e) = r {
                    flag.0.store(true, Ordering::Relaxed);
                    raised = Some(e);
                }
            }
            if finished {
                break;
            }
        }
        let out = match handle.join() {
            Ok(v) => v,
            Err(panic) => std::panic::resume_unwind(panic),
        };
        let closed = sink.finish(py);
        match raised {
            Some(e) => Err(e),
            None => closed.map(|()| out),
        }
    })
}
