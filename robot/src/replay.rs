//! The third backend of the hardware contract: a recording played back.
//!
//! [`Taped`] wraps any backend (the twin's `SimRobot`, the real robot's `SerialRobot`) and notes
//! every call made through the contract with its answer — an [`Exchange`] — in order: the
//! motions commanded, each status report, each scan with its stamp, each error. [`ReplayRobot`]
//! implements the contract from such a tape: each call is answered with the recorded answer,
//! after checking that it is the call that was recorded. A controller and a localiser run on it
//! exactly as they ran on the robot — the same decisions, the same estimate to the last bit — and
//! a controller that decides differently is stopped at its first different call, named with the
//! call the tape expected.

use crate::hardware::{
    Batteries, BatteryVoltages, DriveBase, DriveCommand, DriveStatus, DriveWait, ErrorKind,
    Hardware, HardwareError, Laser, LaserScan, PanTilt, PanTiltCommand, PanTiltStatus, PanTiltWait,
    SonarCommand, SonarEchoes, SonarRing,
};
use crate::time::Stamp;
use core::time::Duration;
use serde::{Deserialize, Serialize};

/// One call through the contract.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "call", rename_all = "snake_case")]
pub enum Call {
    /// [`DriveBase::drive`].
    Drive {
        /// The command.
        command: DriveCommand,
    },
    /// [`DriveBase::wait_drive`].
    WaitDrive {
        /// The wait.
        wait: DriveWait,
    },
    /// [`DriveBase::drive_status`].
    DriveStatus,
    /// [`Laser::read_scan`].
    ReadScan {
        /// Its timeout, nanoseconds.
        timeout_ns: u64,
    },
    /// [`Laser::read_scan_since`].
    ReadScanSince {
        /// The earliest stamp wanted.
        since: Stamp,
        /// Its timeout, nanoseconds.
        timeout_ns: u64,
    },
    /// [`SonarRing::sonar`].
    Sonar {
        /// The command.
        command: SonarCommand,
    },
    /// [`SonarRing::sonar_echoes`].
    SonarEchoes,
    /// [`PanTilt::pan_tilt`].
    PanTilt {
        /// The command.
        command: PanTiltCommand,
    },
    /// [`PanTilt::wait_pan_tilt`].
    WaitPanTilt {
        /// The wait.
        wait: PanTiltWait,
    },
    /// [`PanTilt::pan_tilt_status`].
    PanTiltStatus,
    /// [`Batteries::battery_voltages`].
    BatteryVoltages,
}

/// What a call returned.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "answer", rename_all = "snake_case")]
pub enum Answer {
    /// A command acknowledged, a wait over.
    Done,
    /// The base's status report.
    DriveStatus {
        /// The report.
        status: DriveStatus,
    },
    /// A scan, or none in time.
    Scan {
        /// The scan.
        scan: Option<LaserScan>,
    },
    /// The sonar ring's report.
    Echoes {
        /// The report.
        echoes: SonarEchoes,
    },
    /// The pan-tilt's status report.
    PanTiltStatus {
        /// The report.
        status: PanTiltStatus,
    },
    /// The battery voltages.
    Voltages {
        /// The report.
        voltages: BatteryVoltages,
    },
    /// The call failed.
    Failed {
        /// How.
        kind: ErrorKind,
        /// The backend's message.
        message: String,
    },
}

/// One call and its answer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Exchange {
    /// The call.
    #[serde(flatten)]
    pub call: Call,
    /// Its answer.
    #[serde(flatten)]
    pub answer: Answer,
}

impl Exchange {
    /// The time the exchange carries: its answer's stamp, if it has one.
    pub fn stamp(&self) -> Option<Stamp> {
        match &self.answer {
            Answer::DriveStatus { status } => Some(status.stamp),
            Answer::Scan { scan } => scan.as_ref().map(|s| s.stamp),
            Answer::Echoes { echoes } => Some(echoes.stamp),
            Answer::PanTiltStatus { status } => Some(status.stamp),
            Answer::Voltages { voltages } => Some(voltages.stamp),
            Answer::Done | Answer::Failed { .. } => None,
        }
    }
}

/// What watches a tape as it is written: called with the backend and each exchange.
pub type Hook<R> = Box<dyn FnMut(&R, &Exchange) + Send>;

/// A backend whose calls are noted on a tape.
pub struct Taped<R> {
    inner: R,
    tape: Vec<Exchange>,
    hook: Option<Hook<R>>,
}

impl<R: core::fmt::Debug> core::fmt::Debug for Taped<R> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Taped")
            .field("inner", &self.inner)
            .field("tape", &self.tape.len())
            .field("hook", &self.hook.is_some())
            .finish()
    }
}

