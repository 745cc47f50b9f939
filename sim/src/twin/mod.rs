//! The twin's world: a bevy_ecs [`World`] stepped by one explicitly ordered schedule.
//!
//! Resources hold what is shared — the clock, the rapier world, the static map — and a robot is an
//! entity whose components are its parts: the base microcontroller board, the drive train, the
//! traction on the floor, the batteries, the chassis body, its true trajectory and its laser —
//! and, when the robot has them, its sonar ring and its pan-tilt unit (a second microcontroller
//! board and the head it drives, which carries the laser). The schedule runs with the
//! single-threaded executor and refuses ambiguous system order, so two
//! runs with the same seed are bit-identical.
//!
//! One step is [`STEP`] = 8 firmware ticks (8.192 ms): inside it the firmware and motors run
//! tick by tick, then the body moves once. See [`systems`] for the order.

pub mod components;
pub mod fleet;
pub mod sim_robot;
pub mod systems;

pub use components::{STEP, TICK, TICKS_PER_STEP};

use crate::config::{ConfigError, NoiseSettings, RobotDescription, WorldDescription};
use crate::devices::battery::Electrics;
use crate::devices::firmware::{BaseBoard, BaseFirmware, Board as McuBoard, PanTiltFirmware};
use crate::devices::laser::beam::Disc;
use crate::devices::laser::{LaserFrame, LaserModel};
use crate::devices::motor::{Motor, MotorParams};
use crate::devices::pan_tilt::{HeadAngles, PanTiltHead};
use crate::devices::sonar::SonarModel;
use crate::rng;
use crate::world::WorldMap;
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, SingleThreadedExecutor};
use components::*;
use rapier2d::prelude::*;
use robot::hardware::LaserScan;
use robot::odometry::History;
use robot::{Pose2, Stamp};
use std::collections::VecDeque;
use std::sync::Arc;

/// A running twin: one robot in one world.
pub struct Twin {
    world: World,
    schedule: Schedule,
    robot: Entity,
}

impl Twin {
    /// Builds the world and puts the robot at the world's start pose.
    ///
    /// Fails with an error naming the world file when the robot's footprint overlaps a wall at
    /// the start.
    pub fn new(
        world_desc: &WorldDescription,
        robot_desc: &RobotDescription,
        noise: &NoiseSettings,
        seed: u64,
    ) -> Result<Twin, ConfigError> {
        let map = Arc::new(WorldMap::new(world_desc));
        Twin::in_map(world_desc, map, robot_desc, noise, seed)
    }

