//! The base microcontroller's commands and replies, as bytes.
//!
//! Encoding follows the thesis's syntax (`a535\n`, `k5 30 50\n`, `v130 130\n`); replies follow the
//! firmware code, which is what the robot does where the prose differs: `r` answers `r` (the prose
//! says `c`), `l` writes each counter as `turns.hundredths` with two decimals, and `w` only
//! honours its flags when all three are sent.

use crate::hardware::{
    ArgumentError, BatteryVoltages, DriveCommand, DriveStatus, DriveWait, Ramp, SonarCommand,
    WHEEL_SPEED_LIMIT,
};
use crate::time::Stamp;

/// The status request.
pub const STATUS_REQUEST: &str = "l\n";

/// The sonar report request.
pub const SONAR_REQUEST: &str = "s\n";

/// The battery request.
pub const BATTERY_REQUEST: &str = "t\n";

/// A reply that is not what the protocol allows for the command sent.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("bad reply to `{command}`: expected {expected}, got {got:?}")]
pub struct ReplyError {
    /// The command letter the reply answers.
    pub command: char,
    /// What the protocol allows.
    pub expected: &'static str,
    /// The line received, without its newline.
    pub got: String,
}

impl ReplyError {
    /// The error for `line` (its newline dropped) answering `command`.
    pub fn new(command: char, expected: &'static str, line: &str) -> Self {
        ReplyError {
            command,
            expected,
            got: line.strip_suffix('\n').unwrap_or(line).to_string(),
        }
    }
}

/// A command line that does not spell a drive command.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CommandTextError {
    /// Empty text.
    #[error("empty command")]
    Empty,
    /// The letter is not a drive command.
    #[error("unknown drive command letter `{0}`: expected one of a r i d v p k z w")]
    UnknownLetter(char),
    /// An argument is not a whole number in the range that argument takes.
    #[error(
        "`{command}` argument {index} ({field}) is {text:?}: expected a whole number {min}..={max}"
    )]
    BadNumber {
        /// The command letter.
        command: char,
        /// Which argument (1-based).
        index: usize,
        /// The argument's name in App. A.
        field: &'static str,
        /// The text found.
        text: String,
        /// The smallest value the argument takes, as written on the line.
        min: i64,
        /// The largest.
        max: i64,
    },
    /// Wrong number of arguments.
    #[error("`{command}` takes {expected}, got {got} argument(s)")]
    Arity {
        /// The command letter.
        command: char,
        /// What it takes.
        expected: &'static str,
        /// How many were given.
        got: usize,
    },
    /// An argument outside its documented range.
    #[error(transparent)]
    Range(#[from] ArgumentError),
}

/// A drive command or a wait, as a script or a terminal user writes it.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum DriveLine {
    /// A command answered at once.
    Command(DriveCommand),
    /// `w`: a wait.
    Wait(DriveWait),
}

/// The wire form of a command, newline included. Fails when an argument is out of range.
///
/// ```
/// use robot::hardware::{DriveCommand, Ramp};
/// use robot::protocol::base::encode_command;
/// assert_eq!(encode_command(&DriveCommand::Advance(535)).unwrap(), "a535\n");
/// assert_eq!(encode_command(&DriveCommand::WheelSpeeds { left: 30, right: -30 }).unwrap(), "v130 70\n");
/// assert_eq!(encode_command(&DriveCommand::Ramp(Ramp::POWER_ON)).unwrap(), "k5 30 50\n");
/// assert_eq!(encode_command(&DriveCommand::Stop).unwrap(), "p\n");
/// ```
pub fn encode_command(command: &DriveCommand) -> Result<String, ArgumentError> {
    command.validate()?;
    let letter = command.letter();
    Ok(match *command {
        DriveCommand::Advance(c)
        | DriveCommand::Retreat(c)
        | DriveCommand::TurnLeft(c)
        | DriveCommand::TurnRight(c) => format!("{letter}{c}\n"),
        DriveCommand::WheelSpeeds { left, right } => {
            format!(
                "{letter}{} {}\n",
                i32::from(left) + 100,
                i32::from(right) + 100
            )
        }
        DriveCommand::Stop => format!("{letter}\n"),
        DriveCommand::Ramp(r) => format!("{letter}{} {} {}\n", r.initial, r.top, r.period_ms),
        DriveCommand::Buzzer(on) => format!("{letter}{}\n", u8::from(on)),
    })
}

/// The wire form of a wait: `w ms` without flags, `w ms Fi Fd Fs` with any.
///
/// ```
/// use robot::hardware::DriveWait;
/// use robot::protocol::base::encode_wait;
/// assert_eq!(encode_wait(&DriveWait::sleep(1000)), "w1000\n");
/// assert_eq!(encode_wait(&DriveWait::motors(10000)), "w10000 1 1 0\n");
/// ```
pub fn encode_wait(wait: &DriveWait) -> String {
    if wait.has_flags() {
        format!(
            "w{} {} {} {}\n",
            wait.max_ms,
            u8::from(wait.left),
            u8::from(wait.right),
            u8::from(wait.sonar)
        )
    } else {
        format!("w{}\n", wait.max_ms)
    }
}

