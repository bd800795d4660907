//! Progress of the long commands (`torso fit`, `torso fit-sweep`, `torso bench soak`) on
//! stderr. On a terminal: a bar redrawn in place (at most every 0.1 s, and every 0.5 s by a
//! ticker so that the elapsed time moves), which reaches 100 % when the work ends. When
//! stderr is piped or redirected: one line at the first update, then at least every
//! [`LINE_INTERVAL`] (a ticker thread writes one even when no update comes), and a last
//! line at 100 %; each line holds the count done over the total, the percentage, the
//! command's own detail (e.g. the best cost), the elapsed time and the estimated time left.
//! When the total is a limit the work may stop before (a search's largest number of
//! evaluations, [`Progress::up_to`]), the lines say so ("10 of at most 120", "ETA at most"),
//! and the last one gives the count reached and the limit it stopped before.

use std::io::{IsTerminal, Write};
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Longest time between two progress lines when stderr is not a terminal.
pub const LINE_INTERVAL: Duration = Duration::from_secs(5);

/// Width of the terminal bar in characters.
const BAR_WIDTH: usize = 30;

struct State {
    done: usize,
    total: usize,
    detail: String,
    /// Whether `total` is a limit the work may stop before ([`Progress::up_to`]).
    limit: bool,
    /// The limit the work ended before ([`Progress::finish`] of a limited count).
    stopped_before: Option<usize>,
    last_line: Option<Instant>,
    last_draw: Option<Instant>,
    drawn: bool,
}

struct Shared {
    label: String,
    unit: String,
    terminal: bool,
    interval: Duration,
    start: Instant,
    state: Mutex<State>,
    out: Mutex<Box<dyn Write + Send>>,
}

/// A progress reporter (see the module doc). `update` takes `&self`, so threads may share
/// it.
pub struct Progress {
    shared: Arc<Shared>,
    ticker: Mutex<Option<(Sender<()>, JoinHandle<()>)>>,
}

/// `secs` as `12.3 s`, `4 min 05 s` or `1 h 02 min`.
pub fn format_secs(secs: f64) -> String {
    if !secs.is_finite() {
        return "?".into();
    }
    let s = secs.max(0.0);
    if s < 60.0 {
        format!("{s:.1} s")
    } else if s < 3600.0 {
        let m = (s / 60.0).floor();
        format!("{m:.0} min {:02.0} s", (s - 60.0 * m).floor())
    } else {
        let h = (s / 3600.0).floor();
        format!("{h:.0} h {:02.0} min", ((s - 3600.0 * h) / 60.0).floor())
    }
}

impl Shared {
    fn percent(&self, st: &State) -> f64 {
        if st.total == 0 {
            100.0
        } else {
            (100.0 * st.done as f64 / st.total as f64).min(100.0)
        }
    }

    fn eta(&self, st: &State, elapsed: f64) -> String {
        let at_most = if st.limit { "at most " } else { "" };
        if st.done >= st.total {
            "0 s".into()
        } else if st.done == 0 {
            "?".into()
        } else {
            let left = elapsed * (st.total - st.done) as f64 / st.done as f64;
            format!("{at_most}{}", format_secs(left))
        }
    }

    /// The count: `10/120 evaluations`, with a limit `10 of at most 120 evaluations`, and at
    /// the end of a limited count `59 evaluations`.
    fn count(&self, st: &State) -> String {
        let (done, total, unit) = (st.done, st.total, &self.unit);
        match st.stopped_before {
            Some(_) => format!("{done} {unit}"),
            None if st.limit => format!("{done} of at most {total} {unit}"),
            None => format!("{done}/{total} {unit}"),
        }
    }

    /// What follows the percentage: `, stopped before the limit of 120` at the end of a
    /// limited count that ended early, then the command's detail.
    fn detail(st: &State) -> String {
        let stopped = st
            .stopped_before
            .map(|limit| format!(", stopped before the limit of {limit}"))
            .unwrap_or_default();
        if st.detail.is_empty() {
            stopped
        } else {
            format!("{stopped}, {}", st.detail)
        }
    }