    /// As [`Twin::new`], in `map`, the map of `world_desc` already built (robots of one world
    /// share it).
    pub fn in_map(
        world_desc: &WorldDescription,
        map: Arc<WorldMap>,
        robot_desc: &RobotDescription,
        noise: &NoiseSettings,
        seed: u64,
    ) -> Result<Twin, ConfigError> {
        let start = world_desc.start;
        let radius = robot_desc.body.radius_m.get();
        let centre = start.transform_point(robot_desc.body.center_x_m.get(), 0.0);
        let clearance = map.clearance([centre.0, centre.1]);
        if clearance < radius {
            return Err(ConfigError {
                path: world_desc.path.clone(),
                line: None,
                column: None,
                field: Some("start".into()),
                message: format!(
                    "the robot `{}` (radius {radius} m) overlaps a wall at the start pose: the nearest wall is {clearance:.3} m from its centre",
                    robot_desc.name
                ),
                excerpt: None,
            });
        }

        // Seen from above: no gravity. The base's velocity is set every step, so one solver
        // iteration is enough to keep it out of the walls.
        let mut physics = PhysicsWorld {
            gravity: Vector::ZERO,
            ..PhysicsWorld::default()
        };
        physics.integration_parameters.dt = STEP.as_secs_f32();
        physics.integration_parameters.num_solver_iterations = 1;
        let (vertices, indices) = map.obstacles_below(robot_desc.body.height_m.get());
        if !indices.is_empty() {
            physics.insert(
                RigidBodyBuilder::fixed(),
                ColliderBuilder::polyline(vertices, Some(indices)),
            );
        }
        let mass = robot_desc.body.mass_kg.get();
        let inertia = 0.5 * mass * radius * radius;
        let (body, collider) = physics.insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(start.x as f32, start.y as f32))
                .rotation(start.theta as f32)
                .ccd_enabled(true)
                .additional_mass_properties(MassProperties::new(
                    Vector::ZERO,
                    mass as f32,
                    inertia as f32,
                )),
            ColliderBuilder::ball(radius as f32)
                .translation(Vector::new(robot_desc.body.center_x_m.get() as f32, 0.0))
                .density(0.0)
                .friction(0.3),
        );

        let geometry = robot_desc.geometry();
        let nominal_radius = 0.5 * geometry.wheel_diameter_m;
        let scale = 1.0 + noise.wheel_scale_error;
        let half_ratio = 0.5 * noise.wheel_diameter_ratio_error;
        let radius_true = [
            nominal_radius * scale * (1.0 - half_ratio),
            nominal_radius * scale * (1.0 + half_ratio),
        ];
        let motor = |wheel_radius: f64| {
            let reflected = 0.5 * mass * (wheel_radius / geometry.gear_ratio).powi(2);
            Motor::new(MotorParams::from_datasheet(
                &robot_desc.motor,
                geometry.gear_ratio,
                geometry.counts_per_rotor_turn,
                reflected,
            ))
        };
        let laser = LaserModel::new(
            &robot_desc.laser,
            robot_desc.laser_mount(),
            noise.laser_sigma_m,
            noise.outliers,
        );

        let mut world = World::new();
        world.insert_resource(SimClock::default());
        world.insert_resource(Physics(physics));
        world.insert_resource(Map(map));
        world.insert_resource(OtherRobots::default());
        world.insert_resource(Gliding(true));
        let robot = world
            .spawn((
                Board(BaseBoard::power_on(robot_desc.drive.serial_baud)),
                Drivetrain {
                    left: motor(radius_true[0]),
                    right: motor(radius_true[1]),
                    rotation: [0.0; 2],
                },
                Traction {
                    radius: radius_true,
                    track: geometry.track_m * (1.0 + noise.track_error),
                    gear_ratio: geometry.gear_ratio,
                    slip_sigma: noise.slip_sigma_sqrt_m,
                    rng: [
                        rng::stream(seed, "slip/left"),
                        rng::stream(seed, "slip/right"),
                    ],
                },
                Power(Electrics::new(&robot_desc.battery)),
                Chassis {
                    body,
                    collider,
                    radius,
                    center_x: robot_desc.body.center_x_m.get(),
                    height: robot_desc.body.height_m.get(),
                    touching: false,
                    collisions: 0,
                    clearance: None,
                },
                Trajectory::starting_at(start),
                Lidar {
                    next_due: laser.timing().first_scan(),
                    line_free: Stamp::ZERO,
                    next_index: 0,
                    model: laser,
                    stream_seed: rng::stream_seed(seed, "laser"),
                    outbox: VecDeque::new(),
                },
            ))
            .id();
        if let Some(sonar) = &robot_desc.sonar {
            world.entity_mut(robot).insert(Sonars {
                model: SonarModel::new(sonar),
                stream_seed: rng::stream_seed(seed, "sonar"),
                shots: 0,
                measured: [None; 16],
            });
        }
        if let Some(pt) = &robot_desc.pan_tilt {
            let head = PanTiltHead::new(pt);
            world.entity_mut(robot).insert(PanTiltUnit {
                board: McuBoard::new(head.power_on_firmware(), pt.serial_baud),
                history: {
                    let mut history = History::unbounded();
                    history.push(Stamp::ZERO, head.angles());
                    history
                },
                head,
            });
        }

        let mut schedule = Schedule::default();
        schedule.set_executor(SingleThreadedExecutor::new());
        schedule.set_build_settings(ScheduleBuildSettings {
            ambiguity_detection: LogLevel::Error,
            ..Default::default()
        });
        schedule.add_systems(
            (
                systems::advance_clock,
                systems::run_drive_electronics,
                systems::drive_chassis,
                systems::step_physics,
                systems::track_pose,
                systems::run_pan_tilt,
                systems::sense_lasers,
            )
                .chain(),
        );
        schedule
            .initialize(&mut world)
            .expect("the twin's schedule is totally ordered");
        Ok(Twin {
            world,
            schedule,
            robot,
        })
    }

    /// The robot's body where it stands now, as other robots' lasers see it.
    pub fn body_disc(&self) -> Disc {
        self.disc_at(self.true_pose())
    }

    /// The robot's body with its base at `base`.
    fn disc_at(&self, base: Pose2) -> Disc {
        let chassis = self.component::<Chassis>();
        let (cx, cy) = base.transform_point(chassis.center_x, 0.0);
        Disc {
            center: [cx, cy],
            radius: chassis.radius,
            height: chassis.height,
        }
    }

    /// Every robot's body in the world (this one's at `me`), which this robot's laser meets
    /// from now on and its body bumps into (see [`fleet::Fleet`]): those within reach of its own
    /// body this step stand in its physics as immovable discs, so a robot is stopped by another
    /// as by a wall.
    pub fn set_other_robots(&mut self, all: std::sync::Arc<Vec<Disc>>, me: usize) {
        let own = self.body_disc();
        let mut near = std::mem::take(&mut self.world.resource_mut::<OtherRobots>().near);
        let mut physics = self.world.resource_mut::<Physics>();
        let physics = &mut physics.0;
        // Within a step a base moves centimetres: a disc farther than half a metre beyond
        // touching cannot be met before the next step.
        let reaches = |d: &Disc| {
            let gap = (d.center[0] - own.center[0]).hypot(d.center[1] - own.center[1]);
            gap < d.radius + own.radius + 0.5
        };
        let wanted: Vec<usize> = (0..all.len())
            .filter(|&j| j != me && reaches(&all[j]))
            .collect();
        let gone: Vec<usize> = near
            .keys()
            .copied()
            .filter(|j| !wanted.contains(j))
            .collect();
        for j in gone {
            if let Some(handle) = near.remove(&j) {
                physics.remove_body(handle);
            }
        }
        for j in wanted {
            let at = Vector::new(all[j].center[0] as f32, all[j].center[1] as f32);
            match near.get(&j) {
                Some(&handle) => {
                    if let Some(body) = physics.bodies.get_mut(handle) {
                        body.set_next_kinematic_translation(at);
                    }
                }
                None => {
                    let (handle, _) = physics.insert(
                        RigidBodyBuilder::kinematic_position_based().translation(at),
                        ColliderBuilder::ball(all[j].radius as f32).friction(0.3),
                    );
                    near.insert(j, handle);
                }
            }
        }
        *self.world.resource_mut::<OtherRobots>() = OtherRobots { all, me, near };
    }

    /// Whether steps clear of every wall skip rapier's solver (the default; the positions are
    /// the same to the last bit either way).
    pub fn set_gliding(&mut self, on: bool) {
        self.world.insert_resource(Gliding(on));
    }

    /// Advances the world by one [`STEP`].
    pub fn step(&mut self) {
        self.schedule.run(&mut self.world);
    }

    /// The world's time: the end of the last step.
    pub fn now(&self) -> Stamp {
        self.world.resource::<SimClock>().now
    }

    /// The ECS world, to inspect anything.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The ECS world, to change anything (tests and tools).
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// The robot's entity.
    pub fn robot(&self) -> Entity {
        self.robot
    }

    fn component<T: Component>(&self) -> &T {
        self.world
            .get::<T>(self.robot)
            .expect("the robot entity has all its components")
    }

    fn component_mut<T: Component<Mutability = bevy_ecs::component::Mutable>>(
        &mut self,
    ) -> Mut<'_, T> {
        self.world
            .get_mut::<T>(self.robot)
            .expect("the robot entity has all its components")
    }

    /// The base microcontroller board.
    pub fn board(&self) -> &BaseBoard {
        &self.component::<Board>().0
    }

    /// The base microcontroller board, to send it bytes and read its replies.
    pub fn board_mut(&mut self) -> &mut BaseBoard {
        &mut self.component_mut::<Board>().into_inner().0
    }

    /// The base's firmware.
    pub fn firmware(&self) -> &BaseFirmware {
        self.board().firmware()
    }

    /// When the next scan on its way reaches the host.
    pub fn next_scan_delivery(&self) -> Option<Stamp> {
        self.component::<Lidar>().outbox.front().map(|p| p.delivery)
    }

    /// Takes the next scan on its way to the host, with its delivery time.
    pub fn pop_scan(&mut self) -> Option<(Stamp, LaserScan)> {
        let pending = self.component_mut::<Lidar>().outbox.pop_front()?;
        let map = &self.world.resource::<Map>().0;
        let lidar = self.component::<Lidar>();
        let body = self.disc_at(pending.base);
        let robots = self.world.resource::<OtherRobots>();
        let others: Vec<Disc> = robots
            .all
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != robots.me)
            .map(|(_, d)| *d)
            .collect();
        let mut rng = rng::substream(lidar.stream_seed, pending.index);
        let mut scan = lidar.model.scan_among(
            map,
            Some(body),
            &others,
            pending.frame,
            pending.stamp,
            &mut rng,
        );
        // The head's angles when the scan was measured, interpolated on its history.
        scan.head = self.head_angles_at(pending.stamp);
        Some((pending.delivery, scan))
    }

    /// Drops the next scan on its way without measuring it (nobody asked for it); returns its
    /// delivery time.
    pub fn drop_next_scan(&mut self) -> Option<Stamp> {
        self.component_mut::<Lidar>()
            .outbox
            .pop_front()
            .map(|p| p.delivery)
    }

    /// Drops, unmeasured, the scans on their way that were measured before `t`; returns the
    /// delivery time of the last one dropped.
    pub fn skip_scans_before(&mut self, t: Stamp) -> Option<Stamp> {
        let mut lidar = self.component_mut::<Lidar>();
        let mut last = None;
        while lidar.outbox.front().is_some_and(|p| p.stamp < t) {
            last = lidar.outbox.pop_front().map(|p| p.delivery);
        }
        last
    }

    /// The laser model.
    pub fn laser(&self) -> &LaserModel {
        &self.component::<Lidar>().model
    }

    /// The laser's true frame at `t` (on its fixed mount or on the pan-tilt head), or `None`
    /// outside the simulated time.
    pub fn laser_frame_at(&self, t: Stamp) -> Option<LaserFrame> {
        let base = self.true_pose_at(t)?;
        laser_frame(
            self.component::<Lidar>(),
            self.world.get::<PanTiltUnit>(self.robot),
            base,
            t,
        )
    }

    /// The pan-tilt microcontroller board, if the robot has a pan-tilt.
    pub fn pan_tilt_board(&self) -> Option<&McuBoard<PanTiltFirmware>> {
        self.world.get::<PanTiltUnit>(self.robot).map(|u| &u.board)
    }

    /// The pan-tilt microcontroller board, to send it bytes and read its replies.
    pub fn pan_tilt_board_mut(&mut self) -> Option<&mut McuBoard<PanTiltFirmware>> {
        self.world
            .get_mut::<PanTiltUnit>(self.robot)
            .map(|u| &mut u.into_inner().board)
    }

    /// The pan-tilt head, if the robot has one.
    pub fn pan_tilt_head(&self) -> Option<&PanTiltHead> {
        self.world.get::<PanTiltUnit>(self.robot).map(|u| &u.head)
    }

    /// The pan-tilt head's true angles at `t`, if the robot has one and `t` is simulated.
    pub fn head_angles_at(&self, t: Stamp) -> Option<HeadAngles> {
        self.world
            .get::<PanTiltUnit>(self.robot)
            .and_then(|u| u.history.at(t))
    }

    /// The map of the world the twin casts its rays in.
    pub fn map(&self) -> &Arc<WorldMap> {
        &self.world.resource::<Map>().0
    }

    /// The true pose of the base now.
    pub fn true_pose(&self) -> Pose2 {
        self.component::<Trajectory>().current.1
    }

    /// The true pose at `t`, or `None` outside the simulated time.
    pub fn true_pose_at(&self, t: Stamp) -> Option<Pose2> {
        self.component::<Trajectory>().history.at(t)
    }

    /// The true path, one pose per step, oldest first.
    pub fn true_path(&self) -> impl ExactSizeIterator<Item = (Stamp, Pose2)> + '_ {
        self.component::<Trajectory>().history.iter()
    }

    /// Length of the true path, metres.
    pub fn distance_travelled(&self) -> f64 {
        self.component::<Trajectory>().distance
    }

    /// Times the base came into contact with a wall.
    pub fn collisions(&self) -> u32 {
        self.component::<Chassis>().collisions
    }

    /// Whether the base touches a wall now.
    pub fn touching(&self) -> bool {
        self.component::<Chassis>().touching
    }

    /// Encoder edges of each wheel since the start, as a counter that never resets would show.
    pub fn encoder_edges(&self) -> (u64, u64) {
        let d = self.component::<Drivetrain>();
        (d.left.total_edges(), d.right.total_edges())
    }

    /// The sonar ring's model, if the robot has one.
    pub fn sonar(&self) -> Option<&SonarModel> {
        self.world.get::<Sonars>(self.robot).map(|s| &s.model)
    }

    /// When each position of the sonar firing sequence was last measured.
    pub fn sonar_measured(&self) -> [Option<Stamp>; 16] {
        self.world
            .get::<Sonars>(self.robot)
            .map_or([None; 16], |s| s.measured)
    }

    /// State of charge of the (logic, motor) battery pairs.
    pub fn battery_charge(&self) -> (f64, f64) {
        let p = &self.component::<Power>().0;
        (p.logic.charge(), p.motor.charge())
    }
}
