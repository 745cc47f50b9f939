//! The systems of one world step, in the order the schedule runs them:
//!
//! 1. [`advance_clock`] — the step covers `(step_start, now]`;
//! 2. [`run_drive_electronics`] — tick by tick: the motors turn under the H-bridge inputs, the
//!    board's interrupt fires and its main loop runs the firmware;
//! 3. [`drive_chassis`] — the wheels' rotation becomes travel on the floor (true wheel sizes,
//!    random slip) and a velocity for the base's rigid body;
//! 4. [`step_physics`] — rapier moves the body and stops it at walls;
//! 5. [`track_pose`] — the true pose is recorded and contacts counted;
//! 6. [`run_pan_tilt`] — tick by tick: the pan-tilt's motors turn, its encoders, index pulses
//!    and switches interrupt its microcontroller, whose main loop runs;
//! 7. [`sense_lasers`] — scans due within the step are recorded with the interpolated pose and
//!    laser frame (their beams are cast when the host takes them).

use super::components::*;
use crate::world::WorldMap;
use bevy_ecs::prelude::*;
use rand_distr::{Distribution, StandardNormal};
use rapier2d::prelude::Vector;
use robot::Pose2;

/// Moves the clock one step forward.
pub fn advance_clock(mut clock: ResMut<SimClock>) {
    clock.step_start = clock.now;
    clock.now += STEP;
}

/// Runs each robot's motors and base microcontroller through the step's ticks, and answers the
/// sonar shots the firmware fires.
pub fn run_drive_electronics(
    clock: Res<SimClock>,
    map: Res<Map>,
    mut robots: Query<(
        &mut Board,
        &mut Drivetrain,
        &mut Power,
        &Trajectory,
        Option<&mut Sonars>,
    )>,
) {
    let dt = TICK.as_secs_f64();
    for (mut board, mut drive, mut power, path, mut sonars) in &mut robots {
        let drive = &mut *drive;
        let mut tick_time = clock.step_start;
        for _ in 0..TICKS_PER_STEP {
            tick_time += TICK;
            let (left_bridge, right_bridge) = board.0.firmware().bridges();
            let supply = power.0.motor_supply_v();
            let left = drive.left.advance(left_bridge, supply, dt);
            let right = drive.right.advance(right_bridge, supply, dt);
            drive.rotation[0] += left.rotation;
            drive.rotation[1] += right.rotation;
            power.0.draw(left.supply_current + right.supply_current, dt);
            let adc = power.0.adc();
            let (l, r) = (&mut drive.left, &mut drive.right);
            board.0.tick(
                tick_time,
                |fw| fw.rti_interrupt(adc),
                |fw| fw.latch_encoders(l.take_edges(), r.take_edges()),
            );
            if let Some(sonars) = sonars.as_deref_mut() {
                listen_for_echoes(&mut board.0, sonars, &map.0, path.current.1, tick_time);
            }
        }
    }
}

/// Answers a shot fired during this tick with its echo, if it comes back within the echo window,
/// and notes when a reading is stored.
fn listen_for_echoes(
    board: &mut crate::devices::firmware::BaseBoard,
    sonars: &mut Sonars,
    map: &crate::world::WorldMap,
    base: robot::Pose2,
    now: robot::Stamp,
) {
    let fw = board.firmware_mut();
    if let Some(k) = fw.take_sonar_fired() {
        let mut rng = crate::rng::substream(sonars.stream_seed, sonars.shots);
        sonars.shots += 1;
        if let Some(distance) = sonars.model.echo(map, base, usize::from(k), &mut rng) {
            let units = robot::hardware::echo_units(distance, robot::hardware::SPEED_OF_SOUND);
            let window_units = f64::from(fw.sonar_window_ticks()) * TICK.as_secs_f64()
                / robot::hardware::SONAR_TIME_UNIT_S;
            if f64::from(units) < window_units {
                fw.sonar_echo(units);
            }
        }
    }
    if let Some(slot) = fw
        .take_sonar_stored()
        .and_then(|p| sonars.measured.get_mut(p))
    {
        *slot = Some(now);
    }
}

/// Turns the wheels' rotation into floor travel and sets the base's velocity for the step.
pub fn drive_chassis(
    mut physics: ResMut<Physics>,
    mut robots: Query<(&mut Drivetrain, &mut Traction, &Chassis)>,
) {
    let dt = STEP.as_secs_f64();
    for (mut drive, mut traction, chassis) in &mut robots {
        let rotation = std::mem::take(&mut drive.rotation);
        let traction = &mut *traction;
        let mut travel = [0.0; 2];
        for wheel in 0..2 {
            let d = rotation[wheel] / traction.gear_ratio * traction.radius[wheel];
            let slip = if traction.slip_sigma > 0.0 && d != 0.0 {
                let n: f64 = StandardNormal.sample(&mut traction.rng[wheel]);
                traction.slip_sigma * d.abs().sqrt() * n
            } else {
                0.0
            };
            travel[wheel] = d + slip;
        }
        let dtheta = (travel[1] - travel[0]) / traction.track;
        let ds = 0.5 * (travel[0] + travel[1]);
        let half = 0.5 * dtheta;
        let chord = if half.abs() < 1e-12 {
            ds
        } else {
            ds * half.sin() / half
        };
        let body = &mut physics.0.bodies[chassis.body];
        let heading = f64::from(body.rotation().angle()) + half;
        let velocity = Vector::new(
            (chord * heading.cos() / dt) as f32,
            (chord * heading.sin() / dt) as f32,
        );
        let moving = chord != 0.0 || dtheta != 0.0;
        body.set_linvel(velocity, moving);
        body.set_angvel((dtheta / dt) as f32, moving);
    }
}

