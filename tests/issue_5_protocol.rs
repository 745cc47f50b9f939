//! Issue 5, first part: the protocol layer of the real backend. The line links of
//! `robot::protocol::line` talk to the twin's port of the base firmware (App. A) byte for byte,
//! and no byte sequence makes the line reader or the SICK telegram decoder panic, loop or hold
//! more than a bounded buffer (property tests).

use proptest::prelude::*;
use robot::Stamp;
use robot::hardware::{DriveCommand, DriveWait, PanTiltCommand, Ramp, SonarCommand};
use robot::protocol::line::{BaseLink, LineReader, LinkError, MAX_LINE, PanTiltLink};
use robot::protocol::sick::{Frame, MAX_LENGTH, MeasuredValues, Telegram, TelegramDecoder};
use sim::devices::firmware::{BaseFirmware, PanTiltFirmware};
use std::io::{self, Read, Write};

/// The twin's base firmware as a byte stream: what is written reaches its receive interrupt,
/// what it writes is read back; silence reads as a timeout, as on a serial port.
struct FirmwarePort(BaseFirmware, Vec<u8>);

impl Read for FirmwarePort {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let out = self.0.take_output();
        self.1.extend(out);
        if self.1.is_empty() {
            return Err(io::ErrorKind::TimedOut.into());
        }
        let n = self.1.len().min(buf.len());
        buf[..n].copy_from_slice(&self.1[..n]);
        self.1.drain(..n);
        Ok(n)
    }
}

