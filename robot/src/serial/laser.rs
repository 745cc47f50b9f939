//! The laser's line: a reader thread decodes telegrams as they arrive and stamps each scan then,
//! so a scan that waits in a queue while the controller is busy keeps the time it was measured.
//!
//! A scan's stamp is the clock when its telegram was complete, less the telegram's time on the
//! line at the laser's rate and one sweep of the mirror: the start of its sweep, as the twin
//! stamps it. The queue of scans is bounded (the oldest are dropped and counted), the decoder
//! holds at most one telegram, and replies to requests go to a second bounded queue.

use super::port::{Endpoint, Port, open};
use crate::hardware::LaserScan;
use crate::protocol::serial_time;
use crate::protocol::sick::{Frame, MEASURED_VALUES, MeasuredValues, Telegram, TelegramDecoder};
use crate::time::{Clock, Stamp};
use core::time::Duration;
use std::collections::VecDeque;
use std::io::{self, Write};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;

/// Scans kept while nobody reads them (about 6 s of a 38400 bps LMS).
const SCAN_QUEUE: usize = 32;
/// Replies kept while nobody reads them.
const REPLY_QUEUE: usize = 16;

/// How the laser's telegrams are timed and read.
#[derive(Clone, Debug)]
pub(crate) struct LaserTiming {
    /// Line rate, bits per second.
    pub baud: u32,
    /// Time the mirror takes for one scan.
    pub sweep: Duration,
    /// The no-return value, millimetres.
    pub range_max_mm: u16,
}

/// What the reader thread shares with the backend.
#[derive(Default)]
struct State {
    scans: VecDeque<LaserScan>,
    replies: VecDeque<Frame>,
    /// The reader is running on a live stream.
    alive: bool,
    /// The backend asks the reader to end.
    stop: bool,
    /// What happened on the line, for the backend's report.
    notes: Vec<String>,
    dropped_scans: u64,
}

#[derive(Default)]
struct Shared {
    state: Mutex<State>,
    changed: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        // A reader that panicked leaves the queues consistent: keep using them.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// One connection to the laser, with its reader thread.
pub(crate) struct LaserLink {
    writer: Box<dyn Port>,
    shared: Arc<Shared>,
    reader: Option<JoinHandle<()>>,
}

impl LaserLink {
    /// Opens `endpoint` and starts the reader.
    pub fn open(
        endpoint: &Endpoint,
        timing: &LaserTiming,
        poll: Duration,
        clock: Arc<dyn Clock>,
    ) -> io::Result<Self> {
        let writer = open(endpoint, timing.baud, poll)?;
        let reader_port = writer.try_clone_port()?;
        let shared = Arc::new(Shared::default());
        shared.lock().alive = true;
        let reader = {
            let shared = Arc::clone(&shared);
            let timing = timing.clone();
            std::thread::Builder::new()
                .name("laser-reader".into())
                .spawn(move || read_loop(reader_port, &shared, &timing, clock.as_ref()))?
        };
        Ok(LaserLink {
            writer,
            shared,
            reader: Some(reader),
        })
    }

    /// Whether the stream is still up.
    pub fn alive(&self) -> bool {
        self.shared.lock().alive
    }

    /// Sends one telegram.
    pub fn send(&mut self, telegram: &Telegram) -> io::Result<()> {
        let bytes = telegram
            .encode()
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
        self.writer.write_all(&bytes)?;
        self.writer.flush()
    }

    /// Forgets replies received so far (before a request).
    pub fn clear_replies(&self) {
        self.shared.lock().replies.clear();
    }

    /// Takes the oldest reply, waiting up to `wait` of wall time for one.
    pub fn next_reply(&self, wait: Duration) -> Option<Frame> {
        self.take_waiting(wait, |state| state.replies.pop_front())
    }

    /// Takes the oldest scan, waiting up to `wait` of wall time for one.
    pub fn next_scan(&self, wait: Duration) -> Option<LaserScan> {
        self.take_waiting(wait, |state| state.scans.pop_front())
    }

    /// Takes what `take` finds, waiting once, up to `wait`, for the reader to add something.
    fn take_waiting<T>(&self, wait: Duration, take: impl Fn(&mut State) -> Option<T>) -> Option<T> {
        let mut state = self.shared.lock();
        if let Some(found) = take(&mut state) {
            return Some(found);
        }
        if state.alive {
            state = self
                .shared
                .changed
                .wait_timeout(state, wait)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
        take(&mut state)
    }

    /// Drops the scans measured before `t` without handing them over.
    pub fn drop_scans_before(&self, t: Stamp) {
        self.shared.lock().scans.retain(|s| s.stamp >= t);
    }

    /// What the reader noted since the last call, and scans dropped for want of a reader.
    pub fn take_notes(&self) -> (Vec<String>, u64) {
        let mut state = self.shared.lock();
        (
            std::mem::take(&mut state.notes),
            std::mem::take(&mut state.dropped_scans),
        )
    }
}

impl Drop for LaserLink {
    fn drop(&mut self) {
        self.shared.lock().stop = true;
        if let Some(reader) = self.reader.take() {
            // It notices within one poll interval.
            let _ = reader.join();
        }
    }
}

/// The reader thread: bytes in, stamped scans and replies out, until the stream ends or the
/// backend lets go.
fn read_loop(mut port: Box<dyn Port>, shared: &Shared, timing: &LaserTiming, clock: &dyn Clock) {
    let mut decoder = TelegramDecoder::new();
    let mut chunk = [0u8; 1024];
    let sweep = timing.sweep;
    let end = loop {
        if shared.lock().stop {
            break None;
        }
        match port.read(&mut chunk) {
            Ok(0) => break Some("the laser's stream closed".to_string()),
            Ok(n) => decoder.push(&chunk[..n]),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut
                        | io::ErrorKind::WouldBlock
                        | io::ErrorKind::Interrupted
                ) =>
            {
                continue;
            }
            Err(e) => break Some(format!("the laser's stream failed: {e}")),
        }
        let now = clock.now();
        let mut state = shared.lock();
        let mut skipped = 0usize;
        while let Some(frame) = decoder.next_frame() {
            match frame {
                Frame::Telegram(t) if t.command == MEASURED_VALUES => {
                    let scan = MeasuredValues::from_telegram(&t)
                        .and_then(|values| values.to_scan(Stamp::ZERO, timing.range_max_mm));
                    match scan {
                        Ok(mut scan) => {
                            let bytes = 8 + t.data.len(); // STX, address, length, command, status, CRC
                            let on_line = serial_time(bytes, timing.baud) + sweep;
                            let stamp = Stamp(now.0.saturating_sub(on_line.as_nanos() as u64));
                            if state.scans.len() == SCAN_QUEUE {
                                state.scans.pop_front();
                                state.dropped_scans += 1;
                            }
                            scan.stamp = stamp;
                            state.scans.push_back(scan);
                        }
                        Err(e) => state.notes.push(format!("unreadable measured values: {e}")),
                    }
                }
                Frame::Skipped { bytes, .. } => skipped += bytes,
                reply => {
                    if state.replies.len() == REPLY_QUEUE {
                        state.replies.pop_front();
                    }
                    state.replies.push_back(reply);
                }
            }
        }
        if skipped > 0 {
            state.notes.push(format!(
                "skipped {skipped} byte(s) of noise on the laser's line"
            ));
        }
        drop(state);
        shared.changed.notify_all();
    };
    let mut state = shared.lock();
    state.alive = false;
    if let Some(reason) = end {
        state.notes.push(reason);
    }
    drop(state);
    shared.changed.notify_all();
}
