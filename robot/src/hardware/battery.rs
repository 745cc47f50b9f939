//! The battery report of the base microcontroller (`t`).

use crate::time::Stamp;

/// The four battery voltages, millivolts: two pairs of 12 V lead-acid batteries, one pair for
/// the electronics (microcontrollers, sonar, laser) and one for the motors, each measured at the
/// middle (12 V) and top (24 V) of the pair.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct BatteryVoltages {
    /// When the report was taken.
    pub stamp: Stamp,
    /// Electronics pair, lower battery (`Bat12`).
    pub logic_12_mv: u16,
    /// Electronics pair, both batteries (`Bat24`).
    pub logic_24_mv: u16,
    /// Motor pair, lower battery (`Bat12M`).
    pub motor_12_mv: u16,
    /// Motor pair, both batteries (`Bat24M`).
    pub motor_24_mv: u16,
}

impl BatteryVoltages {
    /// The thesis's limit: at or below 11 200 mV per battery (22 400 mV per pair) a battery is
    /// flat and running on would damage it.
    pub fn any_flat(&self) -> bool {
        self.logic_12_mv <= 11_200
            || self.motor_12_mv <= 11_200
            || self.logic_24_mv <= 22_400
            || self.motor_24_mv <= 22_400
    }
}
