//! Robot description files: wheels, gearbox, motors, body, laser mount and batteries.
//!
//! Everything the twin needs to know about a robot is data. The two shipped descriptions are
//! `scenarios/robots/pioneer-3dx.toml` (the project's default, a Pioneer 3-DX class base carrying
//! the thesis's drive electronics and sensors) and `scenarios/robots/thesis-roca.toml` (the custom
//! base of the thesis). Each names its sources.

use super::error::{ConfigError, Source};
use super::values::{Angle, Finite, NonNegative, Positive, Seconds, Sigma, UnitInterval};
use robot::mount::{HeadGeometry, LaserMount};
use robot::{DriveGeometry, Pose2};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A validated robot description.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotDescription {
    /// Short name.
    pub name: String,
    /// What the robot is.
    pub description: String,
    /// Where the numbers come from.
    pub sources: Vec<String>,
    /// Wheels and gearbox, as the robot's software believes them.
    pub drive: DriveDescription,
    /// The drive motors.
    pub motor: MotorDescription,
    /// The body that collides with walls.
    pub body: BodyDescription,
    /// The laser and its mount.
    pub laser: LaserDescription,
    /// The batteries.
    pub battery: BatteryDescription,
    /// The sonar ring, if the robot has one.
    pub sonar: Option<SonarDescription>,
    /// The pan-tilt unit the laser rides on, if the robot has one.
    pub pan_tilt: Option<PanTiltDescription>,
    /// The file it was read from.
    pub path: PathBuf,
}

/// Wheels, gearbox and encoders.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveDescription {
    /// Nominal wheel diameter, metres.
    pub wheel_diameter_m: Positive,
    /// Nominal distance between the wheels' contact points, metres.
    pub track_m: Positive,
    /// Motor turns per wheel turn.
    pub gear_ratio: Positive,
    /// Encoder counts per motor (rotor) turn as the firmware counts them.
    pub counts_per_rotor_turn: u32,
    /// Bit rate of the base microcontroller's serial line.
    pub serial_baud: u32,
}

/// A brushed DC gear motor, from its datasheet figures at nominal voltage.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotorDescription {
    /// Voltage of the datasheet figures, volts.
    pub nominal_voltage_v: Positive,
    /// Output-shaft speed without load at nominal voltage, rpm.
    pub no_load_output_rpm: Positive,
    /// Current at stall and nominal voltage, amperes.
    pub stall_current_a: Positive,
    /// Current without load at nominal voltage, amperes (sets the friction torque).
    pub no_load_current_a: NonNegative,
    /// Inertia of the rotor, kg·m².
    pub rotor_inertia_kg_m2: Positive,
}

/// The robot's body.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyDescription {
    /// Mass with batteries and payload, kg.
    pub mass_kg: Positive,
    /// Radius of the round footprint that collides with walls, metres.
    pub radius_m: Positive,
    /// Position of the footprint's centre ahead of the wheel axle, metres.
    #[serde(default = "zero")]
    pub center_x_m: Finite,
    /// Height of the robot's top, metres: it passes under what is higher, and reflected laser
    /// pulses meet it below that.
    pub height_m: Positive,
}

/// The laser rangefinder and where it sits on the base. On a robot with a pan-tilt the mount
/// comes from the pan-tilt (the laser at level tilt, looking forward) and the file must not give
/// one.
#[derive(Clone, Debug, PartialEq)]
pub struct LaserDescription {
    /// Mount position ahead of the wheel axle, metres.
    pub x_m: Finite,
    /// Mount position to the left of the axle's centre, metres.
    pub y_m: Finite,
    /// Mount heading, degrees counter-clockwise.
    pub yaw_deg: Finite,
    /// Height of the scan plane above the floor, metres.
    pub z_m: Positive,
    /// Number of beams.
    pub beams: u16,
    /// Field of view from first to last beam, degrees.
    pub fov_deg: Positive,
    /// Maximum range and no-return value, metres.
    pub range_max_m: Positive,
    /// Standard deviation of the range noise, metres.
    pub sigma_m: Sigma,
    /// Bit rate of the laser's serial line.
    pub baud: u32,
    /// Time the mirror takes for one scan at this resolution, seconds.
    pub sweep_s: Seconds,
    /// Bytes of one scan telegram on the serial line.
    pub telegram_bytes: u32,
}

/// The `[laser]` section as written: the mount is optional (absent on a pan-tilt).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LaserFile {
    x_m: Option<Finite>,
    y_m: Option<Finite>,
    yaw_deg: Option<Finite>,
    z_m: Option<Positive>,
    beams: u16,
    fov_deg: Positive,
    range_max_m: Positive,
    sigma_m: Sigma,
    baud: u32,
    sweep_s: Seconds,
    telegram_bytes: u32,
}

