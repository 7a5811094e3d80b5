//! What a person sees while a command runs: lines on stdout and stderr that never panic when the
//! reader has gone (`xtask run … | head -1`, `| true`), and the progress of the run in flight — a
//! bar (or a spinner with the elapsed time, for runners that report no progress) on a terminal,
//! plain lines at every tenth of the way (or every minute) when stderr is a file or a pipe.
//!
//! Experiments report progress through `Recorder::progress`; the file recorder forwards it to
//! [`progress`], which updates the run in flight ([`RunProgress::start`]).

use std::fmt;
use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

static STDOUT_GONE: AtomicBool = AtomicBool::new(false);

/// Writes to stdout; a closed or broken stdout is remembered and further output dropped, never a
/// panic (the run goes on and still writes its files).
pub fn out(args: fmt::Arguments) {
    if STDOUT_GONE.load(Ordering::Relaxed) {
        return;
    }
    let mut s = std::io::stdout().lock();
    if s.write_fmt(args).and_then(|_| s.write_all(b"\n")).and_then(|_| s.flush()).is_err() {
        STDOUT_GONE.store(true, Ordering::Relaxed);
    }
}

/// Writes a line to stderr, ignoring a closed stderr.
pub fn err(args: fmt::Arguments) {
    let mut s = std::io::stderr().lock();
    let _ = s.write_fmt(args).and_then(|_| s.write_all(b"\n"));
}

/// `println!` that never panics ([`out`]).
#[macro_export]
macro_rules! say {
    ($($t:tt)*) => { $crate::ui::out(format_args!($($t)*)) };
}

/// `eprintln!` that never panics ([`err`]).
#[macro_export]
macro_rules! tell {
    ($($t:tt)*) => { $crate::ui::err(format_args!($($t)*)) };
}

/// True when stderr is a terminal (bars and spinners), false for files and pipes (plain lines).
pub fn stderr_is_terminal() -> bool {
    std::io::stderr().is_terminal()
}

enum Display {
    /// indicatif on a terminal.
    Bar(ProgressBar),
    /// Plain lines: the last tenth printed.
    Plain { last_tenth: u64 },
}

struct State {
    label: String,
    start: Instant,
    display: Display,
    has_total: bool,
}

/// The progress display of one run (a scene or a benchmark).
#[derive(Clone)]
pub struct RunProgress {
    state: Arc<Mutex<State>>,
    stop: Arc<AtomicBool>,
}

static CURRENT: Mutex<Option<RunProgress>> = Mutex::new(None);

/// Reports progress of the run in flight: `done` of `total` units (frames, steps, sweep points).
pub fn progress(done: u64, total: u64) {
    let cur = CURRENT.lock().ok().and_then(|c| c.clone());
    if let Some(p) = cur {
        p.set(done, total);
    }
}

fn lock(m: &Mutex<State>) -> std::sync::MutexGuard<'_, State> {
    // A poisoned lock only means a panic elsewhere while printing; the state is still usable.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl RunProgress {
    /// Starts the display for a run labelled `label` and makes it the run in flight. On a
    /// terminal: a spinner with the elapsed time until the run reports a total, then a bar. Not
    /// on a terminal: a line every minute until the run reports a total, then a line per tenth.
    pub fn start(label: &str) -> RunProgress {
        let display = if stderr_is_terminal() {
            let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
            bar.set_style(
                ProgressStyle::with_template("{spinner} {prefix} {elapsed:>4} {msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            );
            bar.set_prefix(label.to_string());
            bar.enable_steady_tick(Duration::from_millis(120));
            Display::Bar(bar)
        } else {
            Display::Plain { last_tenth: 0 }
        };
        let p = RunProgress {
            state: Arc::new(Mutex::new(State {
                label: label.to_string(),
                start: Instant::now(),
                display,
                has_total: false,
            })),
            stop: Arc::new(AtomicBool::new(false)),
        };
        if matches!(lock(&p.state).display, Display::Plain { .. }) {
            let q = p.clone();
            std::thread::spawn(move || q.plain_ticker());
        }
        if let Ok(mut c) = CURRENT.lock() {
            *c = Some(p.clone());
        }
        p
    }

    /// Not on a terminal: "still running" every minute while the run reports no total.
    fn plain_ticker(&self) {
        let mut next = 60u64;
        while !self.stop.load(Ordering::Relaxed) {
            std::thread::sleep(Duration::from_millis(250));
            let st = lock(&self.state);
            let el = st.start.elapsed().as_secs();
            if el >= next {
                next += 60;
                if !st.has_total {
                    tell!("  {} … {el} s", st.label);
                }
            }
        }
    }

    /// Updates the display: `done` of `total`.
    pub fn set(&self, done: u64, total: u64) {
        let mut st = lock(&self.state);
        let had_total = st.has_total;
        st.has_total = total > 0;
        let elapsed = st.start.elapsed().as_secs_f64();
        let label = st.label.clone();
        match &mut st.display {
            Display::Bar(bar) => {
                if !had_total && total > 0 {
                    bar.set_style(
                        ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} {elapsed:>4} eta {eta} {msg}")
                            .unwrap_or_else(|_| ProgressStyle::default_bar())
                            .progress_chars("=> "),
                    );
                }
                bar.set_length(total);
                bar.set_position(done.min(total));
            }
            Display::Plain { last_tenth } => {
                if let Some(tenth) = (10 * done.min(total)).checked_div(total) {
                    if tenth > *last_tenth {
                        *last_tenth = tenth;
                        tell!("  {label} {done}/{total} ({} %) {elapsed:.1} s", 10 * tenth);
                    }
                }
            }
        }
    }

    /// Sets the message shown after the bar (the stage of the run: "previews" …).
    pub fn message(&self, msg: &str) {
        if let Display::Bar(bar) = &lock(&self.state).display {
            bar.set_message(msg.to_string());
        }
    }

    /// Removes the display and stops being the run in flight.
    pub fn finish(&self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Display::Bar(bar) = &lock(&self.state).display {
            bar.finish_and_clear();
        }
        if let Ok(mut c) = CURRENT.lock() {
            if c.as_ref().is_some_and(|p| Arc::ptr_eq(&p.state, &self.state)) {
                *c = None;
            }
        }
    }
}

/// A byte count for people: `812 B`, `14.2 kB`, `3.1 MB`.
pub fn human_bytes(n: u64) -> String {
    if n < 1000 {
        format!("{n} B")
    } else if n < 1_000_000 {
        format!("{:.1} kB", n as f64 / 1e3)
    } else if n < 1_000_000_000 {
        format!("{:.1} MB", n as f64 / 1e6)
    } else {
        format!("{:.2} GB", n as f64 / 1e9)
    }
}

/// A duration for people: `0.42 s`, `12.3 s`, `4 min 05 s`.
pub fn human_secs(s: f64) -> String {
    if !s.is_finite() {
        format!("{s} s")
    } else if s < 10.0 {
        format!("{s:.2} s")
    } else if s < 120.0 {
        format!("{s:.1} s")
    } else {
        let m = (s / 60.0).floor();
        format!("{m:.0} min {:02.0} s", s - 60.0 * m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn human_units() {
        assert_eq!(human_bytes(812), "812 B");
        assert_eq!(human_bytes(14_200), "14.2 kB");
        assert_eq!(human_bytes(3_100_000), "3.1 MB");
        assert_eq!(human_secs(0.421), "0.42 s");
        assert_eq!(human_secs(12.34), "12.3 s");
        assert_eq!(human_secs(245.0), "4 min 05 s");
    }
}