    /// One progress line (piped output).
    fn line(&self, st: &State, end: bool) -> String {
        let elapsed = self.start.elapsed().as_secs_f64();
        format!(
            "{}: {} ({:.0} %){}, elapsed {}, {}\n",
            self.label,
            self.count(st),
            self.percent(st),
            Self::detail(st),
            format_secs(elapsed),
            if end {
                "done".to_string()
            } else {
                format!("ETA {}", self.eta(st, elapsed))
            }
        )
    }

    /// The bar, drawn over the current line (terminal).
    fn bar(&self, st: &State) -> String {
        let elapsed = self.start.elapsed().as_secs_f64();
        let p = self.percent(st);
        let filled = ((p / 100.0 * BAR_WIDTH as f64).floor() as usize).min(BAR_WIDTH);
        format!(
            "\r{} [{}{}] {:>3.0} % {}{}, {} elapsed, ETA {}\x1b[K",
            self.label,
            "#".repeat(filled),
            ".".repeat(BAR_WIDTH - filled),
            p,
            self.count(st),
            Self::detail(st),
            format_secs(elapsed),
            self.eta(st, elapsed)
        )
    }

    fn write(&self, text: &str) {
        if let Ok(mut out) = self.out.lock() {
            // Progress is advisory: a closed stderr must not stop the work.
            let _ = out.write_all(text.as_bytes());
            let _ = out.flush();
        }
    }

    /// Writes what is due: `force` writes whatever the throttle says. The text is written
    /// while the state is locked, so that lines reach the output in the order of their
    /// counts (a ticker's line never lands after a newer one).
    fn emit(&self, force: bool) {
        let Ok(mut st) = self.state.lock() else {
            return;
        };
        let now = Instant::now();
        if self.terminal {
            let due = st
                .last_draw
                .is_none_or(|t| now.duration_since(t) >= Duration::from_millis(100));
            if force || due {
                st.last_draw = Some(now);
                st.drawn = true;
                let text = self.bar(&st);
                self.write(&text);
            }
        } else {
            let due = st
                .last_line
                .is_none_or(|t| now.duration_since(t) >= self.interval);
            if force || due {
                st.last_line = Some(now);
                let text = self.line(&st, false);
                self.write(&text);
            }
        }
    }
}

impl Progress {
    /// A reporter on stderr for `total` items of `unit` (e.g. `evaluations`), labelled
    /// `label`; a bar when stderr is a terminal, lines otherwise.
    pub fn new(label: &str, total: usize, unit: &str) -> Progress {
        let terminal = std::io::stderr().is_terminal();
        Progress::to_writer(
            label,
            total,
            unit,
            terminal,
            LINE_INTERVAL,
            Box::new(std::io::stderr()),
        )
    }

    /// A reporter writing to `out`, as a bar (`terminal`) or as lines at least every
    /// `interval`.
    pub fn to_writer(
        label: &str,
        total: usize,
        unit: &str,
        terminal: bool,
        interval: Duration,
        out: Box<dyn Write + Send>,
    ) -> Progress {
        let shared = Arc::new(Shared {
            label: label.into(),
            unit: unit.into(),
            terminal,
            interval,
            start: Instant::now(),
            state: Mutex::new(State {
                done: 0,
                total,
                detail: String::new(),
                limit: false,
                stopped_before: None,
                last_line: None,
                last_draw: None,
                drawn: false,
            }),
            out: Mutex::new(out),
        });
        let (tx, rx) = mpsc::channel::<()>();
        let tick = if terminal {
            Duration::from_millis(500)
        } else {
            (interval / 10).max(Duration::from_millis(10))
        };
        let ticker_shared = Arc::clone(&shared);
        let handle = std::thread::spawn(move || {
            while let Err(RecvTimeoutError::Timeout) = rx.recv_timeout(tick) {
                let s = &ticker_shared;
                if s.terminal {
                    // Redraw a started bar so that the elapsed time moves.
                    if s.state.lock().is_ok_and(|st| st.drawn) {
                        s.emit(true);
                    }
                } else {
                    // Lines: due `interval` after the last one (or the start).
                    let due = s
                        .state
                        .lock()
                        .is_ok_and(|st| st.last_line.unwrap_or(s.start).elapsed() >= s.interval);
                    if due {
                        s.emit(true);
                    }
                }
            }
        });
        Progress {
            shared,
            ticker: Mutex::new(Some((tx, handle))),
        }
    }

