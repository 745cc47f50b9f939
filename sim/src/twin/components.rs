//! What the twin's world is made of: resources shared by everything, and the components of a
//! robot entity.

use crate::devices::battery::Electrics;
use crate::devices::firmware::{BaseBoard, PanTiltFirmware};
use crate::devices::laser::{LaserFrame, LaserModel};
use crate::devices::motor::Motor;
use crate::devices::pan_tilt::{HeadAngles, PanTiltHead};
use crate::devices::sonar::SonarModel;
use crate::rng::SimRng;
use crate::world::WorldMap;
use bevy_ecs::prelude::*;
use core::time::Duration;
use rapier2d::prelude::{ColliderHandle, PhysicsWorld, RigidBodyHandle};
use robot::odometry::{History, PoseHistory};
use robot::{Pose2, Stamp};
use std::collections::VecDeque;

/// Length of one firmware tick: the base microcontroller's real-time interrupt, 1.024 ms.
pub const TICK: Duration = Duration::from_nanos(1_024_000);

/// Firmware ticks per world step. The world steps every 8.192 ms; inside a step the firmware and
/// the motors run tick by tick.
pub const TICKS_PER_STEP: u32 = 8;

/// Length of one world step.
pub const STEP: Duration = Duration::from_nanos(1_024_000 * TICKS_PER_STEP as u64);

/// The simulated clock: the step being computed covers `(step_start, now]`.
#[derive(Resource, Copy, Clone, Debug, Default)]
pub struct SimClock {
    /// Start of the current step.
    pub step_start: Stamp,
    /// End of the current step (the world's time once the step is done).
    pub now: Stamp,
}

/// The rapier world: bodies, colliders and the pipelines that move them.
#[derive(Resource)]
pub struct Physics(pub PhysicsWorld);

/// The static surfaces, for ray casts: shared with the fleet's other robots and with the run's
/// record, which draws and checks against the same map.
#[derive(Resource)]
pub struct Map(pub std::sync::Arc<WorldMap>);

/// Whether a step in which a robot alone (not one of a fleet) moves clear of every wall is
/// integrated without rapier's solver ([`super::systems::step_physics`]): on unless a reference
/// run turns it off.
#[derive(Resource)]
pub struct Gliding(pub bool);

/// Other robots' bodies in the same world (a [`super::fleet::Fleet`]'s), as their lasers see
/// them: empty for a robot alone.
#[derive(Resource, Default)]
pub struct OtherRobots {
    /// Every robot's body, this one's included.
    pub all: std::sync::Arc<Vec<crate::devices::laser::beam::Disc>>,
    /// This robot's place in `all`.
    pub me: usize,
    /// The others near enough to touch, as immovable discs in this robot's physics, by their
    /// place in `all`.
    pub near: std::collections::BTreeMap<usize, rapier2d::prelude::RigidBodyHandle>,
}

/// The base microcontroller board of a robot.
#[derive(Component)]
pub struct Board(pub BaseBoard);

/// The two drive motors, and how far their rotors turned during the current step.
#[derive(Component)]
pub struct Drivetrain {
    /// Left motor.
    pub left: Motor,
    /// Right motor.
    pub right: Motor,
    /// Rotor rotation this step, radians (left, right).
    pub rotation: [f64; 2],
}

/// How the wheels meet the floor: true wheel sizes and track, and random slip.
#[derive(Component)]
pub struct Traction {
    /// True wheel radii, metres (left, right).
    pub radius: [f64; 2],
    /// True track, metres.
    pub track: f64,
    /// Motor turns per wheel turn.
    pub gear_ratio: f64,
    /// Slip noise, √m (see `NoiseSettings::slip_sigma_sqrt_m`).
    pub slip_sigma: f64,
    /// One random stream per wheel.
    pub rng: [SimRng; 2],
}

/// The robot's batteries.
#[derive(Component)]
pub struct Power(pub Electrics);

