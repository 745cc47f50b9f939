//! One step of a tour, as written in a scenario file.
//!
//! A step is either a firmware command spelled as on the wire (`a535`, `i78`, `k5 30 50`,
//! `v130 130`, `p`, `w1000`) or a step in SI units that the robot turns into one:
//! `move 0.5` (metres, negative backward), `turn -25` (degrees, positive to the left) and
//! `pause 2` (seconds of scanning without commanding anything).

use crate::drive_geometry::DriveGeometry;
use crate::protocol::base::{CommandTextError, DriveLine, parse_command_text};
use core::fmt;
use core::str::FromStr;

/// One step of a tour.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Step {
    /// A firmware command or wait, sent as is. Motions (`a r i d`) are followed to their end.
    Firmware(DriveLine),
    /// A straight move, metres (negative backward).
    Move {
        /// Distance, metres.
        metres: f64,
    },
    /// A turn in place, degrees (positive counter-clockwise, to the left).
    Turn {
        /// Angle, degrees.
        degrees: f64,
    },
    /// Keep reading scans and odometry for this long without commanding anything.
    Pause {
        /// Duration, seconds.
        seconds: f64,
    },
}

/// A step that cannot be parsed or carried out.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The text is not a step.
    #[error(
        "{0}; a step is a firmware command (a535, i78, k5 30 50, v130 130, p, w1000) or move METRES, turn DEGREES, pause SECONDS"
    )]
    Command(#[from] CommandTextError),
    /// A number of an SI step is missing or not finite.
    #[error("`{keyword}` needs one finite number ({unit}), got {text:?}")]
    Number {
        /// The step keyword.
        keyword: &'static str,
        /// The unit expected.
        unit: &'static str,
        /// The text found.
        text: String,
    },
    /// A move or turn too long for the firmware's 16-bit argument.
    #[error("{0} does not fit in one firmware command (at most 65535 tenths of a motor turn)")]
    TooLong(String),
}

impl Step {
    /// The firmware line this step sends, or `None` for a pause.
    pub fn to_line(&self, geometry: &DriveGeometry) -> Result<Option<DriveLine>, StepError> {
        use crate::hardware::DriveCommand as C;
        let too_long = || StepError::TooLong(self.to_string());
        Ok(match *self {
            Step::Firmware(line) => Some(line),
            Step::Move { metres } => {
                let tenths = geometry.tenths_for_distance(metres).ok_or_else(too_long)?;
                Some(DriveLine::Command(if metres >= 0.0 {
                    C::Advance(tenths)
                } else {
                    C::Retreat(tenths)
                }))
            }
            Step::Turn { degrees } => {
                let tenths = geometry
                    .tenths_for_turn(degrees.to_radians())
                    .ok_or_else(too_long)?;
                Some(DriveLine::Command(if degrees >= 0.0 {
                    C::TurnLeft(tenths)
                } else {
                    C::TurnRight(tenths)
                }))
            }
            Step::Pause { .. } => None,
        })
    }
}

impl FromStr for Step {
    type Err = StepError;

    /// ```
    /// use robot::control::Step;
    /// assert_eq!("move -0.5".parse::<Step>().unwrap(), Step::Move { metres: -0.5 });
    /// assert_eq!("turn 25".parse::<Step>().unwrap(), Step::Turn { degrees: 25.0 });
    /// assert!("a535".parse::<Step>().is_ok());
    /// assert!("move fast".parse::<Step>().is_err());
    /// ```
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let text = text.trim();
        let (keyword, rest) = text.split_once(char::is_whitespace).unwrap_or((text, ""));
        let number = |keyword: &'static str, unit: &'static str| {
            rest.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| StepError::Number {
                    keyword,
                    unit,
                    text: rest.trim().to_string(),
                })
        };
        match keyword {
            "move" => Ok(Step::Move {
                metres: number("move", "metres")?,
            }),
            "turn" => Ok(Step::Turn {
                degrees: number("turn", "degrees")?,
            }),
            "pause" => {
                let seconds = number("pause", "seconds, not negative")?;
                if seconds < 0.0 {
                    return Err(StepError::Number {
                        keyword: "pause",
                        unit: "seconds, not negative",
                        text: rest.trim().to_string(),
                    });
                }
                Ok(Step::Pause { seconds })
            }
            _ => Ok(Step::Firmware(parse_command_text(text)?)),
        }
    }
}

impl fmt::Display for Step {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use crate::protocol::base::{encode_command, encode_wait};
        match self {
            Step::Firmware(DriveLine::Command(c)) => match encode_command(c) {
                Ok(line) => write!(f, "{}", line.trim_end()),
                Err(_) => write!(f, "{c:?}"),
            },
            Step::Firmware(DriveLine::Wait(w)) => write!(f, "{}", encode_wait(w).trim_end()),
            Step::Move { metres } => write!(f, "move {metres}"),
            Step::Turn { degrees } => write!(f, "turn {degrees}"),
            Step::Pause { seconds } => write!(f, "pause {seconds}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hardware::DriveCommand;

    const G: DriveGeometry = crate::drive_geometry::TEST_GEOMETRY;

    #[test]
    fn si_steps_become_firmware_commands() {
        let back = "move -0.5".parse::<Step>().unwrap().to_line(&G).unwrap();
        assert_eq!(back, Some(DriveLine::Command(DriveCommand::Retreat(535))));
        let right = "turn -90".parse::<Step>().unwrap().to_line(&G).unwrap();
        assert!(matches!(
            right,
            Some(DriveLine::Command(DriveCommand::TurnRight(_)))
        ));
        assert_eq!(
            "pause 1".parse::<Step>().unwrap().to_line(&G).unwrap(),
            None
        );
    }

    #[test]
    fn errors_explain_what_a_step_is() {
        let e = "jump 3".parse::<Step>().unwrap_err().to_string();
        assert!(
            e.contains("unknown drive command letter `j`") && e.contains("move METRES"),
            "{e}"
        );
        assert!("pause -1".parse::<Step>().is_err());
        assert!(matches!(
            "move 100".parse::<Step>().unwrap().to_line(&G),
            Err(StepError::TooLong(_))
        ));
    }

    #[test]
    fn display_round_trips() {
        for text in [
            "a535",
            "k5 30 50",
            "w1000 1 1 0",
            "move 0.5",
            "turn -25",
            "pause 2",
        ] {
            assert_eq!(text.parse::<Step>().unwrap().to_string(), text);
        }
    }
}
