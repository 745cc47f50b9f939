//! A microcontroller board: the firmware, its serial port, and when its main loop is free.
//!
//! Both of the robot's microcontrollers (the base's and the pan-tilt's) run the same shape of
//! program: interrupts count encoder edges and set a flag every 1.024 ms; the main loop executes
//! a received line, then, if a real-time interrupt has happened, runs `check_rtf` once.
//! `ser0_putchar` busy-waits until the UART can take the next byte, so while a reply goes out at 9600 bps — 18 ms for a
//! status line — the main loop is stuck: the speed loop does not run, the ramp timer does not
//! count, and the 8-bit encoder pulse accumulators, no longer latched, saturate at 255.
//! [`Board`] reproduces that timing for any firmware that implements [`MainLoop`]:
//!
//! - a byte written by the firmware takes ten bit-times on the line after the previous one, and
//!   `putchar` returns when the byte has moved into the UART's data register;
//! - a line from the host is executed at the first tick where the main loop is free; lines that
//!   complete while an earlier one waits are lost, as `decode_command` clears the whole buffer;
//! - `check_rtf` runs once when the main loop comes back, however many interrupts happened.

use super::base::BaseFirmware;
use robot::Stamp;
use std::collections::VecDeque;

/// The main loop of a firmware, as a board drives it.
pub trait MainLoop {
    /// Decodes and executes one received command line (`decode_command`, `do_command`).
    fn execute_line(&mut self, line: &[u8]);
    /// The main loop's pass after a real-time interrupt: `check_rtf` and what follows it.
    fn after_interrupt(&mut self);
    /// Takes the bytes written to the serial port since the last call.
    fn take_output(&mut self) -> Vec<u8>;
}

impl MainLoop for BaseFirmware {
    fn execute_line(&mut self, line: &[u8]) {
        BaseFirmware::execute_line(self, line);
    }
    fn after_interrupt(&mut self) {
        self.check_rtf();
    }
    fn take_output(&mut self) -> Vec<u8> {
        BaseFirmware::take_output(self)
    }
}

/// The base microcontroller with its serial port.
pub type BaseBoard = Board<BaseFirmware>;

/// A microcontroller with its serial port.
#[derive(Clone, Debug)]
pub struct Board<F> {
    firmware: F,
    /// Bit rate of the serial line.
    baud: u32,
    /// Ten bit-times, nanoseconds.
    byte_ns: u64,
    /// Lines received from the host, with the time their `\n` arrived.
    inbox: VecDeque<(Stamp, Vec<u8>)>,
    /// Bytes sent to the host, with the time each arrives there.
    outbox: VecDeque<(Stamp, u8)>,
    /// When the UART's shift register finishes the last queued byte.
    tx_free_at: Stamp,
    /// When the UART's data register empties (the last queued byte started shifting).
    tdre_at: Stamp,
    /// The main loop is inside `ser0_putchar` until then.
    busy_until: Stamp,
    /// `real_time_flag`: an interrupt happened and `check_rtf` has not run yet.
    rtf_pending: bool,
    lost_lines: u64,
}

impl BaseBoard {
    /// The base microcontroller just switched on, talking at `baud` bits per second; its greeting
    /// goes out at time zero.
    pub fn power_on(baud: u32) -> Self {
        Board::new(BaseFirmware::power_on(), baud)
    }
}

impl<F: MainLoop> Board<F> {
    /// A board running `firmware` just switched on, talking at `baud` bits per second; whatever
    /// the firmware wrote at power-on goes out at time zero.
    pub fn new(firmware: F, baud: u32) -> Self {
        let mut board = Board {
            firmware,
            baud,
            byte_ns: robot::protocol::serial_time(1, baud).as_nanos() as u64,
            inbox: VecDeque::new(),
            outbox: VecDeque::new(),
            tx_free_at: Stamp::ZERO,
            tdre_at: Stamp::ZERO,
            busy_until: Stamp::ZERO,
            rtf_pending: false,
            lost_lines: 0,
        };
        board.send_output(Stamp::ZERO);
        board
    }

    /// Bit rate of the serial line.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// The firmware.
    pub fn firmware(&self) -> &F {
        &self.firmware
    }

    /// The firmware, to feed its interrupts or set its state directly.
    pub fn firmware_mut(&mut self) -> &mut F {
        &mut self.firmware
    }

    /// A complete line from the host whose last byte arrived at `arrival`.
    pub fn deliver(&mut self, arrival: Stamp, line: Vec<u8>) {
        self.inbox.push_back((arrival, line));
    }

    /// Forgets the serial link's traffic (its client has gone): lines the main loop has not
    /// read yet, and bytes not yet taken by the host. Returns the bytes of output dropped.
    pub fn forget_link(&mut self) -> usize {
        self.inbox.clear();
        let dropped = self.outbox.len();
        self.outbox.clear();
        dropped
    }

    /// The next byte sent to the host, with the time it arrives there.
    pub fn pop_output(&mut self) -> Option<(Stamp, u8)> {
        self.outbox.pop_front()
    }

    /// Lines lost because they arrived while an earlier line waited for the main loop.
    pub fn lost_lines(&self) -> u64 {
        self.lost_lines
    }

