//! The base firmware model against the C code of the thesis (App. A.3.1): move lengths, the
//! acceleration ramp, turns in place, and the behaviours of the code that a controller must
//! know about (the `v` ramp-down, the main loop stalled by status replies).

use crate::common::*;
use robot::geometry::wrap_angle;
use robot::hardware::{DriveBase, DriveWait, Laser, Ramp};
use sim::config::NoiseSettings;
use sim::devices::firmware::BaseFirmware;
use sim::devices::motor::{Motor, MotorParams};
use std::time::Duration;

/// The firmware driving the twin's motor models, one 1.024 ms tick at a time, with nothing in
/// between (no serial timing, no body): what the C code sees.
struct Bench {
    fw: BaseFirmware,
    left: Motor,
    right: Motor,
}

impl Bench {
    fn new() -> Self {
        let robot = robot("pioneer-3dx");
        let g = robot.geometry();
        let load =
            0.5 * robot.body.mass_kg.get() * (0.5 * g.wheel_diameter_m / g.gear_ratio).powi(2);
        let params =
            MotorParams::from_datasheet(&robot.motor, g.gear_ratio, g.counts_per_rotor_turn, load);
        let mut fw = BaseFirmware::power_on();
        fw.take_output();
        Bench {
            fw,
            left: Motor::new(params),
            right: Motor::new(params),
        }
    }

    fn send(&mut self, line: &str) -> String {
        self.fw.receive(line.as_bytes());
        String::from_utf8(self.fw.take_output()).unwrap()
    }

    /// One tick; returns the edges each pulse accumulator counted.
    fn tick(&mut self) -> (u32, u32) {
        let (l, r) = self.fw.bridges();
        self.left.advance(l, 25.0, 1.024e-3);
        self.right.advance(r, 25.0, 1.024e-3);
        let edges = (self.left.take_edges(), self.right.take_edges());
        self.fw.rti_tick(edges.0, edges.1, [0; 4]);
        edges
    }
}

#[test]
fn a10_moves_each_wheel_1000_counts_within_one_loop() {
    let mut b = Bench::new();
    assert_eq!(b.send("a10\n"), "a\n");
    let mut last_counted = (0, 0);
    for _ in 0..10_000 {
        let on = b.fw.motors_on();
        let edges = b.tick();
        if on == (true, true) {
            last_counted = edges;
        }
        if b.fw.motors_on() == (false, false) {
            break;
        }
    }
    assert_eq!(b.fw.motors_on(), (false, false), "the move ended");
    let (l, r) = b.fw.totals();
    assert!(
        (1000..=1000 + last_counted.0).contains(&l),
        "left {l}, last loop {last_counted:?}"
    );
    assert!(
        (1000..=1000 + last_counted.1).contains(&r),
        "right {r}, last loop {last_counted:?}"
    );
    assert_eq!(
        b.send("l\n"),
        format!(
            "l{}.{:02} {}.{:02} 0 0 0\n",
            l / 100,
            l % 100,
            r / 100,
            r % 100
        )
    );
}

#[test]
fn ramp_raises_desired_speed_by_one_every_tc_plus_one_ticks() {
    let mut b = Bench::new();
    b.send("k5 30 10\n");
    b.send("a5000\n");
    assert_eq!(b.fw.desired_speeds(), (5, 5), "a move starts at Pi");
    let mut changes = Vec::new();
    let mut previous = b.fw.desired_speeds().0;
    for tick in 1..=2000 {
        b.tick();
        let now = b.fw.desired_speeds().0;
        if now != previous {
            changes.push((tick, now - previous));
            previous = now;
        }
    }
    // The timer reloads with Tc = 10 and acts once it has counted down: every 11 ticks.
    for (i, (tick, step)) in changes.iter().enumerate() {
        assert_eq!(*step, 1, "{changes:?}");
        assert_eq!(*tick, 11 * (i + 1), "{changes:?}");
    }
    // Acceleration ends when the measured speed is within 3 of Pf (`g_left_vel + 3 >=
    // k_vel_end`), so the cruise speed may stop short of Pf.
    assert!((27..=30).contains(&previous), "cruise at {previous}");
    assert!(changes.len() >= 22, "{changes:?}");
}