    /// Records `done` items so far and the detail shown after the count, and writes the bar
    /// or a line when due.
    pub fn update(&self, done: usize, detail: impl Into<String>) {
        if let Ok(mut st) = self.shared.state.lock() {
            st.done = done;
            st.detail = detail.into();
        }
        self.shared.emit(false);
    }

    /// Writes one message line without breaking the bar: on a terminal the bar's line is
    /// cleared, the message written and the bar drawn again below it.
    pub fn message(&self, text: &str) {
        // Under the state's lock, as every line (see `emit`).
        let Ok(mut st) = self.shared.state.lock() else {
            return;
        };
        if self.shared.terminal {
            st.last_draw = Some(Instant::now());
            st.drawn = true;
            let bar = self.shared.bar(&st);
            self.shared.write(&format!("\r\x1b[K{text}\n{bar}"));
        } else {
            self.shared.write(&format!("{text}\n"));
        }
    }

    /// Marks the total as a limit the work may stop before (a search's largest number of
    /// evaluations): the count reads "10 of at most 120", the estimate "at most", and the
    /// last line the count reached and the limit.
    pub fn up_to(self) -> Progress {
        if let Ok(mut st) = self.shared.state.lock() {
            st.limit = true;
        }
        self
    }

    /// Changes the total (e.g. when the work turns out shorter).
    pub fn set_total(&self, total: usize) {
        if let Ok(mut st) = self.shared.state.lock() {
            st.total = total;
        }
    }

    fn stop_ticker(&self) {
        if let Some((tx, handle)) = self.ticker.lock().ok().and_then(|mut t| t.take()) {
            let _ = tx.send(());
            let _ = handle.join();
        }
    }

    /// Ends the work: the count becomes the total (a search that stops early has done all
    /// it will do), and the last line or the full bar is written with `detail`.
    pub fn finish(&self, detail: impl Into<String>) {
        self.stop_ticker();
        let Ok(mut st) = self.shared.state.lock() else {
            return;
        };
        if st.done < st.total {
            if st.limit {
                st.stopped_before = Some(st.total);
            }
            st.total = st.done;
        }
        st.detail = detail.into();
        let text = if self.shared.terminal {
            self.shared.bar(&st) + "\n"
        } else {
            self.shared.line(&st, true)
        };
        // Written under the state's lock, as every line (see `emit`).
        self.shared.write(&text);
        st.drawn = false;
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.stop_ticker();
        // An unfinished bar (an error ended the work): end its line.
        if let Ok(st) = self.shared.state.lock()
            && self.shared.terminal
            && st.drawn
        {
            self.shared.write("\n");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Default)]
    struct Sink(Arc<Mutex<Vec<u8>>>);
    impl Write for Sink {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }
    impl Sink {
        fn text(&self) -> String {
            String::from_utf8(self.0.lock().unwrap().clone()).unwrap()
        }
    }

