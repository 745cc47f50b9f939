//! The four 12 V lead-acid batteries: one pair for the electronics, one for the motors.
//!
//! Each battery is an open-circuit voltage that falls with its charge, behind an internal
//! resistance. The base microcontroller reads each pair at its middle and top through dividers
//! into 10-bit ADC channels AN2..AN5; the divider ratios here are the ones the firmware's
//! calibration constants assume (`bateries` in App. A: 639 counts for 12.72 V, and so on).

use crate::config::robot_file::BatteryDescription;

/// Open-circuit voltage of a 12 V lead-acid battery at rest, full and empty.
const OCV_FULL_V: f64 = 12.73;
const OCV_EMPTY_V: f64 = 11.90;

/// Millivolts per ADC count times ten, for AN2..AN5, before the firmware's integer rounding.
const DIVIDERS: [f64; 4] = [
    127_200.0 / 639.0,
    259_000.0 / 691.0,
    130_100.0 / 691.0,
    261_000.0 / 696.0,
];

/// Two 12 V batteries in series.
#[derive(Clone, Debug)]
pub struct BatteryPair {
    /// State of charge, 0..=1.
    charge: f64,
    /// Capacity of each battery, ampere-seconds.
    capacity_as: f64,
    /// Internal resistance of each battery, ohms.
    resistance: f64,
    /// Current drawn during the last interval, amperes.
    current: f64,
}

impl BatteryPair {
    fn new(d: &BatteryDescription) -> Self {
        BatteryPair {
            charge: d.state_of_charge.get(),
            capacity_as: d.capacity_ah.get() * 3600.0,
            resistance: d.internal_resistance_ohm.get(),
            current: 0.0,
        }
    }

    /// Draws `current` amperes for `dt` seconds.
    fn draw(&mut self, current: f64, dt: f64) {
        self.current = current;
        self.charge = (self.charge - current * dt / self.capacity_as).clamp(0.0, 1.0);
    }

    /// Terminal voltage of one battery under the present load, volts.
    fn battery_v(&self) -> f64 {
        OCV_EMPTY_V + (OCV_FULL_V - OCV_EMPTY_V) * self.charge - self.current * self.resistance
    }

    /// State of charge, 0..=1.
    pub fn charge(&self) -> f64 {
        self.charge
    }
}

/// The robot's electrical supply.
#[derive(Clone, Debug)]
pub struct Electrics {
    /// Microcontrollers, sonar, laser.
    pub logic: BatteryPair,
    /// Drive (and pan-tilt) motors.
    pub motor: BatteryPair,
    logic_load_a: f64,
}

impl Electrics {
    /// Batteries as described, with the electronics load switched on.
    pub fn new(d: &BatteryDescription) -> Self {
        Electrics {
            logic: BatteryPair::new(d),
            motor: BatteryPair::new(d),
            logic_load_a: d.logic_load_a.get(),
        }
    }

    /// Voltage across the motor pair, volts.
    pub fn motor_supply_v(&self) -> f64 {
        2.0 * self.motor.battery_v()
    }

    /// Accounts for `dt` seconds with the motors drawing `motor_current` amperes.
    pub fn draw(&mut self, motor_current: f64, dt: f64) {
        self.logic.draw(self.logic_load_a, dt);
        self.motor.draw(motor_current, dt);
    }

    /// The four ADC readings (AN2 logic 12 V, AN3 logic 24 V, AN4 motor 12 V, AN5 motor 24 V).
    pub fn adc(&self) -> [u16; 4] {
        let volts = [
            self.logic.battery_v(),
            2.0 * self.logic.battery_v(),
            self.motor.battery_v(),
            2.0 * self.motor.battery_v(),
        ];
        core::array::from_fn(|i| {
            super::round(volts[i] * 1000.0 * 10.0 / DIVIDERS[i]).clamp(0.0, 1023.0) as u16
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::values::{NonNegative, Positive, UnitInterval};

    fn full() -> Electrics {
        Electrics::new(&BatteryDescription {
            capacity_ah: Positive(7.0),
            state_of_charge: UnitInterval(1.0),
            internal_resistance_ohm: NonNegative(0.03),
            logic_load_a: NonNegative(1.5),
        })
    }

    #[test]
    fn the_thesis_calibration_point_reads_back() {
        // 639 counts on AN2 is the calibration point for 12.72 V.
        let volts = 12.72_f64;
        let count = (volts * 10_000.0 / DIVIDERS[0]).round();
        assert_eq!(count, 639.0);
        let e = full();
        let adc = e.adc();
        assert!((630..=645).contains(&adc[0]), "{adc:?}");
        assert!(adc[1] > 600, "{adc:?}");
    }

    #[test]
    fn charge_falls_and_voltage_sags_under_load() {
        let mut e = full();
        let idle = e.motor_supply_v();
        e.draw(10.0, 3600.0);
        assert!((e.motor.charge() - (1.0_f64 - 10.0 / 7.0).max(0.0)).abs() < 1e-9);
        assert!(e.motor_supply_v() < idle - 1.0);
        assert!(e.logic.charge() < 1.0);
    }
}