/// Advances the rigid bodies by one step.
///
/// A step in which the robot (alone in its world, not one of a fleet) moves far from any wall is
/// integrated here, as rapier's solver integrates a body with no contact (`glide`), without
/// the solver's fixed cost: the same positions to the last bit (every scenario's files are
/// compared byte for byte with and without it, `tests/issue_17_glide.rs`).
pub fn step_physics(
    mut physics: ResMut<Physics>,
    map: Res<Map>,
    others: Res<OtherRobots>,
    gliding: Res<Gliding>,
    mut robots: Query<&mut Chassis>,
) {
    let physics = &mut physics.0;
    // A fleet's robots do not glide: their neighbours' discs come and go in each other's
    // physics, and a rapier that saw those changes late would order its contacts otherwise
    // (`tests/issue_17_fleet.rs` holds a fleet to the same bits either way).
    let mut free = gliding.0 && others.all.len() <= 1;
    for mut chassis in &mut robots {
        free = free && in_free_flight(physics, &map.0, &mut chassis);
    }
    if free {
        for chassis in &robots {
            glide(physics, chassis);
        }
        return;
    }
    physics.step();
}

/// Whether a robot's step can meet nothing: its body awake and moving (rapier puts still bodies
/// to sleep, which this step would not), slowly enough, and its footprint farther from every
/// face than it can travel in a step plus rapier's contact prediction, with a wide margin.
fn in_free_flight(
    physics: &rapier2d::prelude::PhysicsWorld,
    map: &WorldMap,
    chassis: &mut Chassis,
) -> bool {
    let body = &physics.bodies[chassis.body];
    let (v, w) = (body.linvel(), body.angvel());
    let dt = physics.integration_parameters.dt;
    let moving = v.x != 0.0 || v.y != 0.0 || w != 0.0;
    let slow = v.length() < 5.0 && (w * dt).abs() < 0.1;
    if body.is_sleeping() || !moving || !slow || !body.is_dynamic() {
        return false;
    }
    // The footprint's centre from the body's pose (a glided body's collider is only moved by
    // rapier's next step).
    let at = body
        .position()
        .transform_point(Vector::new(chassis.center_x as f32, 0.0));
    let at = [f64::from(at.x), f64::from(at.y)];
    let travel = f64::from(v.length() * dt) + chassis.center_x.abs() * f64::from((w * dt).abs());
    let reach = chassis.radius + travel + FREE_MARGIN;
    // The distance to the nearest face shrinks at most as fast as the footprint moves: measured
    // again only when that bound no longer clears it.
    let bound =
        |(from, clearance): ([f64; 2], f64)| clearance - (at[0] - from[0]).hypot(at[1] - from[1]);
    if chassis.clearance.is_none_or(|c| bound(c) <= reach) {
        chassis.clearance = Some((at, map.clearance(at)));
    }
    chassis.clearance.is_some_and(|c| bound(c) > reach)
}

/// How much farther than a step's travel a robot must be from every face to glide, metres:
/// far above rapier's contact prediction (2 mm).
const FREE_MARGIN: f64 = 0.05;

/// Moves a body by its velocity over one step as rapier's solver does for a body that meets
/// nothing: about its centre of mass, the rotation advanced to first order and normalised.
fn glide(physics: &mut rapier2d::prelude::PhysicsWorld, chassis: &Chassis) {
    let dt = physics.integration_parameters.dt;
    let body = &mut physics.bodies[chassis.body];
    let com = body.local_center_of_mass();
    let (v, w) = (body.linvel(), body.angvel());
    let mut pose = body.position().prepend_translation(com);
    let dang = w * dt;
    let (re, im) = (pose.rotation.re, pose.rotation.im);
    let mut rotation =
        rapier2d::math::Rotation::from_cos_sin_unchecked(re - dang * im, im + dang * re);
    rotation.normalize_mut();
    pose.rotation = rotation;
    pose.translation += v * dt;
    body.set_position(pose.prepend_translation(-com), false);
}