impl<R: Hardware> Taped<R> {
    /// `inner`, with an empty tape.
    pub fn new(inner: R) -> Self {
        Taped {
            inner,
            tape: Vec::new(),
            hook: None,
        }
    }

    /// The same, with `hook` called with the backend and each exchange as it is noted: how a
    /// caller learns, beside the contract, what the backend alone knows at that moment (the
    /// twin's truth when a scan comes back).
    pub fn with_hook(mut self, hook: impl FnMut(&R, &Exchange) + Send + 'static) -> Self {
        self.hook = Some(Box::new(hook));
        self
    }

    /// The backend.
    pub fn inner(&self) -> &R {
        &self.inner
    }

    /// The backend, for what the contract does not cover (a twin's ground truth).
    pub fn inner_mut(&mut self) -> &mut R {
        &mut self.inner
    }

    /// The exchanges so far.
    pub fn tape(&self) -> &[Exchange] {
        &self.tape
    }

    /// The backend and the tape.
    pub fn into_parts(self) -> (R, Vec<Exchange>) {
        (self.inner, self.tape)
    }

    fn note<T>(
        &mut self,
        call: Call,
        result: Result<T, R::Error>,
        answer: impl FnOnce(&T) -> Answer,
    ) -> Result<T, R::Error> {
        let answer = match &result {
            Ok(value) => answer(value),
            Err(e) => Answer::Failed {
                kind: e.kind(),
                message: e.to_string(),
            },
        };
        let exchange = Exchange { call, answer };
        if let Some(hook) = &mut self.hook {
            hook(&self.inner, &exchange);
        }
        self.tape.push(exchange);
        result
    }
}

impl<R: Hardware> Hardware for Taped<R> {
    type Error = R::Error;
}

impl<R: DriveBase> DriveBase for Taped<R> {
    fn drive(&mut self, command: DriveCommand) -> Result<(), Self::Error> {
        let result = self.inner.drive(command);
        self.note(Call::Drive { command }, result, |_| Answer::Done)
    }

    fn wait_drive(&mut self, wait: DriveWait) -> Result<(), Self::Error> {
        let result = self.inner.wait_drive(wait);
        self.note(Call::WaitDrive { wait }, result, |_| Answer::Done)
    }

    fn drive_status(&mut self) -> Result<DriveStatus, Self::Error> {
        let result = self.inner.drive_status();
        self.note(Call::DriveStatus, result, |&status| Answer::DriveStatus {
            status,
        })
    }
}

impl<R: Laser> Laser for Taped<R> {
    fn read_scan(&mut self, timeout: Duration) -> Result<Option<LaserScan>, Self::Error> {
        let result = self.inner.read_scan(timeout);
        let call = Call::ReadScan {
            timeout_ns: timeout.as_nanos() as u64,
        };
        self.note(call, result, |scan| Answer::Scan { scan: scan.clone() })
    }

    fn read_scan_since(
        &mut self,
        since: Stamp,
        timeout: Duration,
    ) -> Result<Option<LaserScan>, Self::Error> {
        let result = self.inner.read_scan_since(since, timeout);
        let call = Call::ReadScanSince {
            since,
            timeout_ns: timeout.as_nanos() as u64,
        };
        self.note(call, result, |scan| Answer::Scan { scan: scan.clone() })
    }
}

impl<R: SonarRing> SonarRing for Taped<R> {
    fn sonar(&mut self, command: SonarCommand) -> Result<(), Self::Error> {
        let result = self.inner.sonar(command.clone());
        self.note(Call::Sonar { command }, result, |_| Answer::Done)
    }

    fn sonar_echoes(&mut self) -> Result<SonarEchoes, Self::Error> {
        let result = self.inner.sonar_echoes();
        self.note(Call::SonarEchoes, result, |echoes| Answer::Echoes {
            echoes: echoes.clone(),
        })
    }
}

impl<R: PanTilt> PanTilt for Taped<R> {
    fn pan_tilt(&mut self, command: PanTiltCommand) -> Result<(), Self::Error> {
        let result = self.inner.pan_tilt(command);
        self.note(Call::PanTilt { command }, result, |_| Answer::Done)
    }

    fn wait_pan_tilt(&mut self, wait: PanTiltWait) -> Result<(), Self::Error> {
        let result = self.inner.wait_pan_tilt(wait);
        self.note(Call::WaitPanTilt { wait }, result, |_| Answer::Done)
    }