/// A ring of ultrasonic transducers fired by the base microcontroller.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SonarDescription {
    /// Transducers, evenly spaced counter-clockwise from the front (at most 16).
    pub count: u8,
    /// Radius of the circle they sit on, metres.
    pub ring_radius_m: Positive,
    /// Centre of that circle ahead of the wheel axle, metres.
    #[serde(default = "zero")]
    pub center_x_m: Finite,
    /// Full width of a transducer's cone, degrees.
    pub cone_deg: Positive,
    /// Rays sampling the cone.
    pub rays: u8,
    /// Nearest echo heard (blanking), metres.
    pub min_range_m: Positive,
    /// Farthest echo heard, metres.
    pub max_range_m: Positive,
    /// Incidence beyond which a smooth surface reflects the burst away, degrees.
    pub critical_deg: Angle,
    /// Standard deviation of the range noise, metres.
    pub sigma_m: Sigma,
    /// Height of the transducers above the floor, metres.
    pub height_m: Positive,
}

/// The pan-tilt unit carrying the laser (thesis §2.5, App. A.3.2, App. D).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PanTiltDescription {
    /// Pan axis ahead of the wheel axle, metres.
    pub axis_x_m: Finite,
    /// Pan axis to the left of the axle's centre, metres.
    #[serde(default = "zero")]
    pub axis_y_m: Finite,
    /// Height of the tilt axis above the floor, metres.
    pub axis_z_m: Positive,
    /// The laser's optical centre ahead of the tilt axis, in the tilting frame (App. D `DELTAZ`).
    pub laser_forward_m: Finite,
    /// The laser's optical centre above the tilt axis, in the tilting frame (App. D `DELTAY`).
    pub laser_up_m: Finite,
    /// Bit rate of the pan-tilt microcontroller's serial line.
    pub serial_baud: u32,
    /// Pan angle per pan motor turn (one position), degrees.
    pub pan_deg_per_turn: Positive,
    /// Tilt angle per tilt motor turn (one position), degrees.
    pub tilt_deg_per_turn: Positive,
    /// The tilt position at which the scan plane is level.
    pub level_position: u16,
    /// Pan angle at power-up, before homing, degrees from pan position 0.
    #[serde(default = "zero")]
    pub initial_pan_deg: Finite,
    /// Tilt angle at power-up, before homing, degrees above level.
    #[serde(default = "zero")]
    pub initial_tilt_deg: Finite,
    /// Pan motor gearbox, motor turns per output turn.
    pub pan_gear_ratio: Positive,
    /// Tilt motor gearbox, motor turns per output turn.
    pub tilt_gear_ratio: Positive,
    /// The pan motor (on the 24 V motor pair).
    pub pan_motor: MotorDescription,
    /// The tilt motor (on the 12 V tap of the motor pair).
    pub tilt_motor: MotorDescription,
}

/// The two battery pairs.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BatteryDescription {
    /// Capacity of each 12 V battery, ampere-hours.
    pub capacity_ah: Positive,
    /// Charge at the start, 0..=1.
    pub state_of_charge: UnitInterval,
    /// Internal resistance of each 12 V battery, ohms.
    pub internal_resistance_ohm: NonNegative,
    /// Current drawn from the electronics pair (laser, sonar, boards), amperes.
    pub logic_load_a: NonNegative,
}

fn zero() -> Finite {
    Finite(0.0)
}