/// Records where each base is now and whether it touches a wall.
pub fn track_pose(
    physics: Res<Physics>,
    clock: Res<SimClock>,
    mut robots: Query<(&mut Chassis, &mut Trajectory)>,
) {
    for (mut chassis, mut path) in &mut robots {
        let body = &physics.0.bodies[chassis.body];
        let t = body.translation();
        let pose = Pose2::new(
            f64::from(t.x),
            f64::from(t.y),
            f64::from(body.rotation().angle()),
        );
        path.previous = path.current;
        path.current = (clock.now, pose);
        path.distance += path.previous.1.distance(&pose);
        path.history.push(clock.now, pose);
        let touching = physics
            .0
            .narrow_phase
            .contact_pairs_with(chassis.collider)
            .any(|pair| pair.has_any_active_contact());
        if touching && !chassis.touching {
            chassis.collisions += 1;
        }
        chassis.touching = touching;
    }
}

/// Runs each robot's pan-tilt microcontroller and head through the step's ticks.
pub fn run_pan_tilt(clock: Res<SimClock>, mut robots: Query<(&mut PanTiltUnit, &mut Power)>) {
    let dt = TICK.as_secs_f64();
    for (mut unit, mut power) in &mut robots {
        let unit = &mut *unit;
        let mut tick_time = clock.step_start;
        for _ in 0..TICKS_PER_STEP {
            tick_time += TICK;
            let supply = power.0.motor_supply_v();
            let head = &mut unit.head;
            let mut current = 0.0;
            unit.board
                .tick(tick_time, |fw| current = head.tick(fw, supply, dt), |_| {});
            power.0.draw(current, dt);
        }
        unit.history.push(clock.now, unit.head.angles());
    }
}

/// Records the scans that fell due during the step, with the pose and laser frame at their
/// exact time.
pub fn sense_lasers(
    clock: Res<SimClock>,
    mut robots: Query<(&Trajectory, &mut Lidar, Option<&PanTiltUnit>)>,
) {
    for (path, mut lidar, unit) in &mut robots {
        let lidar = &mut *lidar;
        let timing = lidar.model.timing();
        while lidar.next_due <= clock.now {
            let t = lidar.next_due;
            let (t0, p0) = path.previous;
            let (t1, p1) = path.current;
            let s = if t1 > t0 {
                (t.0.saturating_sub(t0.0) as f64 / (t1.0 - t0.0) as f64).min(1.0)
            } else {
                1.0
            };
            let base = p0.interpolate(&p1, s);
            let frame = laser_frame(lidar, unit, base, t)
                .expect("run_pan_tilt has recorded the head up to the end of the step");
            let delivery = timing.delivery(t, lidar.line_free);
            lidar.line_free = delivery;
            lidar.outbox.push_back(PendingScan {
                stamp: t,
                delivery,
                base,
                frame,
                index: lidar.next_index,
            });
            lidar.next_index += 1;
            lidar.next_due = timing.next_scan(t, lidar.line_free);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::devices::laser::LaserModel;
    use bevy_ecs::system::RunSystemOnce;
    use robot::Stamp;
    use std::collections::VecDeque;

    /// `sense_lasers` on a hand-built world: a scan falling due inside a step is queued with
    /// the pose interpolated at its exact time and the delivery time of its telegram.
    #[test]
    fn a_scan_due_mid_step_gets_the_interpolated_pose() {
        let desc = crate::devices::laser::lms_description(0.0);
        let model = LaserModel::new(&desc, Pose2::IDENTITY, 0.0, crate::config::Outliers::NONE);
        let timing = model.timing();
        let mut world = World::new();
        world.insert_resource(SimClock {
            step_start: Stamp::from_millis(100),
            now: Stamp::from_millis(110),
        });
        let mut path = Trajectory::starting_at(Pose2::new(0.0, 0.0, 0.0));
        path.previous = (Stamp::from_millis(100), Pose2::new(1.0, 0.0, 0.0));
        path.current = (Stamp::from_millis(110), Pose2::new(2.0, 0.0, 0.2));
        let robot = world
            .spawn((
                path,
                Lidar {
                    model,
                    stream_seed: 1,
                    next_due: Stamp::from_millis(104),
                    line_free: Stamp::ZERO,
                    next_index: 7,
                    outbox: VecDeque::new(),
                },
            ))
            .id();
        world.run_system_once(sense_lasers).unwrap();
        let lidar = world.get::<Lidar>(robot).unwrap();
        assert_eq!(lidar.outbox.len(), 1);
        let scan = lidar.outbox[0];
        assert_eq!(scan.stamp, Stamp::from_millis(104));
        assert_eq!(
            scan.delivery,
            Stamp::from_millis(104) + timing.sweep + timing.transfer
        );
        assert_eq!(scan.index, 7);
        assert!((scan.base.x - 1.4).abs() < 1e-12 && (scan.base.theta - 0.08).abs() < 1e-12);
        assert_eq!(lidar.next_index, 8);
        assert!(
            lidar.next_due > Stamp::from_millis(110),
            "the next scan is due after this step"
        );
    }
}
