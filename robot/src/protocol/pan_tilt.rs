//! The pan-tilt microcontroller's commands and replies, as bytes (thesis App. A.2.2, and the
//! firmware code of App. A.3.2 where the two differ).
//!
//! `g c` and `e c` move to absolute positions, `k`/`K` set the pan and tilt ramps, `w ms Fg Fe`
//! waits, `l` reports nine fields. Every command but `w` answers its letter at once; `w` answers
//! `w` when the wait ends. At power-up the unit greets, homes while narrating on the line, and
//! ends with [`READY`].

use super::base::ReplyError;
use crate::hardware::{ArgumentError, PanTiltCommand, PanTiltStatus, PanTiltWait};
use crate::time::Stamp;

/// The status request.
pub const STATUS_REQUEST: &str = "l\n";

/// The last line of the power-up homing.
pub const READY: &str = "Listo\n";

/// The wire form of a command, newline included. Fails when an argument is out of range.
///
/// ```
/// use robot::hardware::{PanTiltCommand, Ramp};
/// use robot::protocol::pan_tilt::encode_command;
/// assert_eq!(encode_command(&PanTiltCommand::Pan(127)).unwrap(), "g127\n");
/// assert_eq!(encode_command(&PanTiltCommand::Tilt(31)).unwrap(), "e31\n");
/// let ramp = Ramp { initial: 3, top: 50, period_ms: 30 };
/// assert_eq!(encode_command(&PanTiltCommand::TiltRamp(ramp)).unwrap(), "K3 50 30\n");
/// assert!(encode_command(&PanTiltCommand::Tilt(120)).is_err());
/// ```
pub fn encode_command(command: &PanTiltCommand) -> Result<String, ArgumentError> {
    command.validate()?;
    let letter = command.letter();
    Ok(match *command {
        PanTiltCommand::Pan(c) | PanTiltCommand::Tilt(c) => format!("{letter}{c}\n"),
        PanTiltCommand::PanRamp(r) | PanTiltCommand::TiltRamp(r) => {
            format!("{letter}{} {} {}\n", r.initial, r.top, r.period_ms)
        }
    })
}

/// The wire form of a wait: `w ms` without flags, `w ms Fg Fe` with any (the firmware honours
/// the flags only with exactly three arguments).
///
/// ```
/// use robot::hardware::PanTiltWait;
/// use robot::protocol::pan_tilt::encode_wait;
/// assert_eq!(encode_wait(&PanTiltWait { max_ms: 500, pan: false, tilt: false }), "w500\n");
/// assert_eq!(encode_wait(&PanTiltWait { max_ms: 500, pan: true, tilt: false }), "w500 1 0\n");
/// ```
pub fn encode_wait(wait: &PanTiltWait) -> String {
    if wait.pan || wait.tilt {
        format!(
            "w{} {} {}\n",
            wait.max_ms,
            u8::from(wait.pan),
            u8::from(wait.tilt)
        )
    } else {
        format!("w{}\n", wait.max_ms)
    }
}

/// Parses the status reply `l abs_giro g_giro_clicks abs_elev g_elev_clicks TopeIzq TopeDer
/// TopeInf Eg Ee` (signed decimals and flags).
///
/// ```
/// use robot::protocol::pan_tilt::parse_status;
/// use robot::Stamp;
/// let s = parse_status("l12 -36 31 0 0 0 0 1 0\n", Stamp::ZERO).unwrap();
/// assert_eq!((s.pan, s.pan_clicks, s.tilt), (12, -36, 31));
/// assert!(s.pan_on && !s.tilt_on && !s.lower_limit);
/// assert!(parse_status("l12 -36 31\n", Stamp::ZERO).is_err());
/// ```
pub fn parse_status(line: &str, stamp: Stamp) -> Result<PanTiltStatus, ReplyError> {
    let bad = |expected| ReplyError::new('l', expected, line);
    let fields =
        super::reply_fields(line, 'l').ok_or_else(|| bad("a line `l…` ending in a newline"))?;
    let [pan, pan_clicks, tilt, tilt_clicks, izq, der, inf, eg, ee] = fields[..] else {
        return Err(bad(
            "nine fields `abs_giro g_giro_clicks abs_elev g_elev_clicks TopeIzq TopeDer TopeInf Eg Ee`",
        ));
    };
    let number = |f: &str| -> Result<i16, ReplyError> {
        let digits = f.strip_prefix('-').unwrap_or(f);
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return Err(bad("signed decimal positions and clicks"));
        }
        f.parse()
            .map_err(|_| bad("positions and clicks in -32768..=32767"))
    };
    let flag = |f: &str| super::parse_flag(f).ok_or_else(|| bad("switch and motor flags 0 or 1"));
    Ok(PanTiltStatus {
        stamp,
        pan: number(pan)?,
        pan_clicks: number(pan_clicks)?,
        tilt: number(tilt)?,
        tilt_clicks: number(tilt_clicks)?,
        left_limit: flag(izq)?,
        right_limit: flag(der)?,
        lower_limit: flag(inf)?,
        pan_on: flag(eg)?,
        tilt_on: flag(ee)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn garbled_status_lines_are_rejected_with_the_line() {
        for line in [
            "l1 2 3 4 5 6 7 8 9\n",
            "l1 2 3 4 0 0 0 0\n",
            "x1 2 3 4 0 0 0 0 0\n",
            "l1 2 3 4 0 0 0 0 0",
            "l1 2 + 4 0 0 0 0 0\n",
            "l99999 2 3 4 0 0 0 0 0\n",
        ] {
            let err = parse_status(line, Stamp::ZERO).unwrap_err();
            assert_eq!(err.command, 'l');
            assert_eq!(err.got, line.trim_end());
        }
    }
}
