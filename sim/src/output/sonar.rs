//! `sonar.json`: one full reading of the sonar ring, with the pose it was taken from.

use crate::record::SonarRecord;
use robot::hardware::{SPEED_OF_SOUND, echo_distance_m};
use serde::Serialize;
use std::path::Path;

#[derive(Serialize)]
struct Reading {
    /// Transducer number (0 at the front, counter-clockwise).
    sonar: u8,
    /// Echo time in 5.33 µs units, 65535 for none.
    echo_units: u16,
    /// Distance at 343 m/s, metres, or null.
    distance_m: Option<f64>,
    /// When it was measured, seconds.
    measured_t: Option<f64>,
}

#[derive(Serialize)]
struct Ring {
    /// When the report was read, seconds.
    t: f64,
    /// True pose of the base `[x, y, theta]`.
    truth: [f64; 3],
    readings: Vec<Reading>,
}

/// Writes the ring reading as pretty JSON.
pub fn write_sonar(path: &Path, record: &SonarRecord) -> std::io::Result<()> {
    let e = &record.echoes;
    let ring = Ring {
        t: e.stamp.secs_f64(),
        truth: [record.truth.x, record.truth.y, record.truth.theta],
        readings: (0..e.times.len())
            .map(|i| Reading {
                sonar: e.sequence[i],
                echo_units: e.times[i],
                distance_m: echo_distance_m(e.times[i], SPEED_OF_SOUND),
                measured_t: e.measured[i].map(|t| t.secs_f64()),
            })
            .collect(),
    };
    let mut text = serde_json::to_string_pretty(&ring)?;
    text.push('\n');
    robot::logs::write_file(path, text)
}