impl Write for FirmwarePort {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0.receive(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[test]
fn the_base_link_and_the_twin_firmware_agree_byte_for_byte() {
    let mut base = BaseLink::new(FirmwarePort(BaseFirmware::power_on(), Vec::new()));
    // At power-on the firmware greets: a backend reads that line before its first command.
    assert_eq!(
        base.0.read_line().unwrap(),
        "Robot ROCA-MOBILE-2 v1.0 listo\n"
    );
    for command in [
        DriveCommand::Ramp(Ramp::POWER_ON),
        DriveCommand::Advance(535),
        DriveCommand::Retreat(10),
        DriveCommand::TurnLeft(78),
        DriveCommand::TurnRight(78),
        DriveCommand::WheelSpeeds {
            left: 30,
            right: -30,
        },
        DriveCommand::Stop,
        DriveCommand::Buzzer(false),
    ] {
        base.command(&command)
            .unwrap_or_else(|e| panic!("{command:?}: {e}"));
    }
    // Nothing has moved: the counters read zero, the motors off after `p`.
    let status = base.status(Stamp::ZERO).unwrap();
    assert_eq!((status.left_counts, status.right_counts), (0, 0));
    assert!(!status.left_on && !status.right_on);
    // The battery reply parses (the ADC reads zero before the first tick).
    base.battery(Stamp::ZERO).unwrap();
    base.sonar(&SonarCommand::Sequence(vec![0, 4, 8, 12]))
        .unwrap();
    base.sonar(&SonarCommand::Timing {
        echo_ms: 50,
        relax_ms: 20,
    })
    .unwrap();
    let echoes = base.sonar_report(4).unwrap();
    assert_eq!(echoes.len(), 4);
    // A wait on idle motors answers at once.
    base.wait(&DriveWait::motors(1000)).unwrap();
    // Nothing is left unread on the line.
    assert!(!base.0.stream_mut().0.has_output());
}

#[test]
fn an_unknown_letter_gets_no_answer_and_the_line_stays_usable() {
    let mut base = BaseLink::new(FirmwarePort(BaseFirmware::power_on(), Vec::new()));
    base.0.read_line().unwrap();
    // `do_command` ignores letters it does not know: the link reports the silence as a timeout.
    base.0.send("x12\n").unwrap();
    assert!(matches!(base.0.read_line(), Err(LinkError::Timeout)));
    base.command(&DriveCommand::Stop).unwrap();
}

/// The twin's pan-tilt firmware as a byte stream: a line reaches `do_command` at its newline.
struct PanTiltPort(PanTiltFirmware, Vec<u8>, Vec<u8>);

impl Read for PanTiltPort {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let out = self.0.take_output();
        self.2.extend(out);
        if self.2.is_empty() {
            return Err(io::ErrorKind::TimedOut.into());
        }
        let n = self.2.len().min(buf.len());
        buf[..n].copy_from_slice(&self.2[..n]);
        self.2.drain(..n);
        Ok(n)
    }
}

impl Write for PanTiltPort {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        for &c in buf {
            self.1.push(c);
            if c == b'\n' {
                let line = std::mem::take(&mut self.1);
                self.0.execute_line(&line);
            }
        }
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[test]
fn the_pan_tilt_link_and_the_twin_firmware_agree_byte_for_byte() {
    let fw = PanTiltFirmware::power_on(false, false, false);
    let mut head = PanTiltLink::new(PanTiltPort(fw, Vec::new(), Vec::new()));
    assert_eq!(head.0.read_line().unwrap(), "Sistema ROCA-PANT-TILT v1.0\n");
    for command in [
        PanTiltCommand::PanRamp(Ramp::POWER_ON),
        PanTiltCommand::TiltRamp(Ramp::POWER_ON),
        PanTiltCommand::Pan(3),
        PanTiltCommand::Tilt(31),
    ] {
        head.command(&command)
            .unwrap_or_else(|e| panic!("{command:?}: {e}"));
    }
    // `l` answers the nine fields of `report_status`; the moves just started.
    let status = head.status(Stamp::ZERO).unwrap();
    assert_eq!((status.pan, status.tilt), (0, 0));
    assert!(status.pan_on && status.tilt_on, "{status:?}");
    head.0.acknowledged("*\n", '*').unwrap();
    // The firmware has no `p`: the prose's stop request gets no answer, as the code says.
    head.0.send("p\n").unwrap();
    assert!(matches!(head.0.read_line(), Err(LinkError::Timeout)));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Any bytes, cut anywhere: the line reader returns lines or typed errors, each call
    /// consumes input or ends, and never buffers more than a line's bound.
    #[test]
    fn the_line_reader_survives_any_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..4096),
                                          chunk in 1usize..97) {
        let mut stream = io::Cursor::new(bytes.clone())
            .chain(io::Cursor::new(Vec::new()));
        struct Chunked<R>(R, usize);
        impl<R: Read> Read for Chunked<R> {
            fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
                let n = buf.len().min(self.1);
                self.0.read(&mut buf[..n])
            }
        }
        let mut source = Chunked(&mut stream, chunk);
        let mut reader = LineReader::new();
        let mut calls = 0;
        let mut text_bytes = 0;
        loop {
            calls += 1;
            prop_assert!(calls <= bytes.len() + 2, "the reader loops");
            match reader.read_line(&mut source) {
                Ok(line) => {
                    prop_assert!(line.ends_with('\n'));
                    prop_assert!(line.len() <= MAX_LINE + 64);
                    text_bytes += line.len();
                }
                Err(LinkError::Disconnected) => break,
                Err(LinkError::Garbled(_)) | Err(LinkError::TooLong { .. }) => {}
                Err(e) => prop_assert!(false, "unexpected {e}"),
            }
        }
        prop_assert!(text_bytes <= bytes.len());
    }

    /// Any bytes, with or without valid telegrams among them: the decoder yields every intact
    /// telegram, never panics, and never holds more than one telegram's worth.
    #[test]
    fn the_telegram_decoder_survives_any_bytes(
        noise in proptest::collection::vec(any::<u8>(), 0..2048),
        at in any::<prop::sample::Index>(),
        chunk in 1usize..131,
        ranges in proptest::collection::vec(0u16..32_768, 0..400),
    ) {
        let telegram = MeasuredValues::telegram_mm(&ranges, 0).encode().unwrap();
        let split = at.index(noise.len() + 1);
        let mut stream = noise[..split].to_vec();
        stream.extend(&telegram);
        stream.extend(&noise[split..]);
        // The scan also alone, after the noise: whatever the noise did, this one must come out.
        stream.extend(&telegram);
        let mut decoder = TelegramDecoder::new();
        let mut found = 0;
        let mut frames = 0;
        for piece in stream.chunks(chunk) {
            decoder.push(piece);
            while let Some(frame) = decoder.next_frame() {
                frames += 1;
                prop_assert!(frames <= stream.len() + 1, "the decoder loops");
                if let Frame::Telegram(t) = frame
                    && MeasuredValues::from_telegram(&t).map(|v| v.ranges) == Ok(ranges.clone())
                {
                    found += 1;
                }
            }
            prop_assert!(decoder.pending() <= MAX_LENGTH + 6 + chunk);
        }
        prop_assert!(found >= 1, "the intact telegram after the noise is found");
        // Decoding arbitrary bytes directly is an answer, never a panic.
        let _ = Telegram::decode(&noise);
    }
}