/// The wire form of a sonar command and the letter that acknowledges it.
///
/// ```
/// use robot::hardware::SonarCommand;
/// use robot::protocol::base::encode_sonar;
/// assert_eq!(encode_sonar(&SonarCommand::Sequence(vec![15, 0, 1])).unwrap(), ("S15 0 1\n".to_string(), 'S'));
/// assert_eq!(encode_sonar(&SonarCommand::Firing(true)).unwrap(), ("s1\n".to_string(), 's'));
/// assert_eq!(encode_sonar(&SonarCommand::Timing { echo_ms: 50, relax_ms: 20 }).unwrap().0, "s2 50 20\n");
/// ```
pub fn encode_sonar(command: &SonarCommand) -> Result<(String, char), ArgumentError> {
    command.validate()?;
    Ok(match command {
        SonarCommand::Sequence(seq) => {
            let list: Vec<String> = seq.iter().map(u8::to_string).collect();
            (format!("S{}\n", list.join(" ")), 'S')
        }
        SonarCommand::Firing(on) => (format!("s{}\n", u8::from(*on)), 's'),
        SonarCommand::Timing { echo_ms, relax_ms } => (format!("s2 {echo_ms} {relax_ms}\n"), 's'),
    })
}

/// Parses the sonar report: as `sonar_report` writes it, `s` then one echo time per line for
/// each of the `count` positions of the firing sequence (the prose shows them on one line; the
/// code prints a newline after each).
///
/// ```
/// use robot::protocol::base::parse_sonar_report;
/// assert_eq!(parse_sonar_report(&["s1634\n", "1779\n", "65535\n"], 3).unwrap(), vec![1634, 1779, 65535]);
/// assert!(parse_sonar_report(&["s1634\n"], 3).is_err());
/// ```
pub fn parse_sonar_report(lines: &[&str], count: usize) -> Result<Vec<u16>, ReplyError> {
    let bad = |expected, got: &str| ReplyError {
        command: 's',
        expected,
        got: got.trim_end().to_string(),
    };
    if lines.len() != count {
        return Err(bad("one line per sonar of the sequence", &lines.concat()));
    }
    lines
        .iter()
        .enumerate()
        .map(|(i, line)| {
            let body = line
                .strip_suffix('\n')
                .ok_or_else(|| bad("lines ending in a newline", line))?;
            let body = if i == 0 {
                body.strip_prefix('s')
                    .ok_or_else(|| bad("`s` before the first echo time", line))?
            } else {
                body
            };
            parse_digits(body).ok_or_else(|| bad("echo times 0..=65535", line))
        })
        .collect()
}

/// Checks a one-letter acknowledgement (`a\n` answers `a`, and so on).
pub fn parse_ack(line: &str, command: char) -> Result<(), ReplyError> {
    let body = line.strip_suffix('\n').unwrap_or(line);
    let mut chars = body.chars();
    if chars.next() == Some(command) && chars.next().is_none() {
        Ok(())
    } else {
        Err(ReplyError {
            command,
            expected: "the command letter alone",
            got: body.to_string(),
        })
    }
}

/// Parses the status reply `l Ci Cd Ei Ed Es` (counters as `turns.hundredths`).
///
/// ```
/// use robot::protocol::base::parse_status;
/// use robot::Stamp;
/// let s = parse_status("l10.03 9.98 1 1 0\n", Stamp::ZERO).unwrap();
/// assert_eq!((s.left_counts, s.right_counts), (1003, 998));
/// assert!(s.left_on && s.right_on && !s.sonar_firing);
/// ```
pub fn parse_status(line: &str, stamp: Stamp) -> Result<DriveStatus, ReplyError> {
    let bad = |expected| ReplyError::new('l', expected, line);
    let fields =
        super::reply_fields(line, 'l').ok_or_else(|| bad("a line `l…` ending in a newline"))?;
    let [left, right, el, er, es] = fields[..] else {
        return Err(bad("five fields `Ci Cd Ei Ed Es`"));
    };
    let counts = |f: &str| -> Result<u32, ReplyError> {
        let (turns, hundredths) = f
            .split_once('.')
            .ok_or_else(|| bad("counters as turns.hh"))?;
        let turns: u16 = parse_digits(turns).ok_or_else(|| bad("counters as turns.hh"))?;
        if hundredths.len() != 2 {
            return Err(bad("two decimals in the counters"));
        }
        let hundredths: u16 =
            parse_digits(hundredths).ok_or_else(|| bad("counters as turns.hh"))?;
        Ok(u32::from(turns) * 100 + u32::from(hundredths))
    };
    let flag = |f: &str| super::parse_flag(f).ok_or_else(|| bad("motor and sonar flags 0 or 1"));
    Ok(DriveStatus {
        stamp,
        left_counts: counts(left)?,
        right_counts: counts(right)?,
        left_on: flag(el)?,
        right_on: flag(er)?,
        sonar_firing: flag(es)?,
    })
}