impl RobotDescription {
    /// Reads and validates a robot description.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ConfigError> {
        Self::from_source(&Source::read(path.as_ref())?)
    }

    /// Parses and validates robot-description text; `path` only names it in errors.
    pub fn parse(text: &str, path: impl AsRef<Path>) -> Result<Self, ConfigError> {
        Self::from_source(&Source::text(text, path.as_ref()))
    }

    fn from_source(source: &Source) -> Result<Self, ConfigError> {
        let file: RobotFile = source.parse()?;
        let invalid =
            |field: &str, message: String| source.error_in_file(Some(field.into()), message);
        if file.drive.counts_per_rotor_turn == 0 {
            return Err(invalid(
                "drive.counts_per_rotor_turn",
                "expected at least 1 count per turn".into(),
            ));
        }
        if file.laser.beams < 2 {
            return Err(invalid(
                "laser.beams",
                format!("expected at least 2 beams, found {}", file.laser.beams),
            ));
        }
        if file.laser.fov_deg.get() > 360.0 {
            return Err(invalid(
                "laser.fov_deg",
                format!("expected at most 360, found {}", file.laser.fov_deg.get()),
            ));
        }
        if file.laser.range_max_m.get() > 65.535 {
            return Err(invalid(
                "laser.range_max_m",
                format!(
                    "millimetre readings fit 16 bits: expected at most 65.535, found {}",
                    file.laser.range_max_m.get()
                ),
            ));
        }
        let mut bauds = vec![
            ("drive.serial_baud", file.drive.serial_baud),
            ("laser.baud", file.laser.baud),
        ];
        if let Some(pt) = &file.pan_tilt {
            bauds.push(("pan_tilt.serial_baud", pt.serial_baud));
        }
        for (field, baud) in bauds {
            if !(300..=10_000_000).contains(&baud) {
                return Err(invalid(
                    field,
                    format!("expected a bit rate from 300 to 10000000, found {baud}"),
                ));
            }
        }
        if file.laser.beams > 10_000 {
            return Err(invalid(
                "laser.beams",
                format!("expected at most 10000 beams, found {}", file.laser.beams),
            ));
        }
        // Two bytes a reading on the wire, plus the telegram's frame.
        let least = 2 * u32::from(file.laser.beams);
        if !(least..=1_000_000).contains(&file.laser.telegram_bytes) {
            return Err(invalid(
                "laser.telegram_bytes",
                format!(
                    "expected at least 2 bytes per beam ({least}) and at most 1000000, found {}",
                    file.laser.telegram_bytes
                ),
            ));
        }
        if file.drive.counts_per_rotor_turn > 1_000_000 {
            return Err(invalid(
                "drive.counts_per_rotor_turn",
                format!(
                    "expected at most 1000000 counts per turn, found {}",
                    file.drive.counts_per_rotor_turn
                ),
            ));
        }
        let laser = resolve_laser(&file, &invalid)?;
        if let Some(sonar) = &file.sonar {
            if !(1..=16).contains(&sonar.count) {
                return Err(invalid(
                    "sonar.count",
                    format!("expected 1..=16 transducers, found {}", sonar.count),
                ));
            }
            if sonar.rays == 0 {
                return Err(invalid(
                    "sonar.rays",
                    "expected at least 1 ray per cone, found 0".into(),
                ));
            }
            if sonar.min_range_m.get() >= sonar.max_range_m.get() {
                return Err(invalid(
                    "sonar.min_range_m",
                    "must be below sonar.max_range_m".into(),
                ));
            }
        }
        if file.motor.no_load_current_a.get() >= file.motor.stall_current_a.get() {
            return Err(invalid(
                "motor.no_load_current_a",
                "must be below the stall current".into(),
            ));
        }
        Ok(RobotDescription {
            name: file.name,
            description: file.description,
            sources: file.sources,
            drive: file.drive,
            motor: file.motor,
            body: file.body,
            laser,
            battery: file.battery,
            sonar: file.sonar,
            pan_tilt: file.pan_tilt,
            path: source.path.clone(),
        })
    }

    /// The laser's optical centre on the base with the pan-tilt at pan 0 and level tilt, and
    /// the scan plane's height: `(x, y, z)` in metres.
    pub fn level_laser_position(&self) -> (f64, f64, f64) {
        (
            self.laser.x_m.get(),
            self.laser.y_m.get(),
            self.laser.z_m.get(),
        )
    }

    /// The nominal geometry the robot's odometry uses.
    pub fn geometry(&self) -> DriveGeometry {
        DriveGeometry {
            wheel_diameter_m: self.drive.wheel_diameter_m.get(),
            track_m: self.drive.track_m.get(),
            gear_ratio: self.drive.gear_ratio.get(),
            counts_per_rotor_turn: self.drive.counts_per_rotor_turn,
        }
    }

    /// Where the laser sits: on its fixed mount, or on the pan-tilt head with the head's
    /// geometry and units (for the robot code: the chain of thesis Eq. 4.1).
    pub fn mount(&self) -> LaserMount {
        match &self.pan_tilt {
            Some(pt) => LaserMount::Head(HeadGeometry {
                axis: [pt.axis_x_m.get(), pt.axis_y_m.get(), pt.axis_z_m.get()],
                laser_forward: pt.laser_forward_m.get(),
                laser_up: pt.laser_up_m.get(),
                pan_per_position: pt.pan_deg_per_turn.get().to_radians(),
                tilt_per_position: pt.tilt_deg_per_turn.get().to_radians(),
                level_position: f64::from(pt.level_position),
            }),
            None => LaserMount::Fixed {
                pose: self.laser_mount(),
                z: self.laser.z_m.get(),
            },
        }
    }

    /// The laser's pose on the base (axle centre frame); on a pan-tilt, where the level head
    /// looking forward puts it.
    pub fn laser_mount(&self) -> Pose2 {
        Pose2::new(
            self.laser.x_m.get(),
            self.laser.y_m.get(),
            self.laser.yaw_deg.get().to_radians(),
        )
    }
}

