//! A brushed DC gear motor with its quadrature encoder, driven through an LMD18200 H-bridge.
//!
//! The rotor obeys `J ω' = k_t i − τ_f sgn ω` with `i = (V − k_e ω) / R`: the electrical time
//! constant (≈ 1 ms) is small against the mechanical one (≈ 20 ms with the robot's mass reflected
//! through the gearbox), so the current follows the voltage at once. Over one control tick the
//! bridge voltage is constant and the equation is solved exactly, friction included, so the
//! result does not depend on the tick length.
//!
//! The LMD18200 in sign/magnitude mode shorts the motor during the PWM off-time, and with the
//! brake pin set and PWM high it shorts it permanently. The terminal voltage is therefore
//! `duty · V_supply` in the commanded direction, or zero (dynamic braking) when braked.
//!
//! Constants come from datasheet figures at nominal voltage: no-load output speed, stall current
//! and no-load current (which sets the friction torque).

use crate::config::robot_file::MotorDescription;
use crate::devices::firmware::HBridge;
use std::f64::consts::PI;

/// Electrical and mechanical constants of one motor with its load, SI units at the rotor.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct MotorParams {
    /// Winding resistance, ohms.
    pub resistance: f64,
    /// Back-EMF constant, V·s/rad (equal to the torque constant in N·m/A).
    pub k_e: f64,
    /// Coulomb friction torque at the rotor, N·m.
    pub friction: f64,
    /// Rotor inertia plus the load reflected through the gearbox, kg·m².
    pub inertia: f64,
    /// Encoder edges per rotor turn.
    pub counts_per_turn: f64,
}

impl MotorParams {
    /// Constants from a datasheet description, with `load_inertia` (kg·m², already reflected to
    /// the rotor) added to the rotor's own.
    pub fn from_datasheet(
        motor: &MotorDescription,
        gear_ratio: f64,
        counts_per_turn: u32,
        load_inertia: f64,
    ) -> Self {
        let v = motor.nominal_voltage_v.get();
        let resistance = v / motor.stall_current_a.get();
        let no_load_current = motor.no_load_current_a.get();
        let omega_no_load = motor.no_load_output_rpm.get() * gear_ratio * 2.0 * PI / 60.0;
        let k_e = (v - resistance * no_load_current) / omega_no_load;
        MotorParams {
            resistance,
            k_e,
            friction: k_e * no_load_current,
            inertia: motor.rotor_inertia_kg_m2.get() + load_inertia,
            counts_per_turn: f64::from(counts_per_turn),
        }
    }

    /// The mechanical time constant `J R / k_e²`, seconds.
    pub fn time_constant(&self) -> f64 {
        self.inertia * self.resistance / (self.k_e * self.k_e)
    }
}

/// What one tick of motor motion produced.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct MotorStep {
    /// Rotor rotation during the tick, radians (positive forward).
    pub rotation: f64,
    /// Current drawn from the supply, amperes (negative when regenerating).
    pub supply_current: f64,
}

/// One motor: rotor speed, rotor angle and the encoder edges not yet read.
#[derive(Clone, Debug)]
pub struct Motor {
    params: MotorParams,
    /// Rotor speed, rad/s (positive forward).
    omega: f64,
    /// Rotor angle in encoder counts (continuous, signed).
    angle_counts: f64,
    /// Edges seen by the pulse accumulator since it was last latched.
    edges: u32,
    /// Edges seen since the start, for ground truth.
    total_edges: u64,
    /// The last `exp(-span / time constant)` computed, by span: ticks are all one length.
    decay: (f64, f64),
}

impl Motor {
    /// A motor at rest.
    pub fn new(params: MotorParams) -> Self {
        Motor {
            params,
            omega: 0.0,
            angle_counts: 0.0,
            edges: 0,
            total_edges: 0,
            decay: (0.0, 1.0),
        }
    }

    /// The constants.
    pub fn params(&self) -> &MotorParams {
        &self.params
    }

    /// Rotor speed, rad/s.
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// Encoder edges since the start (what a hardware counter that never resets would show).
    pub fn total_edges(&self) -> u64 {
        self.total_edges
    }

    /// Latches and clears the pulse accumulator, as `get_vel` does.
    pub fn take_edges(&mut self) -> u32 {
        std::mem::take(&mut self.edges)
    }