/// Parses the battery reply `t Bat12 Bat24 Bat12M Bat24M` (millivolts).
///
/// ```
/// use robot::protocol::base::parse_battery;
/// use robot::Stamp;
/// let b = parse_battery("t12716 25394 12859 25837\n", Stamp::ZERO).unwrap();
/// assert_eq!(b.motor_24_mv, 25837);
/// ```
pub fn parse_battery(line: &str, stamp: Stamp) -> Result<BatteryVoltages, ReplyError> {
    let bad = || ReplyError::new('t', "`t` and four millivolt values", line);
    let values: Vec<u16> = super::reply_fields(line, 't')
        .ok_or_else(bad)?
        .into_iter()
        .map(|f| parse_digits(f).ok_or_else(bad))
        .collect::<Result<_, _>>()?;
    let [logic_12_mv, logic_24_mv, motor_12_mv, motor_24_mv] = values[..] else {
        return Err(bad());
    };
    Ok(BatteryVoltages {
        stamp,
        logic_12_mv,
        logic_24_mv,
        motor_12_mv,
        motor_24_mv,
    })
}

/// The name and range of a drive command's argument `index` (1-based) as written on the line
/// (App. A): the ramp's speeds and the wheel speeds (offset +100 on the wire) are bounded by the
/// firmware's speed limit, flags are 0 or 1, everything else is a 16-bit count.
fn argument_range(letter: char, index: usize) -> (&'static str, i64, i64) {
    let limit = i64::from(WHEEL_SPEED_LIMIT);
    let count = i64::from(u16::MAX);
    match (letter, index) {
        ('k', 1) => ("Pi", 0, limit),
        ('k', 2) => ("Pf", 0, limit),
        ('k', _) => ("period ms", 0, count),
        ('v', 1) => ("left + 100", 100 - limit, 100 + limit),
        ('v', _) => ("right + 100", 100 - limit, 100 + limit),
        ('z', _) => ("F", 0, 1),
        ('w', 1) => ("ms", 0, count),
        ('w', 2) => ("Fi", 0, 1),
        ('w', 3) => ("Fd", 0, 1),
        ('w', _) => ("Fs", 0, 1),
        _ => ("c", 0, count),
    }
}