    fn pan_tilt_status(&mut self) -> Result<PanTiltStatus, Self::Error> {
        let result = self.inner.pan_tilt_status();
        self.note(Call::PanTiltStatus, result, |&status| {
            Answer::PanTiltStatus { status }
        })
    }
}

impl<R: Batteries> Batteries for Taped<R> {
    fn battery_voltages(&mut self) -> Result<BatteryVoltages, Self::Error> {
        let result = self.inner.battery_voltages();
        self.note(Call::BatteryVoltages, result, |&voltages| {
            Answer::Voltages { voltages }
        })
    }
}

/// Why a replay cannot answer.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ReplayError {
    /// The controller made another call than the one recorded.
    #[error(
        "exchange {index}: the controller called {got:?}, the recording has {expected:?} — it decided differently"
    )]
    Diverged {
        /// Position on the tape, from 0.
        index: usize,
        /// The recorded call.
        expected: Box<Call>,
        /// The call made.
        got: Box<Call>,
    },
    /// The tape ended before the controller did.
    #[error("exchange {index}: the controller called {got:?} after the recording's last exchange")]
    Ended {
        /// Position on the tape, from 0.
        index: usize,
        /// The call made.
        got: Box<Call>,
    },
    /// The recorded call failed on the robot; it fails again, with the robot's message (so a
    /// replay recorded again gives the same tape).
    #[error("{message}")]
    Recorded {
        /// Position on the tape.
        index: usize,
        /// How it failed.
        kind: ErrorKind,
        /// The backend's message.
        message: String,
    },
    /// The recorded answer is not of the call's kind (a corrupt tape).
    #[error("exchange {index}: the recorded answer {answer:?} does not answer {call:?}")]
    Mismatch {
        /// Position on the tape.
        index: usize,
        /// The call.
        call: Box<Call>,
        /// The answer found.
        answer: Box<Answer>,
    },
}

impl HardwareError for ReplayError {
    fn kind(&self) -> ErrorKind {
        match self {
            ReplayError::Recorded { kind, .. } => *kind,
            ReplayError::Diverged { .. } | ReplayError::Mismatch { .. } => ErrorKind::Protocol,
            ReplayError::Ended { .. } => ErrorKind::Disconnected,
        }
    }
}

/// The contract answered from a tape.
#[derive(Clone, Debug)]
pub struct ReplayRobot {
    tape: Vec<Exchange>,
    next: usize,
}

impl ReplayRobot {
    /// A replay of `tape` from its first exchange.
    pub fn new(tape: Vec<Exchange>) -> Self {
        ReplayRobot { tape, next: 0 }
    }

    /// The tape.
    pub fn into_tape(self) -> Vec<Exchange> {
        self.tape
    }

    /// Exchanges answered so far.
    pub fn position(&self) -> usize {
        self.next
    }

    /// Exchanges on the tape.
    pub fn len(&self) -> usize {
        self.tape.len()
    }

    /// Whether the tape is empty.
    pub fn is_empty(&self) -> bool {
        self.tape.is_empty()
    }

    /// The next recorded answer, if `call` is the next recorded call.
    fn answer(&mut self, call: Call) -> Result<Answer, ReplayError> {
        let index = self.next;
        let Some(recorded) = self.tape.get(index) else {
            return Err(ReplayError::Ended {
                index,
                got: Box::new(call),
            });
        };
        if recorded.call != call {
            return Err(ReplayError::Diverged {
                index,
                expected: Box::new(recorded.call.clone()),
                got: Box::new(call),
            });
        }
        self.next += 1;
        match &recorded.answer {
            Answer::Failed { kind, message } => Err(ReplayError::Recorded {
                index,
                kind: *kind,
                message: message.clone(),
            }),
            answer => Ok(answer.clone()),
        }
    }

    fn mismatch(&self, call: Call, answer: Answer) -> ReplayError {
        ReplayError::Mismatch {
            index: self.next - 1,
            call: Box::new(call),
            answer: Box::new(answer),
        }
    }

    fn done(&mut self, call: Call) -> Result<(), ReplayError> {
        match self.answer(call.clone())? {
            Answer::Done => Ok(()),
            other => Err(self.mismatch(call, other)),
        }
    }

    fn scan(&mut self, call: Call) -> Result<Option<LaserScan>, ReplayError> {
        match self.answer(call.clone())? {
            Answer::Scan { scan } => Ok(scan),
            other => Err(self.mismatch(call, other)),
        }
    }
}

impl Hardware for ReplayRobot {
    type Error = ReplayError;
}

impl DriveBase for ReplayRobot {
    fn drive(&mut self, command: DriveCommand) -> Result<(), ReplayError> {
        self.done(Call::Drive { command })
    }