    #[test]
    fn piped_lines_come_at_the_interval_without_updates_and_end_at_100() {
        let sink = Sink::default();
        let p = Progress::to_writer(
            "fit",
            120,
            "evaluations",
            false,
            Duration::from_millis(100),
            Box::new(sink.clone()),
        );
        p.update(10, "best cost 0.900 mm");
        // No update for 0.45 s: the ticker writes about four more lines.
        std::thread::sleep(Duration::from_millis(450));
        p.update(60, "best cost 0.800 mm");
        p.finish("best cost 0.700 mm");
        let text = sink.text();
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines.len() >= 4, "{text}");
        assert!(
            lines[0].starts_with("fit: 10/120 evaluations (8 %), best cost 0.900 mm, elapsed"),
            "{text}"
        );
        assert!(lines[0].contains("ETA"), "{text}");
        let last = lines.last().unwrap();
        assert!(
            last.starts_with("fit: 60/60 evaluations (100 %), best cost 0.700 mm")
                && last.ends_with("done"),
            "{text}"
        );
    }

    #[test]
    fn a_limited_count_says_it_is_a_limit_and_where_it_stopped() {
        let sink = Sink::default();
        let p = Progress::to_writer(
            "fit",
            120,
            "evaluations",
            false,
            Duration::from_secs(60),
            Box::new(sink.clone()),
        )
        .up_to();
        p.update(10, "best cost 0.900 mm");
        p.update(59, "best cost 0.800 mm");
        p.finish("best cost 0.700 mm");
        let text = sink.text();
        let lines: Vec<&str> = text.lines().collect();
        assert!(
            lines[0].starts_with("fit: 10 of at most 120 evaluations (8 %), best cost 0.900 mm")
                && lines[0].contains("ETA at most "),
            "{text}"
        );
        let last = lines.last().unwrap();
        assert!(
            last.starts_with(
                "fit: 59 evaluations (100 %), stopped before the limit of 120, best cost 0.700 mm"
            ) && last.ends_with("done"),
            "{text}"
        );
    }

    /// A sink that takes its time to write, so that a line computed before another one
    /// would have time to be overtaken were it written after releasing the state.
    #[derive(Clone, Default)]
    struct SlowSink(Sink);
    impl Write for SlowSink {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            std::thread::sleep(Duration::from_micros(200));
            self.0.write(b)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn lines_of_the_ticker_and_of_updates_come_in_count_order() {
        let sink = SlowSink::default();
        // Interval zero: every update writes a line, and the ticker one every 10 ms.
        let p = Arc::new(Progress::to_writer(
            "fit",
            400,
            "evaluations",
            false,
            Duration::ZERO,
            Box::new(sink.clone()),
        ));
        let q = Arc::clone(&p);
        let updater = std::thread::spawn(move || {
            for k in 1..=400 {
                q.update(k, "");
            }
        });
        updater.join().unwrap();
        p.finish("");
        let text = sink.0.text();
        let counts: Vec<usize> = text
            .lines()
            .map(|l| {
                let done = l.trim_start_matches("fit: ").split('/').next().unwrap();
                done.parse().unwrap()
            })
            .collect();
        assert!(counts.len() >= 400, "{text}");
        assert!(counts.windows(2).all(|w| w[0] <= w[1]), "{counts:?}");
    }

    #[test]
    fn terminal_bar_is_redrawn_in_place_and_reaches_100() {
        let sink = Sink::default();
        let p = Progress::to_writer(
            "soak",
            4,
            "scenes",
            true,
            LINE_INTERVAL,
            Box::new(sink.clone()),
        );
        p.update(1, "1 ok");
        p.update(4, "4 ok");
        p.finish("4 ok");
        let text = sink.text();
        assert!(text.starts_with("\rsoak [#######"), "{text:?}");
        assert!(
            text.contains("\rsoak [##############################] 100 % 4/4 scenes, 4 ok"),
            "{text:?}"
        );
        assert!(
            text.ends_with('\n') && text.matches('\n').count() == 1,
            "{text:?}"
        );
    }

    #[test]
    fn durations_read_naturally() {
        assert_eq!(format_secs(12.34), "12.3 s");
        assert_eq!(format_secs(245.0), "4 min 05 s");
        assert_eq!(format_secs(3720.0), "1 h 02 min");
        assert_eq!(format_secs(f64::NAN), "?");
    }
}