/// The rigid body and collider of a robot's base.
#[derive(Component)]
pub struct Chassis {
    /// The rapier body (origin at the wheel axle's centre).
    pub body: RigidBodyHandle,
    /// The round footprint.
    pub collider: ColliderHandle,
    /// Radius of the footprint, metres.
    pub radius: f64,
    /// Centre of the footprint ahead of the axle, metres.
    pub center_x: f64,
    /// Height of the robot, metres.
    pub height: f64,
    /// The footprint touches a wall now.
    pub touching: bool,
    /// Times the footprint came into contact with a wall.
    pub collisions: u32,
    /// Where the footprint's centre was when its distance to the nearest face was last
    /// measured, and that distance: a lower bound of the distance from anywhere near.
    pub clearance: Option<([f64; 2], f64)>,
}

/// The true path of a robot's base.
#[derive(Component)]
pub struct Trajectory {
    /// Pose at the start of the current step.
    pub previous: (Stamp, Pose2),
    /// Pose now.
    pub current: (Stamp, Pose2),
    /// Pose at the end of every step; the body moves at constant velocity within a step, so
    /// interpolating it gives the pose at any time.
    pub history: PoseHistory,
    /// Length of the path, metres.
    pub distance: f64,
}

impl Trajectory {
    /// A path that starts at `pose` at time zero.
    pub fn starting_at(pose: Pose2) -> Self {
        let mut history = PoseHistory::unbounded();
        history.push(Stamp::ZERO, pose);
        Trajectory {
            previous: (Stamp::ZERO, pose),
            current: (Stamp::ZERO, pose),
            history,
            distance: 0.0,
        }
    }
}

/// A scan the laser has measured, on its way to the host. The beams are cast when the host
/// takes it (the world is static, so the result is the same as at `stamp`), with noise from
/// substream `index` of the laser's stream.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PendingScan {
    /// When the scan was measured.
    pub stamp: Stamp,
    /// When it reaches the host.
    pub delivery: Stamp,
    /// The base's true pose at `stamp`.
    pub base: Pose2,
    /// The laser's true frame at `stamp`.
    pub frame: LaserFrame,
    /// The scan's number since power-on.
    pub index: u64,
}

/// A laser on a robot, with the scans on their way to the host.
#[derive(Component)]
pub struct Lidar {
    /// Geometry, noise and timing.
    pub model: LaserModel,
    /// Seed of the laser's random stream.
    pub stream_seed: u64,
    /// When the next scan is measured.
    pub next_due: Stamp,
    /// When the serial line finishes the telegram it is sending.
    pub line_free: Stamp,
    /// Number of the next scan.
    pub next_index: u64,
    /// Scans measured and not yet taken by the host.
    pub outbox: VecDeque<PendingScan>,
}

/// A robot's sonar ring: the acoustic model and when each reading was measured.
#[derive(Component)]
pub struct Sonars {
    /// What each transducer hears.
    pub model: SonarModel,
    /// Seed of the ring's random stream.
    pub stream_seed: u64,
    /// Shots fired since power-on (numbers each shot's substream).
    pub shots: u64,
    /// When the reading of each position of the firing sequence was stored.
    pub measured: [Option<Stamp>; 16],
}

/// The pan-tilt unit a robot's laser rides on: its microcontroller board and the head it drives.
#[derive(Component)]
pub struct PanTiltUnit {
    /// The pan-tilt microcontroller with its serial port.
    pub board: crate::devices::firmware::Board<PanTiltFirmware>,
    /// Motors, encoders, switches and the laser's geometry.
    pub head: PanTiltHead,
    /// The head's angles at the end of every step (and at time zero); the head turns at constant
    /// speed within a step, so interpolating gives the angles at any time.
    pub history: History<HeadAngles>,
}

/// Where a robot's laser looks with the base at `base` at time `t`: on its fixed mount, or on
/// the pan-tilt head; `None` outside the head's recorded time.
pub fn laser_frame(
    lidar: &Lidar,
    unit: Option<&PanTiltUnit>,
    base: Pose2,
    t: Stamp,
) -> Option<LaserFrame> {
    match unit {
        Some(unit) => Some(unit.head.laser_frame(base, unit.history.at(t)?)),
        None => Some(lidar.model.frame_on(base)),
    }
}
