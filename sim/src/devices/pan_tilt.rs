//! The pan-tilt unit's mechanics: two geared DC motors with 500-line encoders and an index pulse
//! per rotor turn, three limit switches, and the laser riding on the tilting head.
//!
//! The firmware counts positions in whole motor turns (an index pulse each), so the natural
//! coordinate of each joint here is **motor turns from position 0**: the index pulses sit at the
//! integers, channel B rises every 1/500 turn, and the pulse accumulator that measures speed
//! counts 1000 edges per turn (`clicks_stop = turns × 1000` in `set_params_*`). Pan angle is
//! `turns × pan_deg_per_turn` (counter-clockwise, 0 looking forward); tilt angle is
//! `(turns − level_position) × tilt_deg_per_turn` (positive up).
//!
//! The switches are where homing finds them: the pan's right switch and the tilt's lower switch
//! are pressed from 0.4 turn below position 0 on, the pan's left switch from 0.6 turn beyond the
//! firmware's last position (`MAX_ABS_GIRO`). The motors are the same exact DC model as the
//! drive's ([`crate::devices::motor`]); the pan runs on the 24 V motor pair, the tilt on its 12 V tap. The
//! head is taken as balanced about the tilt axis (no gravity torque).
//!
//! The laser's optical centre sits `laser_forward_m` ahead of and `laser_up_m` above the tilt
//! axis in the tilting frame (App. D's `DELTAZ` = 45 mm and `DELTAY` = 8 mm), so it moves on a
//! circle about the axis as the head tilts.

use crate::config::robot_file::PanTiltDescription;
use crate::devices::firmware::PanTiltFirmware;
use crate::devices::firmware::pan_tilt::MAX_ABS_GIRO;
use crate::devices::laser::LaserFrame;
use crate::devices::motor::{Motor, MotorParams};
use robot::Pose2;
pub use robot::hardware::HeadAngles;
use std::f64::consts::TAU;

/// Pulse-accumulator edges per motor turn.
pub const EDGES_PER_TURN: u32 = 1000;
/// Rising edges of channel B per motor turn.
pub const B_EDGES_PER_TURN: u32 = 500;
/// How far below position 0 (turns) the right pan switch and the lower tilt switch are pressed.
pub const SWITCH_BELOW_ZERO: f64 = 0.4;
/// Inertia of the panning head with the laser about the pan axis, kg·m² (estimate: a 4.5 kg
/// LMS and the tilt stage).
const PAN_LOAD_INERTIA: f64 = 0.06;
/// Inertia of the tilting head about the tilt axis, kg·m² (estimate).
const TILT_LOAD_INERTIA: f64 = 0.03;

/// One joint: its motor and where it is.
#[derive(Clone, Debug)]
struct Joint {
    motor: Motor,
    /// Motor turns from position 0.
    turns: f64,
    /// Radians of joint motion per motor turn.
    rad_per_turn: f64,
}

impl Joint {
    fn new(
        desc: &crate::config::robot_file::MotorDescription,
        gear: f64,
        deg_per_turn: f64,
        load: f64,
        turns: f64,
    ) -> Self {
        let rad_per_turn = deg_per_turn.to_radians();
        // Motor turns per joint radian squared reflects the load to the rotor.
        let reflected = load * (rad_per_turn / TAU).powi(2);
        Joint {
            motor: Motor::new(MotorParams::from_datasheet(
                desc,
                gear,
                EDGES_PER_TURN,
                reflected,
            )),
            turns,
            rad_per_turn,
        }
    }

