//! Progress output that stays useful when stderr is redirected to a file.
//!
//! On a terminal, indicatif draws its bar. Otherwise indicatif would draw nothing, and a long
//! command would be silent for minutes; [`LogLines`] prints the bar's text as a plain log line
//! instead: the first one at once, then whenever the message changes (a new stage or
//! pressure) and at least every [`LOG_INTERVAL`].

use std::io::Write;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Longest silence between two log lines while work goes on.
pub const LOG_INTERVAL: Duration = Duration::from_secs(10);

/// Whether stderr is a terminal.
pub fn is_terminal() -> bool {
    use std::io::IsTerminal;
    std::io::stderr().is_terminal()
}

/// The bar on a terminal, log lines otherwise.
pub fn draw_target() -> indicatif::ProgressDrawTarget {
    if is_terminal() {
        indicatif::ProgressDrawTarget::stderr()
    } else {
        indicatif::ProgressDrawTarget::term_like(Box::new(LogLines::default()))
    }
}

/// An indicatif terminal that writes throttled log lines to stderr.
#[derive(Debug, Default)]
pub struct LogLines {
    /// Time of the last line, and the text of the last line up to its first digit (the
    /// message part; counters and times change on every draw).
    last: Mutex<Option<(Instant, String)>>,
}

/// The part of a drawn line before its counters, used to detect a new message.
fn message_part(s: &str) -> String {
    s.split(|c: char| c.is_ascii_digit())
        .next()
        .unwrap_or("")
        .to_string()
}

impl indicatif::TermLike for LogLines {
    fn width(&self) -> u16 {
        160
    }
    fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn write_line(&self, s: &str) -> std::io::Result<()> {
        let s = s.trim();
        if s.is_empty() {
            return Ok(());
        }
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        let msg = message_part(s);
        let due = match &*last {
            None => true,
            Some((t, m)) => *m != msg || t.elapsed() >= LOG_INTERVAL,
        };
        if due {
            *last = Some((Instant::now(), msg));
            let mut err = std::io::stderr().lock();
            writeln!(err, "{s}")?;
        }
        Ok(())
    }
    fn write_str(&self, s: &str) -> std::io::Result<()> {
        self.write_line(s)
    }
    fn clear_line(&self) -> std::io::Result<()> {
        Ok(())
    }
    fn flush(&self) -> std::io::Result<()> {
        std::io::stderr().flush()
    }
}