#[test]
fn turn_in_place_turns_by_the_angle_the_wheel_geometry_predicts() {
    let desc = robot("pioneer-3dx");
    let g = desc.geometry();
    let mut r = pioneer_in(&big_room(), NoiseSettings::NONE, 1);
    let tenths = g.tenths_for_turn(90f64.to_radians()).unwrap();
    let start = r.twin().true_pose();
    let edges0 = r.twin().encoder_edges();
    r.turn_left(tenths).unwrap();
    r.wait_drive(DriveWait::motors(30_000)).unwrap();
    r.wait_drive(DriveWait::sleep(400)).unwrap(); // `w400`: the wheels coast to a stop
    let end = r.twin().true_pose();
    let edges1 = r.twin().encoder_edges();
    let turned = wrap_angle(end.theta - start.theta);
    // The body turns exactly as far as the wheels say (to one count)...
    let counts = 0.5 * ((edges1.0 - edges0.0) + (edges1.1 - edges0.1)) as f64;
    let per_count = g.turn_for_counts(1.0);
    assert!(
        (turned - g.turn_for_counts(counts)).abs() < 2.0 * per_count,
        "{turned} vs {counts} counts"
    );
    // ...which is the commanded angle plus the coast after the brake, and stays in place.
    let commanded = g.turn_for_counts(f64::from(tenths) * 100.0);
    assert!(turned >= commanded, "{turned} < {commanded}");
    assert!(
        (turned - commanded).to_degrees() < 0.6,
        "{}°",
        turned.to_degrees()
    );
    assert!(
        start.distance(&end) < 1e-4,
        "turned in place: moved {} m",
        start.distance(&end)
    );
}

#[test]
fn v_ramps_down_because_the_braking_point_is_stale() {
    // set_vel neither resets the counters nor clicks_break, so check_stop_motors starts braking
    // at once and ac_control lowers the desired speeds by one every Tc + 1 ticks.
    let mut b = Bench::new();
    assert_eq!(b.send("v130 130\n"), "v\n");
    assert_eq!(b.fw.desired_speeds(), (30, 30));
    for _ in 0..(29 * 51) {
        b.tick();
    }
    let (l, _) = b.fw.desired_speeds();
    assert!((1..=2).contains(&l), "{l}");
    for _ in 0..2000 {
        b.tick();
    }
    assert_eq!(b.fw.desired_speeds(), (0, 0));
    assert_eq!(
        b.fw.motors_on(),
        (true, true),
        "the motors stay on at zero speed"
    );
    let edges = b.tick();
    assert!(
        edges.0 <= 1 && edges.1 <= 1,
        "the wheels have stopped: {edges:?}"
    );
}

/// Drives 535 tenths with the given ramp, polling `l` every 100 ms; returns (firmware counts,
/// true encoder edges) of the left wheel.
fn advance_while_polling(ramp: Ramp) -> (u32, u64) {
    let mut r = pioneer_in(&big_room(), NoiseSettings::NONE, 1);
    r.set_ramp(ramp).unwrap();
    let before = r.twin().encoder_edges().0;
    r.advance(535).unwrap();
    let status = loop {
        r.read_scan(Duration::from_millis(100)).unwrap();
        let s = r.drive_status().unwrap();
        if s.is_idle() {
            break s;
        }
    };
    r.wait_drive(DriveWait::sleep(400)).unwrap();
    (status.left_counts, r.twin().encoder_edges().0 - before)
}

#[test]
fn status_replies_stall_the_speed_loop_and_lose_counts_at_speed() {
    // Each `l` reply keeps the main loop in ser0_putchar for ~18 ms; the 8-bit pulse
    // accumulators saturate at 255 meanwhile. At 30 counts/tick that loses counts...
    let (counted, turned) = advance_while_polling(Ramp::POWER_ON);
    assert!(counted >= 53_500);
    assert!(
        turned > counted as u64 + 3000,
        "counted {counted}, turned {turned}"
    );
    // ...below ~13 counts/tick nothing is lost but the coast after the brake.
    let (counted, turned) = advance_while_polling(Ramp {
        initial: 5,
        top: 12,
        period_ms: 50,
    });
    assert!(counted >= 53_500);
    assert!(
        turned - (counted as u64) < 200,
        "counted {counted}, turned {turned}"
    );
}