/// Parses a command as written in a script or typed at a terminal: `a535`, `k5 30 50`,
/// `v130 130` (offset +100 as on the wire), `w1000 1 1 0`. A trailing newline is allowed.
///
/// ```
/// use robot::hardware::{DriveCommand, DriveWait};
/// use robot::protocol::base::{parse_command_text, DriveLine};
/// assert_eq!(parse_command_text("i78").unwrap(), DriveLine::Command(DriveCommand::TurnLeft(78)));
/// assert_eq!(parse_command_text("v130 70").unwrap(),
///            DriveLine::Command(DriveCommand::WheelSpeeds { left: 30, right: -30 }));
/// assert_eq!(parse_command_text("w500 1 1 0").unwrap(), DriveLine::Wait(DriveWait::motors(500)));
/// assert!(parse_command_text("a70000").is_err());
/// ```
pub fn parse_command_text(text: &str) -> Result<DriveLine, CommandTextError> {
    let text = text.trim();
    let mut chars = text.chars();
    let letter = chars.next().ok_or(CommandTextError::Empty)?;
    if !"aridvpkzw".contains(letter) {
        return Err(CommandTextError::UnknownLetter(letter));
    }
    let rest = chars.as_str().trim();
    let args: Vec<u16> = if rest.is_empty() {
        Vec::new()
    } else {
        rest.split_whitespace()
            .enumerate()
            .map(|(i, t)| {
                parse_digits(t).ok_or_else(|| {
                    let (field, min, max) = argument_range(letter, i + 1);
                    CommandTextError::BadNumber {
                        command: letter,
                        index: i + 1,
                        field,
                        text: t.to_string(),
                        min,
                        max,
                    }
                })
            })
            .collect::<Result<_, _>>()?
    };
    // Each argument against its own range, in the form it was written (a wheel speed with its
    // +100 offset), so the message speaks of what the user typed.
    for (i, &v) in args.iter().enumerate() {
        let (field, min, max) = argument_range(letter, i + 1);
        if !(min..=max).contains(&i64::from(v)) {
            return Err(CommandTextError::BadNumber {
                command: letter,
                index: i + 1,
                field,
                text: v.to_string(),
                min,
                max,
            });
        }
    }
    let arity = |expected: &'static str, ok: bool| {
        if ok {
            Ok(())
        } else {
            Err(CommandTextError::Arity {
                command: letter,
                expected,
                got: args.len(),
            })
        }
    };
    let flag = |v: u16, field: &'static str| -> Result<bool, CommandTextError> {
        ArgumentError::check(letter, field, v.into(), 0, 1)?;
        Ok(v == 1)
    };
    let command = match letter {
        'a' | 'r' | 'i' | 'd' => {
            arity("one argument", args.len() == 1)?;
            let c = args[0];
            match letter {
                'a' => DriveCommand::Advance(c),
                'r' => DriveCommand::Retreat(c),
                'i' => DriveCommand::TurnLeft(c),
                _ => DriveCommand::TurnRight(c),
            }
        }
        'v' => {
            arity("two arguments", args.len() == 2)?;
            DriveCommand::WheelSpeeds {
                left: (i32::from(args[0]) - 100) as i16,
                right: (i32::from(args[1]) - 100) as i16,
            }
        }
        'p' => {
            arity("no arguments", args.is_empty())?;
            DriveCommand::Stop
        }
        'k' => {
            arity("three arguments", args.len() == 3)?;
            DriveCommand::Ramp(Ramp {
                initial: args[0],
                top: args[1],
                period_ms: args[2],
            })
        }
        'z' => {
            arity("one argument", args.len() == 1)?;
            DriveCommand::Buzzer(flag(args[0], "F")?)
        }
        'w' => {
            arity("one or four arguments", args.len() == 1 || args.len() == 4)?;
            let wait = if args.len() == 4 {
                DriveWait {
                    max_ms: args[0],
                    left: flag(args[1], "Fi")?,
                    right: flag(args[2], "Fd")?,
                    sonar: flag(args[3], "Fs")?,
                }
            } else {
                DriveWait::sleep(args[0])
            };
            return Ok(DriveLine::Wait(wait));
        }
        other => return Err(CommandTextError::UnknownLetter(other)),
    };
    command.validate()?;
    Ok(DriveLine::Command(command))
}

/// A non-empty string of ASCII digits that fits in `u16`.
fn parse_digits(text: &str) -> Option<u16> {
    if text.is_empty() || !text.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    text.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_command_round_trips_through_text() {
        let commands = [
            DriveCommand::Advance(535),
            DriveCommand::Retreat(0),
            DriveCommand::TurnLeft(65535),
            DriveCommand::TurnRight(78),
            DriveCommand::WheelSpeeds {
                left: -90,
                right: 90,
            },
            DriveCommand::Stop,
            DriveCommand::Ramp(Ramp {
                initial: 1,
                top: 5,
                period_ms: 50,
            }),
            DriveCommand::Buzzer(true),
        ];
        for c in commands {
            let wire = encode_command(&c).unwrap();
            assert_eq!(
                parse_command_text(&wire).unwrap(),
                DriveLine::Command(c),
                "{wire:?}"
            );
        }
    }

    #[test]
    fn status_rejects_malformed_lines() {
        for bad in [
            "l10.0 9.98 1 1 0\n",
            "l10.03 9.98 1 1\n",
            "l10.03 9.98 1 1 2\n",
            "x10.03 9.98 1 1 0\n",
            "l10.03 9.98 1 1 0",
            "l70000.00 0.00 0 0 0\n",
            "l-1.00 0.00 0 0 0\n",
        ] {
            assert!(parse_status(bad, Stamp::ZERO).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn status_reads_single_digit_hundredths_as_written_by_report_clicks() {
        // report_clicks writes a '0' before hundredths below ten.
        let s = parse_status("l0.05 65535.99 0 0 1\n", Stamp::ZERO).unwrap();
        assert_eq!(s.left_counts, 5);
        assert_eq!(s.right_counts, 6_553_599);
        assert!(s.sonar_firing && s.is_idle());
    }

    #[test]
    fn out_of_range_arguments_name_the_field() {
        let err = parse_command_text("v300 100").unwrap_err();
        assert_eq!(
            err.to_string(),
            "`v` argument 1 (left + 100) is \"300\": expected a whole number 10..=190"
        );
        let err = parse_command_text("a 5x").unwrap_err();
        assert!(
            err.to_string().contains("argument 1 (c) is \"5x\""),
            "{err}"
        );
        assert!(matches!(
            parse_command_text("q"),
            Err(CommandTextError::UnknownLetter('q'))
        ));
    }

    #[test]
    fn acknowledgements() {
        assert!(parse_ack("a\n", 'a').is_ok());
        assert!(parse_ack("c\n", 'r').is_err());
        assert!(parse_ack("aa\n", 'a').is_err());
    }
}
