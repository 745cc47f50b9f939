//! Types of the sonar ring (thesis §2.6.2 and the firmware's `sonar_cmd`).

use crate::time::Stamp;

/// Transducers on the ring, numbered counter-clockwise seen from above, 0 at the front.
pub const SONAR_COUNT: usize = 16;

/// One echo-time unit: the firmware's timer runs at the 24 MHz bus clock divided by 128.
pub const SONAR_TIME_UNIT_S: f64 = 128.0 / 24.0e6;

/// The echo time the firmware reports when no echo came back.
pub const SONAR_NO_ECHO: u16 = 65_535;

/// One command of the sonar ring.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum SonarCommand {
    /// `S d0 d1 …`: the firing sequence, up to 16 transducer numbers.
    Sequence(Vec<u8>),
    /// `s1` / `s0`: start or stop firing the sequence continuously.
    Firing(bool),
    /// `s2 Te Tr`: echo wait and relax time, milliseconds (10..=65535 each).
    Timing {
        /// Longest wait for an echo after a shot, ms.
        echo_ms: u16,
        /// Pause after the echo window before the next shot, ms.
        relax_ms: u16,
    },
}

impl SonarCommand {
    /// Checks the arguments against the ranges the firmware documents.
    pub fn validate(&self) -> Result<(), super::ArgumentError> {
        use super::ArgumentError as E;
        match self {
            SonarCommand::Sequence(seq) => {
                E::check('S', "count", seq.len() as i64, 1, SONAR_COUNT as i64)?;
                for &d in seq {
                    E::check('S', "d", d.into(), 0, SONAR_COUNT as i64 - 1)?;
                }
                Ok(())
            }
            SonarCommand::Firing(_) => Ok(()),
            SonarCommand::Timing { echo_ms, relax_ms } => {
                E::check('s', "Te", (*echo_ms).into(), 10, 65_535)?;
                E::check('s', "Tr", (*relax_ms).into(), 10, 65_535)
            }
        }
    }
}

/// The latest echo time of each transducer of the firing sequence (`s` report).
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SonarEchoes {
    /// When the report was taken.
    pub stamp: Stamp,
    /// The transducer fired at each position of the sequence.
    pub sequence: Vec<u8>,
    /// Echo time of each position, in [`SONAR_TIME_UNIT_S`] units; [`SONAR_NO_ECHO`] for none.
    pub times: Vec<u16>,
    /// When each reading was measured (the end of its echo window), or `None` if not measured
    /// since firing started. The firmware does not report it: the twin knows it, a serial
    /// backend works it out from the firing schedule.
    pub measured: Vec<Option<Stamp>>,
}

impl SonarEchoes {
    /// Distance of reading `i` in metres for a speed of sound `c` (m/s), or `None` without echo.
    pub fn distance_m(&self, i: usize, speed_of_sound: f64) -> Option<f64> {
        echo_distance_m(*self.times.get(i)?, speed_of_sound)
    }
}

/// Speed of sound in dry air at 20 °C, m/s.
pub const SPEED_OF_SOUND: f64 = 343.0;

/// The distance of an echo that took `units` timer units to come back (there and back again),
/// or `None` for [`SONAR_NO_ECHO`].
///
/// ```
/// use robot::hardware::{echo_distance_m, echo_units, SPEED_OF_SOUND};
/// // 1000 units are 5.33 ms: 0.915 m away.
/// assert!((echo_distance_m(1000, SPEED_OF_SOUND).unwrap() - 0.91467).abs() < 1e-5);
/// assert_eq!(echo_units(0.91467, SPEED_OF_SOUND), 1000);
/// ```
pub fn echo_distance_m(units: u16, speed_of_sound: f64) -> Option<f64> {
    (units != SONAR_NO_ECHO && units != 0)
        .then(|| f64::from(units) * SONAR_TIME_UNIT_S * speed_of_sound / 2.0)
}

/// The echo time, in timer units, of an object `distance` metres away (rounded, saturating below
/// [`SONAR_NO_ECHO`]).
pub fn echo_units(distance_m: f64, speed_of_sound: f64) -> u16 {
    let units = (2.0 * distance_m / speed_of_sound / SONAR_TIME_UNIT_S).round();
    units.clamp(1.0, f64::from(SONAR_NO_ECHO - 1)) as u16
}
