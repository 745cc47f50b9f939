//! Types of the sonar ring (thesis §2.6.2 and the firmware's `sonar_cmd`).

use crate::time::Stamp;

/// Transducers on the ring, numbered counter-clockwise seen from above, 0 at the front.
pub const SONAR_COUNT: usize = 16;

/// One echo-time unit: the firmware's timer runs at the 24 MHz bus clock divided by 128.
pub const SONAR_TIME_UNIT_S: f64 = 128.0 / 24.0e6;

/// The echo time the firmware reports when no echo came back.
pub const SONAR_NO_ECHO: u16 = 65_535;

/// One command of the sonar ring.
#[derive(Clone, Debug, PartialEq, Eq)]
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

/// The latest echo time of each transducer of the firing sequence (`s` report).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SonarEchoes {
    /// When the report was taken.
    pub stamp: Stamp,
    /// The transducer fired at each position of the sequence.
    pub sequence: Vec<u8>,
    /// Echo time of each position, in [`SONAR_TIME_UNIT_S`] units; [`SONAR_NO_ECHO`] for none.
    pub times: Vec<u16>,
}

impl SonarEchoes {
    /// Distance of reading `i` in metres for a speed of sound `c` (m/s), or `None` without echo.
    pub fn distance_m(&self, i: usize, speed_of_sound: f64) -> Option<f64> {
        let t = *self.times.get(i)?;
        (t != SONAR_NO_ECHO && t != 0)
            .then(|| f64::from(t) * SONAR_TIME_UNIT_S * speed_of_sound / 2.0)
    }
}