/// The laser's description with its mount: from the `[laser]` section, or from the pan-tilt.
fn resolve_laser(
    file: &RobotFile,
    invalid: &dyn Fn(&str, String) -> ConfigError,
) -> Result<LaserDescription, ConfigError> {
    let l = &file.laser;
    let (x_m, y_m, yaw_deg, z_m) = match &file.pan_tilt {
        Some(pt) => {
            if pt.level_position > 100 {
                return Err(invalid(
                    "pan_tilt.level_position",
                    format!("expected 0..=100, found {}", pt.level_position),
                ));
            }
            if pt.serial_baud == 0 {
                return Err(invalid(
                    "pan_tilt.serial_baud",
                    "expected a bit rate above 0".into(),
                ));
            }
            for (field, given) in [
                ("laser.x_m", l.x_m.is_some()),
                ("laser.y_m", l.y_m.is_some()),
                ("laser.yaw_deg", l.yaw_deg.is_some()),
                ("laser.z_m", l.z_m.is_some()),
            ] {
                if given {
                    return Err(invalid(
                        field,
                        "the laser rides on the pan-tilt: its position comes from [pan_tilt] \
                         (axis_x_m, axis_y_m, axis_z_m, laser_forward_m, laser_up_m); remove this key"
                            .into(),
                    ));
                }
            }
            let z = pt.axis_z_m.get() + pt.laser_up_m.get();
            if z <= 0.0 {
                return Err(invalid(
                    "pan_tilt.laser_up_m",
                    format!("puts the level laser at {z} m: expected above the floor"),
                ));
            }
            (
                Finite(pt.axis_x_m.get() + pt.laser_forward_m.get()),
                pt.axis_y_m,
                Finite(0.0),
                Positive(z),
            )
        }
        None => {
            let (Some(x), Some(z)) = (l.x_m, l.z_m) else {
                let missing = if l.x_m.is_none() {
                    "laser.x_m"
                } else {
                    "laser.z_m"
                };
                return Err(invalid(
                    missing,
                    "expected the laser's mount (x_m, z_m; y_m and yaw_deg default to 0) \
                     on a robot without a pan-tilt"
                        .into(),
                ));
            };
            (x, l.y_m.unwrap_or(zero()), l.yaw_deg.unwrap_or(zero()), z)
        }
    };
    Ok(LaserDescription {
        x_m,
        y_m,
        yaw_deg,
        z_m,
        beams: l.beams,
        fov_deg: l.fov_deg,
        range_max_m: l.range_max_m,
        sigma_m: l.sigma_m,
        baud: l.baud,
        sweep_s: l.sweep_s,
        telegram_bytes: l.telegram_bytes,
    })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    name: String,
    #[serde(default)]
    description: String,
    #[serde(default)]
    sources: Vec<String>,
    drive: DriveDescription,
    motor: MotorDescription,
    body: BodyDescription,
    laser: LaserFile,
    battery: BatteryDescription,
    sonar: Option<SonarDescription>,
    pan_tilt: Option<PanTiltDescription>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped(name: &str) -> RobotDescription {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scenarios/robots")
            .join(name);
        RobotDescription::load(&path).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn shipped_descriptions_load() {
        let p3dx = shipped("pioneer-3dx.toml");
        assert_eq!(p3dx.laser.beams, 361);
        assert!((p3dx.geometry().wheel_diameter_m - 0.195).abs() < 1e-12);
        let roca = shipped("thesis-roca.toml");
        assert_eq!(roca.drive.counts_per_rotor_turn, 1000);
        assert_eq!(roca.laser.baud, 9600);
    }

    #[test]
    fn a_negative_wheel_is_refused_at_its_line() {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/robots/pioneer-3dx.toml");
        let text = std::fs::read_to_string(path).unwrap();
        let bad = text.replace("wheel_diameter_m = 0.195", "wheel_diameter_m = -0.195");
        let err = RobotDescription::parse(&bad, "p3dx.toml").unwrap_err();
        let line = text
            .lines()
            .position(|l| l.starts_with("wheel_diameter_m"))
            .unwrap()
            + 1;
        assert_eq!(err.line, Some(line), "{err}");
        assert_eq!(
            err.field.as_deref(),
            Some("drive.wheel_diameter_m"),
            "{err}"
        );
        assert!(
            err.message
                .contains("expected a positive number from 1e-12 to 1e6, found -0.195"),
            "{err}"
        );
    }
}
