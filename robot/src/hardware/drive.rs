//! Types of the drive base: the commands of the base microcontroller (thesis App. A.2.1 and the
//! firmware's `do_command`) and its status report.

use crate::time::Stamp;
use core::fmt;

/// Largest wheel speed magnitude the firmware documents, in encoder counts per control tick
/// (`k` and `v`: "0 stopped, 90 full speed").
pub const WHEEL_SPEED_LIMIT: u16 = 90;

/// The status report carries each counter as `turns.hundredths` with `turns` an unsigned 16-bit
/// number, so counts wrap at 65 536 × 100.
pub const STATUS_COUNT_MODULUS: u32 = 6_553_600;

/// The acceleration ramp of the next motion command (`k Pi Pf Tc`).
///
/// The firmware starts a move at `initial` counts per tick and raises the desired speed by one
/// count per tick every `period_ms` ticks until `top`, then lowers it the same way when braking.
/// (The firmware's timer reloads with `period_ms` and acts when it has counted down, so one step
/// takes `period_ms + 1` ticks of 1.024 ms — see `ac_control` in App. A.)
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct Ramp {
    /// Desired speed at the start of a move, counts per tick (`Pi`, 0..=90).
    pub initial: u16,
    /// Top desired speed, counts per tick (`Pf`, 0..=90).
    pub top: u16,
    /// Ticks between two speed steps (`Tc`).
    pub period_ms: u16,
}

impl Ramp {
    /// The power-on ramp, `k5 30 50`.
    pub const POWER_ON: Ramp = Ramp {
        initial: 5,
        top: 30,
        period_ms: 50,
    };
}

impl Default for Ramp {
    fn default() -> Self {
        Ramp::POWER_ON
    }
}

/// One command of the base microcontroller that answers with its letter at once.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum DriveCommand {
    /// `a c`: forward, each wheel `c` tenths of a motor turn.
    Advance(u16),
    /// `r c`: backward, each wheel `c` tenths of a motor turn.
    Retreat(u16),
    /// `i c`: turn left in place (left wheel back, right forward), `c` tenths per wheel.
    TurnLeft(u16),
    /// `d c`: turn right in place (left wheel forward, right back), `c` tenths per wheel.
    TurnRight(u16),
    /// `v l r`: wheel speeds in counts per tick, sent offset by +100 on the wire.
    WheelSpeeds {
        /// Left wheel speed; negative runs the wheel backward.
        left: i16,
        /// Right wheel speed; negative runs the wheel backward.
        right: i16,
    },
    /// `p`: stop both drive motors (they brake).
    Stop,
    /// `k Pi Pf Tc`: the acceleration ramp of the next motion.
    Ramp(Ramp),
    /// `z F`: the buzzer on or off.
    Buzzer(bool),
}

impl DriveCommand {
    /// The command's letter on the wire.
    pub fn letter(&self) -> char {
        match self {
            DriveCommand::Advance(_) => 'a',
            DriveCommand::Retreat(_) => 'r',
            DriveCommand::TurnLeft(_) => 'i',
            DriveCommand::TurnRight(_) => 'd',
            DriveCommand::WheelSpeeds { .. } => 'v',
            DriveCommand::Stop => 'p',
            DriveCommand::Ramp(_) => 'k',
            DriveCommand::Buzzer(_) => 'z',
        }
    }

    /// Whether the firmware resets its wheel counters on this command (`a r i d`).
    pub fn resets_counters(&self) -> bool {
        matches!(
            self,
            DriveCommand::Advance(_)
                | DriveCommand::Retreat(_)
                | DriveCommand::TurnLeft(_)
                | DriveCommand::TurnRight(_)
        )
    }