    /// Turns by `rotation` radians of the rotor and tells the firmware's interrupts what the
    /// encoder did, in the order it happened: channel-B edges, the index pulse when an integer
    /// is crossed, the rest of the edges.
    fn advance(&mut self, rotation: f64, fw: &mut PanTiltFirmware, tilt: bool) {
        let before = self.turns;
        self.turns += rotation / TAU;
        let after = self.turns;
        if after == before {
            return;
        }
        let up = after > before;
        let b = |t: f64| (t * f64::from(B_EDGES_PER_TURN)).floor();
        let mut from = before;
        // Index pulses at the integers between the two positions, in path order.
        let (lo, hi) = (
            before.min(after).floor() as i64,
            before.max(after).floor() as i64,
        );
        for k in 0..hi - lo {
            let at = (if up { lo + 1 + k } else { hi - k }) as f64;
            fw.channel_b(tilt, (b(at) - b(from)).abs() as u32, up);
            fw.index_pulse(tilt);
            from = at;
        }
        fw.channel_b(tilt, (b(after) - b(from)).abs() as u32, up);
    }
}

/// The pan-tilt head: both joints and the geometry the laser rides on.
#[derive(Clone, Debug)]
pub struct PanTiltHead {
    pan: Joint,
    tilt: Joint,
    level_position: f64,
    left_switch_turns: f64,
    axis: [f64; 3],
    laser_forward: f64,
    laser_up: f64,
}

impl PanTiltHead {
    /// The head as described, resting where the description says it was left at power-off.
    pub fn new(desc: &PanTiltDescription) -> Self {
        let level = f64::from(desc.level_position);
        let pan_step = desc.pan_deg_per_turn.get();
        let tilt_step = desc.tilt_deg_per_turn.get();
        PanTiltHead {
            pan: Joint::new(
                &desc.pan_motor,
                desc.pan_gear_ratio.get(),
                pan_step,
                PAN_LOAD_INERTIA,
                desc.initial_pan_deg.get() / pan_step,
            ),
            tilt: Joint::new(
                &desc.tilt_motor,
                desc.tilt_gear_ratio.get(),
                tilt_step,
                TILT_LOAD_INERTIA,
                level + desc.initial_tilt_deg.get() / tilt_step,
            ),
            level_position: level,
            left_switch_turns: f64::from(MAX_ABS_GIRO) + 0.6,
            axis: [
                desc.axis_x_m.get(),
                desc.axis_y_m.get(),
                desc.axis_z_m.get(),
            ],
            laser_forward: desc.laser_forward_m.get(),
            laser_up: desc.laser_up_m.get(),
        }
    }

    /// The limit switches as they are now: (left, right, lower) pressed.
    pub fn switches(&self) -> (bool, bool, bool) {
        (
            self.pan.turns >= self.left_switch_turns,
            self.pan.turns <= -SWITCH_BELOW_ZERO,
            self.tilt.turns <= -SWITCH_BELOW_ZERO,
        )
    }

    /// The firmware at power-up, reading the switches where the head rests.
    pub fn power_on_firmware(&self) -> PanTiltFirmware {
        let (izq, der, inf) = self.switches();
        PanTiltFirmware::power_on(izq, der, inf)
    }

    /// Runs the motors for one tick of `dt` seconds under the firmware's bridge inputs and fires
    /// the encoder, index and switch interrupts, then the real-time interrupt that latches the
    /// speeds. Returns the current drawn from the 24 V motor pair, amperes.
    pub fn tick(&mut self, fw: &mut PanTiltFirmware, motor_supply_v: f64, dt: f64) -> f64 {
        let (pan_bridge, tilt_bridge) = fw.bridges();
        let pan = self.pan.motor.advance(pan_bridge, motor_supply_v, dt);
        let tilt = self
            .tilt
            .motor
            .advance(tilt_bridge, 0.5 * motor_supply_v, dt);
        self.pan.advance(pan.rotation, fw, false);
        self.tilt.advance(tilt.rotation, fw, true);
        let (izq, der, inf) = self.switches();
        fw.set_switches(izq, der, inf);
        fw.rti_interrupt(self.pan.motor.take_edges(), self.tilt.motor.take_edges());
        // The 12 V tap carries the tilt current: half of it, in power, from the 24 V pair.
        pan.supply_current + 0.5 * tilt.supply_current
    }