    /// One real-time interrupt at `now`, and whatever the main loop does until the next one.
    /// `interrupts` runs the interrupt handlers of this tick (they run even while the main loop
    /// is busy); `latch` is what the main loop reads from the hardware before `check_rtf`.
    pub fn tick(
        &mut self,
        now: Stamp,
        interrupts: impl FnOnce(&mut F),
        latch: impl FnOnce(&mut F),
    ) {
        interrupts(&mut self.firmware);
        self.rtf_pending = true;
        if now < self.busy_until {
            return;
        }
        if self.inbox.front().is_some_and(|(t, _)| *t <= now) {
            let (_, line) = self.inbox.pop_front().expect("front exists");
            while self.inbox.front().is_some_and(|(t, _)| *t <= now) {
                self.inbox.pop_front();
                self.lost_lines += 1;
            }
            self.firmware.execute_line(&line);
            self.send_output(now);
            if now < self.busy_until {
                return;
            }
        }
        if self.rtf_pending {
            self.rtf_pending = false;
            latch(&mut self.firmware);
            self.firmware.after_interrupt();
            self.send_output(now);
        }
    }

    /// Puts the firmware's new output on the line, byte after byte, and notes how long
    /// `ser0_putchar` keeps the main loop waiting.
    fn send_output(&mut self, now: Stamp) {
        let bytes = self.firmware.take_output();
        let byte = core::time::Duration::from_nanos(self.byte_ns);
        let mut last_write = now;
        for b in bytes {
            let write = now.max(self.tdre_at);
            let start = write.max(self.tx_free_at);
            self.tx_free_at = start + byte;
            self.tdre_at = start;
            self.outbox.push_back((self.tx_free_at, b));
            last_write = write;
        }
        self.busy_until = self.busy_until.max(last_write);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TICK: u64 = 1_024_000;

    fn idle(fw: &mut BaseFirmware) {
        fw.rti_interrupt([0; 4]);
    }

    fn zero(fw: &mut BaseFirmware) {
        fw.latch_encoders(0, 0);
    }
    /// After the 31-byte power-on greeting has gone out.
    const T0: u64 = 50 * TICK;

    fn read_all(board: &mut BaseBoard) -> Vec<(Stamp, u8)> {
        std::iter::from_fn(|| board.pop_output()).collect()
    }

    #[test]
    fn the_greeting_goes_out_first_and_delays_the_first_command() {
        let mut board = BaseBoard::power_on(9600);
        board.deliver(Stamp(TICK), b"*\n".to_vec());
        for k in 1..=40 {
            board.tick(Stamp(k * TICK), idle, zero);
        }
        let out = read_all(&mut board);
        let text: Vec<u8> = out.iter().map(|(_, b)| *b).collect();
        assert_eq!(text, b"Robot ROCA-MOBILE-2 v1.0 listo\n*\n");
        assert!(
            out.last().unwrap().0 > Stamp(31 * TICK),
            "the echo waits for the greeting"
        );
    }

    #[test]
    fn a_status_reply_keeps_the_main_loop_busy_for_its_transmission() {
        let mut board = BaseBoard::power_on(9600);
        read_all(&mut board);
        board.deliver(Stamp(T0), b"l\n".to_vec());
        board.tick(Stamp(T0), idle, zero);
        let reply = read_all(&mut board);
        let text: Vec<u8> = reply.iter().map(|(_, b)| *b).collect();
        assert_eq!(text, b"l0.00 0.00 0 0 0\n");
        // 17 bytes at 9600 bps: the last arrives 17 byte-times after the command ran.
        let byte = 1_041_666;
        assert_eq!(reply.last().unwrap().0, Stamp(T0 + 17 * byte));
        // The main loop stays in ser0_putchar for 15 byte-times: check_rtf is skipped.
        let mut latched = 0;
        for k in 1..=15 {
            board.tick(Stamp(T0 + k * TICK), idle, |fw| {
                latched += 1;
                fw.latch_encoders(0, 0);
            });
        }
        assert_eq!(latched, 0, "no check_rtf while transmitting");
        board.tick(Stamp(T0 + 16 * TICK), idle, |fw| {
            latched += 1;
            fw.latch_encoders(0, 0);
        });
        assert_eq!(latched, 1, "check_rtf runs once when the main loop is back");
    }

    #[test]
    fn a_line_arriving_behind_a_pending_one_is_lost() {
        let mut board = BaseBoard::power_on(9600);
        read_all(&mut board);
        board.deliver(Stamp(T0), b"l\n".to_vec());
        board.tick(Stamp(T0), idle, zero);
        board.deliver(Stamp(T0 + 3 * TICK), b"*\n".to_vec());
        board.deliver(Stamp(T0 + 4 * TICK), b"z1\n".to_vec());
        for k in 1..40 {
            board.tick(Stamp(T0 + k * TICK), idle, zero);
        }
        let text: Vec<u8> = read_all(&mut board).iter().map(|(_, b)| *b).collect();
        assert!(
            text.ends_with(b"*\n"),
            "{:?}",
            String::from_utf8_lossy(&text)
        );
        assert_eq!(board.lost_lines(), 1);
        assert!(!board.firmware().buzzer());
    }
}
