//! The twin behind the hardware contract: exchanges take the time the 9600 bps line takes, the
//! firmware's wait waits, and the batteries read like the firmware's `t`.

use crate::common::*;
use robot::hardware::{Batteries, DriveBase, DriveWait};
use sim::config::NoiseSettings;

/// Ten bit-times at 9600 bps, nanoseconds.
const BYTE_NS: u64 = 1_041_666;
/// One firmware tick, nanoseconds.
const TICK_NS: u64 = 1_024_000;

#[test]
fn a_status_query_costs_its_serial_round_trip() {
    let mut r = pioneer_in(&big_room(), NoiseSettings::NONE, 1);
    let before = r.host_time();
    let status = r.drive_status().unwrap();
    let took = r.host_time().nanos() - before.nanos();
    // "l\n" out, "l0.00 0.00 0 0 0\n" (17 bytes) back, executed at the next firmware tick.
    let wire = 19 * BYTE_NS;
    assert!(
        (wire..=wire + TICK_NS + 1000).contains(&took),
        "took {took} ns"
    );
    assert!(
        status.stamp > before && status.stamp < r.host_time(),
        "stamped when the firmware read its counters"
    );
}

#[test]
fn the_firmware_wait_waits_its_ticks() {
    let mut r = pioneer_in(&big_room(), NoiseSettings::NONE, 1);
    let before = r.host_time();
    r.wait_drive(DriveWait::sleep(500)).unwrap();
    let took = r.host_time().nanos() - before.nanos();
    // "w500\n" out, 500 ticks of 1.024 ms, "w\n" back.
    let expected = 7 * BYTE_NS + 500 * TICK_NS;
    assert!(
        (expected..=expected + 2 * TICK_NS).contains(&took),
        "took {took} ns, expected {expected}"
    );
}

#[test]
fn waiting_for_the_motors_returns_when_the_move_ends() {
    let mut r = pioneer_in(&big_room(), NoiseSettings::NONE, 1);
    r.advance(535).unwrap();
    let before = r.host_time();
    r.wait_drive(DriveWait::motors(20_000)).unwrap();
    let took = r.host_time().nanos() - before.nanos();
    assert!(
        took > 1_000_000_000 && took < 5_000_000_000,
        "a 0.5 m move took {took} ns"
    );
    assert!(r.drive_status().unwrap().is_idle());
}

#[test]
fn batteries_read_like_the_firmware_and_sag_under_the_motors() {
    let mut r = pioneer_in(&big_room(), NoiseSettings::NONE, 1);
    let rest = r.battery_voltages().unwrap();
    assert!((12_400..=12_800).contains(&rest.logic_12_mv), "{rest:?}");
    assert!((24_800..=25_600).contains(&rest.logic_24_mv), "{rest:?}");
    assert!(!rest.any_flat());
    r.advance(2000).unwrap();
    r.wait_drive(DriveWait::sleep(1500)).unwrap();
    let moving = r.battery_voltages().unwrap();
    assert!(
        moving.motor_24_mv < rest.motor_24_mv,
        "{rest:?} -> {moving:?}"
    );
    assert!(
        moving.logic_24_mv <= rest.logic_24_mv,
        "{rest:?} -> {moving:?}"
    );
}