    /// The joints' angles now.
    pub fn angles(&self) -> HeadAngles {
        HeadAngles {
            pan: self.pan.turns * self.pan.rad_per_turn,
            tilt: (self.tilt.turns - self.level_position) * self.tilt.rad_per_turn,
        }
    }

    /// The joints' angles when the firmware reports the head at positions `pan` and `tilt`
    /// (whole motor turns from position 0, as `l` counts them).
    pub fn angles_at(&self, pan: i16, tilt: i16) -> HeadAngles {
        HeadAngles {
            pan: f64::from(pan) * self.pan.rad_per_turn,
            tilt: (f64::from(tilt) - self.level_position) * self.tilt.rad_per_turn,
        }
    }

    /// The joints in motor turns from position 0: (pan, tilt).
    pub fn turns(&self) -> (f64, f64) {
        (self.pan.turns, self.tilt.turns)
    }

    /// The laser's frame with the base at `base` and the head at `angles`.
    pub fn laser_frame(&self, base: Pose2, angles: HeadAngles) -> LaserFrame {
        let (ax, ay) = base.transform_point(self.axis[0], self.axis[1]);
        let yaw = base.theta + angles.pan;
        let (st, ct) = angles.tilt.sin_cos();
        let ahead = self.laser_forward * ct - self.laser_up * st;
        let up = self.laser_forward * st + self.laser_up * ct;
        LaserFrame {
            origin: [
                ax + ahead * yaw.cos(),
                ay + ahead * yaw.sin(),
                self.axis[2] + up,
            ],
            yaw,
            tilt: angles.tilt,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::RobotDescription;

    fn thesis_head() -> PanTiltHead {
        let robot = RobotDescription::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../scenarios/robots/thesis-roca.toml"),
        )
        .unwrap();
        PanTiltHead::new(robot.pan_tilt.as_ref().unwrap())
    }

    #[test]
    fn the_level_laser_is_where_the_fixed_mount_would_be() {
        let head = thesis_head();
        let frame = head.laser_frame(Pose2::new(1.0, 2.0, 0.5), HeadAngles::default());
        let (x, y) = Pose2::new(1.0, 2.0, 0.5).transform_point(0.045, 0.0);
        assert!((frame.origin[0] - x).abs() < 1e-12 && (frame.origin[1] - y).abs() < 1e-12);
        assert!((frame.origin[2] - 1.05).abs() < 1e-12);
        assert_eq!((frame.yaw, frame.tilt), (0.5, 0.0));
    }

    #[test]
    fn tilting_swings_the_laser_about_the_axis() {
        let head = thesis_head();
        let tilt = 30f64.to_radians();
        let frame = head.laser_frame(
            Pose2::IDENTITY,
            HeadAngles {
                pan: std::f64::consts::FRAC_PI_2,
                tilt,
            },
        );
        // Panned to the left: the offset lies along +y.
        let ahead = 0.045 * tilt.cos() - 0.008 * tilt.sin();
        let up = 0.045 * tilt.sin() + 0.008 * tilt.cos();
        assert!(frame.origin[0].abs() < 1e-12);
        assert!((frame.origin[1] - ahead).abs() < 1e-12);
        assert!((frame.origin[2] - (1.042 + up)).abs() < 1e-12);
    }

    #[test]
    fn every_crossed_integer_is_one_index_pulse_between_its_edges() {
        let head = thesis_head();
        let mut fw = head.power_on_firmware();
        let mut joint = head.pan.clone();
        joint.turns = 0.9;
        // Crossing 1.0 upwards: 50 edges before it; the index is counted only after 250
        // clicks (125 edges) since the last, so nothing counts yet; the absolute stays put.
        joint.advance(0.2 * TAU, &mut fw, false);
        assert_eq!(fw.positions().0, 0);
        // A full turn later, the next index counts (500 edges of 2 clicks each before it).
        joint.advance(1.0 * TAU, &mut fw, false);
        assert_eq!(
            fw.positions().0,
            -1,
            "counted turning with the power-on direction"
        );
    }
}
