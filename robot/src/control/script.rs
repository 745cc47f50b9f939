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
    /// Move the pan-tilt head to positions `pan` and `tilt` and wait until it has stopped
    /// (`head PAN TILT`).
    Head {
        /// Pan position, 0..=254.
        pan: u8,
        /// Tilt position, 0..=100.
        tilt: u8,
    },
    /// A 3D sweep at one pan (thesis §5.3.2): tilt the laser from `from` to `to` in steps of
    /// `step` positions, one scan at rest at each (`sweep PAN FROM TO STEP`).
    Sweep {
        /// Pan position, 0..=254.
        pan: u8,
        /// First tilt position.
        from: u8,
        /// Last tilt position (may be below `from`: the sweep goes down).
        to: u8,
        /// Positions between scans, at least 1.
        step: u8,
    },
    /// A 3D scene (thesis §4.3, §5.3.1): one scan at rest at every tilt position from `from` to
    /// `to` at one pan, after a level scan of the station for the 2D localisation; the head then
    /// returns where it was (`scene PAN [FROM TO]`, default tilts 0 to 99: the thesis's 100
    /// scans).
    Scene {
        /// Pan position, 0..=254.
        pan: u8,
        /// First tilt position.
        from: u8,
        /// Last tilt position.
        to: u8,
    },
    /// Four scenes at four pans (thesis §5.3.2: 90° apart cover 360° around the robot), after
    /// one level scan of the station (`survey [P1 P2 P3 P4]`, default 0 64 127 191: 90° apart on
    /// a head of 254 positions per turn).
    Survey {
        /// The four pan positions.
        pans: [u8; 4],
    },
    /// Go to a goal in the map frame, metres, avoiding what the laser and the sonar see, with
    /// the scan-matching estimate (`goto X Y`; see [`crate::control::navigate`]).
    Goto {
        /// Goal, map frame, metres.
        x: f64,
        /// Goal, map frame, metres.
        y: f64,
    },
    /// Follow walls on the right for this long, robot time (`explore SECONDS`).
    Explore {
        /// Duration, seconds.
        seconds: f64,
    },
}

/// The tilts of a scene when the step does not say: the thesis's 100 positions.
pub const SCENE_TILTS: (u8, u8) = (0, 99);
/// The pans of a survey when the step does not say: 90° apart on 254 positions per turn.
pub const SURVEY_PANS: [u8; 4] = [0, 64, 127, 191];

/// A step that cannot be parsed or carried out.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The text is not a step.
    #[error(
        "{0}; a step is a firmware command (a535, i78, k5 30 50, v130 130, p, w1000) or move METRES, turn DEGREES, pause SECONDS, head PAN TILT, sweep PAN FROM TO STEP, scene PAN [FROM TO], survey [P1 P2 P3 P4], goto X Y, explore SECONDS"
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
            Step::Pause { .. }
            | Step::Head { .. }
            | Step::Sweep { .. }
            | Step::Scene { .. }
            | Step::Survey { .. }
            | Step::Goto { .. }
            | Step::Explore { .. } => None,
        })
    }

    /// Whether the step drives the pan-tilt head.
    pub fn uses_head(&self) -> bool {
        matches!(
            self,
            Step::Head { .. } | Step::Sweep { .. } | Step::Scene { .. } | Step::Survey { .. }
        )
    }

    /// The tilt positions of a sweep, in order.
    pub fn sweep_tilts(from: u8, to: u8, step: u8) -> Vec<u8> {
        let step = i32::from(step.max(1));
        let (from, to) = (i32::from(from), i32::from(to));
        let dir = if to >= from { 1 } else { -1 };
        let mut tilts = Vec::new();
        let mut t = from;
        while (t - to) * dir <= 0 {
            tilts.push(t as u8);
            t += dir * step;
        }
        tilts
    }
}