    /// Checks the arguments against the ranges the firmware documents.
    ///
    /// ```
    /// use robot::hardware::{DriveCommand, Ramp};
    /// assert!(DriveCommand::Advance(535).validate().is_ok());
    /// let err = DriveCommand::Ramp(Ramp { initial: 5, top: 120, period_ms: 50 }).validate().unwrap_err();
    /// assert_eq!(err.to_string(), "`k` argument Pf = 120 is out of range: expected 0..=90");
    /// ```
    pub fn validate(&self) -> Result<(), ArgumentError> {
        let limit = i64::from(WHEEL_SPEED_LIMIT);
        match *self {
            DriveCommand::WheelSpeeds { left, right } => {
                ArgumentError::check('v', "left", left.into(), -limit, limit)?;
                ArgumentError::check('v', "right", right.into(), -limit, limit)
            }
            DriveCommand::Ramp(ramp) => {
                ArgumentError::check('k', "Pi", ramp.initial.into(), 0, limit)?;
                ArgumentError::check('k', "Pf", ramp.top.into(), 0, limit)
            }
            _ => Ok(()),
        }
    }
}

/// The firmware's `w ms [Fi Fd Fs]`: wait for idle motors (and sonar) with a time limit.
///
/// The firmware only honours the flags when all three are sent (`w ms Fi Fd Fs`); with fewer
/// arguments it simply waits `ms` ticks. The encoder sends the long form whenever a flag is set.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct DriveWait {
    /// Longest wait, in control ticks of 1.024 ms (the firmware calls them milliseconds).
    pub max_ms: u16,
    /// Wait for the left drive motor to be off.
    pub left: bool,
    /// Wait for the right drive motor to be off.
    pub right: bool,
    /// Wait for the sonar firing sequence to complete.
    pub sonar: bool,
}

impl DriveWait {
    /// Wait until both drive motors are off, at most `max_ms`.
    pub const fn motors(max_ms: u16) -> Self {
        DriveWait {
            max_ms,
            left: true,
            right: true,
            sonar: false,
        }
    }

    /// Just wait `ms` (`w ms`).
    pub const fn sleep(ms: u16) -> Self {
        DriveWait {
            max_ms: ms,
            left: false,
            right: false,
            sonar: false,
        }
    }

    /// Whether any flag is set (the long form goes on the wire).
    pub fn has_flags(&self) -> bool {
        self.left || self.right || self.sonar
    }
}

/// The base's status report (`l Ci Cd Ei Ed Es`).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct DriveStatus {
    /// When the firmware took this snapshot.
    pub stamp: Stamp,
    /// Left wheel encoder counts since the last `a r i d` command, modulo
    /// [`STATUS_COUNT_MODULUS`]. Encoders count edges, not direction: the firmware assumes the
    /// commanded direction.
    pub left_counts: u32,
    /// Right wheel encoder counts since the last `a r i d` command (see `left_counts`).
    pub right_counts: u32,
    /// The left drive motor is powered.
    pub left_on: bool,
    /// The right drive motor is powered.
    pub right_on: bool,
    /// The sonar ring is firing.
    pub sonar_firing: bool,
}

impl DriveStatus {
    /// Both drive motors are off: the last motion has ended.
    pub fn is_idle(&self) -> bool {
        !self.left_on && !self.right_on
    }
}

/// An argument outside the range the firmware documents; nothing was sent.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub struct ArgumentError {
    /// The command letter.
    pub command: char,
    /// The argument's name in the thesis's command table.
    pub field: &'static str,
    /// The value given.
    pub value: i64,
    /// The smallest value accepted.
    pub min: i64,
    /// The largest value accepted.
    pub max: i64,
}

impl ArgumentError {
    /// `Ok` when `min <= value <= max`, else the error naming the argument.
    pub fn check(
        command: char,
        field: &'static str,
        value: i64,
        min: i64,
        max: i64,
    ) -> Result<(), ArgumentError> {
        if (min..=max).contains(&value) {
            Ok(())
        } else {
            Err(ArgumentError {
                command,
                field,
                value,
                min,
                max,
            })
        }
    }
}

impl fmt::Display for ArgumentError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "`{}` argument {} = {} is out of range: expected {}..={}",
            self.command, self.field, self.value, self.min, self.max
        )
    }
}