    fn wait_drive(&mut self, wait: DriveWait) -> Result<(), ReplayError> {
        self.done(Call::WaitDrive { wait })
    }

    fn drive_status(&mut self) -> Result<DriveStatus, ReplayError> {
        match self.answer(Call::DriveStatus)? {
            Answer::DriveStatus { status } => Ok(status),
            other => Err(self.mismatch(Call::DriveStatus, other)),
        }
    }
}

impl Laser for ReplayRobot {
    fn read_scan(&mut self, timeout: Duration) -> Result<Option<LaserScan>, ReplayError> {
        self.scan(Call::ReadScan {
            timeout_ns: timeout.as_nanos() as u64,
        })
    }

    fn read_scan_since(
        &mut self,
        since: Stamp,
        timeout: Duration,
    ) -> Result<Option<LaserScan>, ReplayError> {
        self.scan(Call::ReadScanSince {
            since,
            timeout_ns: timeout.as_nanos() as u64,
        })
    }
}

impl SonarRing for ReplayRobot {
    fn sonar(&mut self, command: SonarCommand) -> Result<(), ReplayError> {
        self.done(Call::Sonar { command })
    }

    fn sonar_echoes(&mut self) -> Result<SonarEchoes, ReplayError> {
        match self.answer(Call::SonarEchoes)? {
            Answer::Echoes { echoes } => Ok(echoes),
            other => Err(self.mismatch(Call::SonarEchoes, other)),
        }
    }
}

impl PanTilt for ReplayRobot {
    fn pan_tilt(&mut self, command: PanTiltCommand) -> Result<(), ReplayError> {
        self.done(Call::PanTilt { command })
    }

    fn wait_pan_tilt(&mut self, wait: PanTiltWait) -> Result<(), ReplayError> {
        self.done(Call::WaitPanTilt { wait })
    }

    fn pan_tilt_status(&mut self) -> Result<PanTiltStatus, ReplayError> {
        match self.answer(Call::PanTiltStatus)? {
            Answer::PanTiltStatus { status } => Ok(status),
            other => Err(self.mismatch(Call::PanTiltStatus, other)),
        }
    }
}

impl Batteries for ReplayRobot {
    fn battery_voltages(&mut self) -> Result<BatteryVoltages, ReplayError> {
        match self.answer(Call::BatteryVoltages)? {
            Answer::Voltages { voltages } => Ok(voltages),
            other => Err(self.mismatch(Call::BatteryVoltages, other)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn status(stamp: u64, left: u32) -> DriveStatus {
        DriveStatus {
            stamp: Stamp(stamp),
            left_counts: left,
            right_counts: left,
            left_on: left < 100,
            right_on: left < 100,
            sonar_firing: false,
        }
    }

    fn tape() -> Vec<Exchange> {
        vec![
            Exchange {
                call: Call::Drive {
                    command: DriveCommand::Advance(50),
                },
                answer: Answer::Done,
            },
            Exchange {
                call: Call::DriveStatus,
                answer: Answer::DriveStatus {
                    status: status(5, 40),
                },
            },
            Exchange {
                call: Call::ReadScan { timeout_ns: 1_000 },
                answer: Answer::Failed {
                    kind: ErrorKind::Timeout,
                    message: "no scan".into(),
                },
            },
        ]
    }

    #[test]
    fn the_tape_answers_the_same_calls_and_stops_a_different_one() {
        let mut robot = ReplayRobot::new(tape());
        robot.advance(50).unwrap();
        assert_eq!(robot.drive_status().unwrap(), status(5, 40));
        let err = robot.read_scan(Duration::from_micros(1)).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Timeout, "the recorded failure again");
        assert!(matches!(
            robot.stop().unwrap_err(),
            ReplayError::Ended { index: 3, .. }
        ));
        let mut other = ReplayRobot::new(tape());
        let err = other.advance(60).unwrap_err();
        assert!(err.to_string().contains("Advance(50)"), "{err}");
        assert_eq!(err.kind(), ErrorKind::Protocol);
    }

    #[test]
    fn a_tape_reads_back_from_json_lines() {
        for exchange in tape() {
            let line = serde_json::to_string(&exchange).unwrap();
            let back: Exchange = serde_json::from_str(&line).unwrap();
            assert_eq!(back, exchange, "{line}");
        }
    }

    #[test]
    fn a_replay_records_the_same_tape_again() {
        let mut taped = Taped::new(ReplayRobot::new(tape()));
        taped.advance(50).unwrap();
        taped.drive_status().unwrap();
        taped.read_scan(Duration::from_micros(1)).unwrap_err();
        assert_eq!(taped.tape(), tape().as_slice());
    }
}