/// The longest `pause`, seconds: an hour.
pub const MAX_PAUSE_S: f64 = 3600.0;

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
                const UNIT: &str = "seconds, 0 to 3600";
                let seconds = number("pause", UNIT)?;
                if !(0.0..=MAX_PAUSE_S).contains(&seconds) {
                    return Err(StepError::Number {
                        keyword: "pause",
                        unit: UNIT,
                        text: rest.trim().to_string(),
                    });
                }
                Ok(Step::Pause { seconds })
            }
            "goto" => {
                let bad = || StepError::Number {
                    keyword: "goto",
                    unit: "X Y: the goal in the map frame, metres",
                    text: rest.trim().to_string(),
                };
                let values: Vec<f64> = rest
                    .split_whitespace()
                    .map(|v| {
                        v.parse::<f64>()
                            .ok()
                            .filter(|x| x.is_finite() && x.abs() < 1e6)
                    })
                    .collect::<Option<_>>()
                    .ok_or_else(bad)?;
                match values.as_slice() {
                    &[x, y] => Ok(Step::Goto { x, y }),
                    _ => Err(bad()),
                }
            }
            "explore" => {
                const UNIT: &str = "seconds, 0 to 3600";
                let seconds = number("explore", UNIT)?;
                if !(0.0..=MAX_PAUSE_S).contains(&seconds) {
                    return Err(StepError::Number {
                        keyword: "explore",
                        unit: UNIT,
                        text: rest.trim().to_string(),
                    });
                }
                Ok(Step::Explore { seconds })
            }
            "head" | "sweep" | "scene" | "survey" => {
                use crate::hardware::{PAN_MAX, TILT_MAX};
                let (keyword, unit): (&'static str, &'static str) = match keyword {
                    "head" => ("head", "PAN TILT: positions, pan 0..=254, tilt 0..=100"),
                    "sweep" => (
                        "sweep",
                        "PAN FROM TO STEP: positions, pan 0..=254, tilts 0..=100, step 1..",
                    ),
                    "scene" => (
                        "scene",
                        "PAN [FROM TO]: positions, pan 0..=254, tilts 0..=100",
                    ),
                    _ => ("survey", "[P1 P2 P3 P4]: four pan positions 0..=254"),
                };
                let bad = || StepError::Number {
                    keyword,
                    unit,
                    text: rest.trim().to_string(),
                };
                let values: Vec<u8> = rest
                    .split_whitespace()
                    .map(|v| v.parse::<u8>().map_err(|_| bad()))
                    .collect::<Result<_, _>>()?;
                let tilt = |t: u8| t <= TILT_MAX;
                let step = match (keyword, values.as_slice()) {
                    ("head", &[pan, t]) if tilt(t) => Step::Head { pan, tilt: t },
                    ("sweep", &[pan, from, to, step]) if tilt(from) && tilt(to) && step > 0 => {
                        Step::Sweep {
                            pan,
                            from,
                            to,
                            step,
                        }
                    }
                    ("scene", &[pan]) => Step::Scene {
                        pan,
                        from: SCENE_TILTS.0,
                        to: SCENE_TILTS.1,
                    },
                    ("scene", &[pan, from, to]) if tilt(from) && tilt(to) && from != to => {
                        Step::Scene { pan, from, to }
                    }
                    ("survey", &[]) => Step::Survey { pans: SURVEY_PANS },
                    ("survey", &[a, b, c, d]) => Step::Survey { pans: [a, b, c, d] },
                    _ => return Err(bad()),
                };
                let pans: &[u8] = match &step {
                    Step::Head { pan, .. } | Step::Sweep { pan, .. } | Step::Scene { pan, .. } => {
                        std::slice::from_ref(pan)
                    }
                    Step::Survey { pans } => pans,
                    _ => &[],
                };
                if pans.iter().any(|&p| p > PAN_MAX) {
                    return Err(bad());
                }
                Ok(step)
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
            Step::Goto { x, y } => write!(f, "goto {x} {y}"),
            Step::Explore { seconds } => write!(f, "explore {seconds}"),
            Step::Head { pan, tilt } => write!(f, "head {pan} {tilt}"),
            Step::Sweep {
                pan,
                from,
                to,
                step,
            } => write!(f, "sweep {pan} {from} {to} {step}"),
            Step::Scene { pan, from, to } => {
                if (*from, *to) == SCENE_TILTS {
                    write!(f, "scene {pan}")
                } else {
                    write!(f, "scene {pan} {from} {to}")
                }
            }
            Step::Survey { pans } => {
                if *pans == SURVEY_PANS {
                    write!(f, "survey")
                } else {
                    write!(f, "survey {} {} {} {}", pans[0], pans[1], pans[2], pans[3])
                }
            }
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
    fn head_steps_parse_print_and_expand() {
        for text in ["head 64 31", "sweep 127 10 60 5"] {
            let step: Step = text.parse().unwrap();
            assert_eq!(step.to_string(), text);
            assert!(step.uses_head());
            assert_eq!(step.to_line(&G).unwrap(), None);
        }
        assert_eq!(Step::sweep_tilts(10, 20, 5), vec![10, 15, 20]);
        assert_eq!(Step::sweep_tilts(20, 8, 5), vec![20, 15, 10]);
        for bad in [
            "head 300 10",
            "head 10 101",
            "head 10",
            "sweep 1 2 3 0",
            "sweep 1 2 3",
        ] {
            assert!(bad.parse::<Step>().is_err(), "{bad}");
        }
    }

    #[test]
    fn scene_steps_parse_print_and_refuse_bad_positions() {
        assert_eq!(
            "scene 64".parse::<Step>().unwrap(),
            Step::Scene {
                pan: 64,
                from: 0,
                to: 99
            }
        );
        assert_eq!(
            "survey".parse::<Step>().unwrap(),
            Step::Survey { pans: SURVEY_PANS }
        );
        for text in [
            "scene 64",
            "scene 10 100 20",
            "survey",
            "survey 0 60 120 180",
        ] {
            let step: Step = text.parse().unwrap();
            assert_eq!(step.to_string(), text);
            assert!(step.uses_head());
            assert_eq!(step.to_line(&G).unwrap(), None);
        }
        for bad in [
            "scene",
            "scene 255",
            "scene 1 2",
            "scene 1 5 5",
            "scene 1 0 101",
            "survey 1 2 3",
            "survey 0 0 0 300",
        ] {
            assert!(bad.parse::<Step>().is_err(), "{bad}");
        }
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
    fn navigation_steps_parse_print_and_refuse_bad_numbers() {
        assert_eq!(
            "goto 3.5 -1".parse::<Step>().unwrap(),
            Step::Goto { x: 3.5, y: -1.0 }
        );
        assert_eq!(
            "explore 60".parse::<Step>().unwrap(),
            Step::Explore { seconds: 60.0 }
        );
        for bad in [
            "goto 1",
            "goto 1 2 3",
            "goto x 2",
            "goto NaN 1",
            "explore -1",
            "explore",
        ] {
            let e = bad.parse::<Step>().unwrap_err().to_string();
            assert!(e.contains(bad.split(' ').next().unwrap()), "{bad}: {e}");
        }
        for text in ["goto 3.5 -1", "explore 60"] {
            assert_eq!(text.parse::<Step>().unwrap().to_string(), text);
        }
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