    /// Runs the motor for `dt` seconds with the bridge inputs held and the supply at
    /// `supply_v` volts.
    pub fn advance(&mut self, bridge: HBridge, supply_v: f64, dt: f64) -> MotorStep {
        let p = self.params;
        let (voltage, duty) = if bridge.brake {
            (0.0, 0.0)
        } else {
            let duty = f64::from(bridge.pwm) / 255.0;
            let sign = if bridge.forward { 1.0 } else { -1.0 };
            (sign * duty * supply_v, sign * duty)
        };
        let a = p.k_e / (p.inertia * p.resistance); // acceleration per volt
        let b = p.k_e * p.k_e / (p.inertia * p.resistance); // 1 / time constant
        let f = p.friction / p.inertia; // friction deceleration
        let omega0 = self.omega;
        let mut t = 0.0;
        let mut rotation = 0.0;
        while t < dt {
            let remaining = dt - t;
            let s = if self.omega != 0.0 {
                self.omega.signum()
            } else if (a * voltage).abs() > f {
                voltage.signum()
            } else {
                break; // stiction holds the rotor
            };
            let omega_ss = (a * voltage - f * s) / b;
            let w0 = self.omega;
            // Would friction and braking stop the rotor within the interval?
            let stop_after = if omega_ss * s < 0.0 && w0 != 0.0 {
                ((w0 - omega_ss) / -omega_ss).ln() / b
            } else {
                f64::INFINITY
            };
            let span = remaining.min(stop_after);
            if span != self.decay.0 {
                self.decay = (span, (-b * span).exp());
            }
            let decay = self.decay.1;
            rotation += omega_ss * span + (w0 - omega_ss) * (1.0 - decay) / b;
            t += span;
            self.omega = if span == stop_after {
                0.0
            } else {
                omega_ss + (w0 - omega_ss) * decay
            };
        }
        let before = super::floor(self.angle_counts);
        self.angle_counts += rotation * p.counts_per_turn / (2.0 * PI);
        let crossed = (super::floor(self.angle_counts) - before).abs() as u64;
        self.edges = self.edges.saturating_add(crossed as u32);
        self.total_edges += crossed;
        let mean_omega = if dt > 0.0 { rotation / dt } else { omega0 };
        let current = (voltage - p.k_e * mean_omega) / p.resistance;
        MotorStep {
            rotation,
            supply_current: duty * current,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::values::{NonNegative, Positive};

    fn gm9236() -> MotorParams {
        let d = MotorDescription {
            nominal_voltage_v: Positive(24.0),
            no_load_output_rpm: Positive(71.0),
            stall_current_a: Positive(9.64),
            no_load_current_a: NonNegative(0.2),
            rotor_inertia_kg_m2: Positive(2.8e-6),
        };
        // 7 kg per wheel on a 0.195 m wheel through 65.5:1.
        let load = 7.0 * (0.0975f64 / 65.5).powi(2);
        MotorParams::from_datasheet(&d, 65.5, 1000, load)
    }

    const DRIVE: HBridge = HBridge {
        forward: true,
        brake: false,
        pwm: 255,
    };

    #[test]
    fn full_pwm_reaches_the_datasheet_no_load_speed() {
        let mut m = Motor::new(gm9236());
        for _ in 0..2000 {
            m.advance(DRIVE, 24.0, 1.024e-3);
        }
        let rpm_out = m.omega() / 65.5 * 60.0 / (2.0 * PI);
        assert!((rpm_out - 71.0).abs() < 0.01, "{rpm_out}");
    }

    #[test]
    fn the_result_does_not_depend_on_the_step() {
        let mut coarse = Motor::new(gm9236());
        let mut fine = Motor::new(gm9236());
        let (mut a, mut b) = (0.0, 0.0);
        for _ in 0..100 {
            a += coarse.advance(DRIVE, 24.0, 1e-3).rotation;
            for _ in 0..10 {
                b += fine.advance(DRIVE, 24.0, 1e-4).rotation;
            }
        }
        assert!((a - b).abs() < 1e-9 * a.abs(), "{a} {b}");
    }

    #[test]
    fn braking_stops_the_rotor_and_friction_holds_it() {
        let mut m = Motor::new(gm9236());
        for _ in 0..200 {
            m.advance(DRIVE, 24.0, 1e-3);
        }
        let brake = HBridge {
            forward: true,
            brake: true,
            pwm: 255,
        };
        let mut coast = 0.0;
        for _ in 0..500 {
            coast += m.advance(brake, 24.0, 1e-3).rotation;
        }
        assert_eq!(m.omega(), 0.0);
        assert!(coast > 0.0, "the rotor coasts forward while braking");
        let still = m.advance(
            HBridge {
                forward: true,
                brake: false,
                pwm: 2,
            },
            24.0,
            1e-3,
        );
        assert_eq!(still.rotation, 0.0, "a tiny duty does not beat stiction");
    }

    #[test]
    fn encoder_counts_edges_in_either_direction() {
        let mut m = Motor::new(gm9236());
        let back = HBridge {
            forward: false,
            brake: false,
            pwm: 128,
        };
        let mut rotation = 0.0;
        for _ in 0..300 {
            rotation += m.advance(back, 24.0, 1e-3).rotation;
        }
        assert!(rotation < 0.0);
        let expected = (-rotation * 1000.0 / (2.0 * PI)).floor();
        let edges = m.take_edges() as f64;
        assert!((edges - expected).abs() <= 1.0, "{edges} vs {expected}");
        assert_eq!(m.take_edges(), 0, "latching clears the accumulator");
    }
}
