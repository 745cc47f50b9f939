//! Dead reckoning from the firmware's wheel counters, and a time-ordered history of poses that
//! can be interpolated to any instant — the odometry FIFO of Aparicio 2011, §7.3.3, which brings
//! odometry to the timestamp of a scan.
//!
//! The base firmware reports, with `l`, the encoder counts of each wheel since the last `a r i d`
//! command. Its encoders count edges without direction, so the odometer must know which way the
//! firmware drives each wheel: it watches the commands ([`Odometer::commanded`]) and the status
//! reports ([`Odometer::observe`]) in the order they happened. Poll the status just before sending
//! a new motion command, or the counts between the last poll and the command are lost.

use crate::drive_geometry::DriveGeometry;
use crate::geometry::{Pose2, wrap_angle};
use crate::hardware::{DriveCommand, DriveStatus, STATUS_COUNT_MODULUS};
use crate::time::Stamp;
use std::collections::VecDeque;

/// Integrates the firmware's wheel counters into a pose.
///
/// ```
/// use robot::hardware::{DriveCommand, DriveStatus};
/// use robot::odometry::Odometer;
/// use robot::{DriveGeometry, Pose2, Stamp};
/// let g = DriveGeometry { wheel_diameter_m: 0.195, track_m: 0.333, gear_ratio: 65.5, counts_per_rotor_turn: 1000 };
/// let mut odo = Odometer::new(g, Pose2::IDENTITY);
/// odo.commanded(&DriveCommand::Advance(535));
/// let done = DriveStatus { stamp: Stamp::ZERO, left_counts: 53_500, right_counts: 53_500,
///                          left_on: false, right_on: false, sonar_firing: false };
/// let pose = odo.observe(&done);
/// assert!((pose.x - 0.5004).abs() < 1e-3 && pose.y.abs() < 1e-12);
/// ```
#[derive(Clone, Debug)]
pub struct Odometer {
    geometry: DriveGeometry,
    pose: Pose2,
    /// Counters at the last observation, or `None` before the first one.
    last_counts: Option<(u32, u32)>,
    /// The direction the firmware drives each wheel: +1 forward, −1 backward.
    signs: (f64, f64),
}

impl Odometer {
    /// An odometer that starts at `start` and believes `geometry`.
    pub fn new(geometry: DriveGeometry, start: Pose2) -> Self {
        Odometer {
            geometry,
            pose: start,
            last_counts: None,
            signs: (1.0, 1.0),
        }
    }

    /// The current dead-reckoned pose.
    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// The geometry this odometer integrates with.
    pub fn geometry(&self) -> &DriveGeometry {
        &self.geometry
    }

    /// Tells the odometer a command was acknowledged by the firmware.
    pub fn commanded(&mut self, command: &DriveCommand) {
        match *command {
            DriveCommand::Advance(_) => self.signs = (1.0, 1.0),
            DriveCommand::Retreat(_) => self.signs = (-1.0, -1.0),
            DriveCommand::TurnLeft(_) => self.signs = (-1.0, 1.0),
            DriveCommand::TurnRight(_) => self.signs = (1.0, -1.0),
            // `v` keeps the counters; a zero speed leaves the wheel's last direction (it is
            // coasting down in that direction, whatever the firmware's direction pin says).
            DriveCommand::WheelSpeeds { left, right } => {
                if left != 0 {
                    self.signs.0 = f64::from(left.signum());
                }
                if right != 0 {
                    self.signs.1 = f64::from(right.signum());
                }
            }
            DriveCommand::Stop | DriveCommand::Ramp(_) | DriveCommand::Buzzer(_) => {}
        }
        if command.resets_counters() {
            self.last_counts = Some((0, 0));
        }
    }

    /// Integrates the counts reported since the previous observation and returns the new pose.
    pub fn observe(&mut self, status: &DriveStatus) -> Pose2 {
        let now = (status.left_counts, status.right_counts);
        if let Some(last) = self.last_counts {
            let dl = counts_since(last.0, now.0) as f64 * self.signs.0;
            let dr = counts_since(last.1, now.1) as f64 * self.signs.1;
            let m = self.geometry.metres_per_count();
            self.pose = integrate_arc(self.pose, dl * m, dr * m, self.geometry.track_m);
        }
        self.last_counts = Some(now);
        self.pose
    }
}

/// Counts elapsed from `last` to `now` on a counter that wraps at [`STATUS_COUNT_MODULUS`].
fn counts_since(last: u32, now: u32) -> u32 {
    (now + STATUS_COUNT_MODULUS - last % STATUS_COUNT_MODULUS) % STATUS_COUNT_MODULUS
}

/// Moves `pose` along the circular arc that the wheel travels `left` and `right` (metres) describe
/// on a base of the given track. Exact for constant wheel speeds over the interval.
pub fn integrate_arc(pose: Pose2, left: f64, right: f64, track: f64) -> Pose2 {
    let ds = 0.5 * (left + right);
    let dtheta = (right - left) / track;
    let half = 0.5 * dtheta;
    let chord = if half.abs() < 1e-9 {
        ds
    } else {
        ds * half.sin() / half
    };
    let heading = pose.theta + half;
    Pose2 {
        x: pose.x + chord * heading.cos(),
        y: pose.y + chord * heading.sin(),
        theta: wrap_angle(pose.theta + dtheta),
    }
}

/// A value that can be interpolated linearly between two samples.
pub trait Interpolate: Copy {
    /// The value a fraction `s` (0..=1) of the way from `self` to `other`.
    fn interpolate(&self, other: &Self, s: f64) -> Self;
}

impl Interpolate for Pose2 {
    fn interpolate(&self, other: &Pose2, s: f64) -> Pose2 {
        Pose2::interpolate(self, other, s)
    }
}

/// A time-ordered FIFO of poses, interpolated on demand: odometry waiting for the scans it must
/// be paired with, or any path to be looked up by time.
///
/// ```
/// use robot::odometry::PoseHistory;
/// use robot::{Pose2, Stamp};
/// let mut h = PoseHistory::new(100);
/// h.push(Stamp::from_millis(0), Pose2::new(0.0, 0.0, 0.0));
/// h.push(Stamp::from_millis(100), Pose2::new(1.0, 0.0, 0.2));
/// let p = h.at(Stamp::from_millis(25)).unwrap();
/// assert!((p.x - 0.25).abs() < 1e-12 && (p.theta - 0.05).abs() < 1e-12);
/// assert!(h.at(Stamp::from_millis(101)).is_none());
/// ```
pub type PoseHistory = History<Pose2>;

/// A time-ordered FIFO of samples of anything [`Interpolate`], looked up at any instant between
/// the first and the last.
#[derive(Clone, Debug)]
pub struct History<T> {
    entries: VecDeque<(Stamp, T)>,
    capacity: usize,
}

impl<T: Interpolate> History<T> {
    /// An empty history that keeps at most `capacity` samples (the oldest are dropped).
    pub fn new(capacity: usize) -> Self {
        History {
            entries: VecDeque::new(),
            capacity: capacity.max(2),
        }
    }

    /// An empty history that keeps every sample.
    pub fn unbounded() -> Self {
        Self::new(usize::MAX)
    }

    /// Number of samples kept.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether no sample is kept.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The samples, oldest first.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = (Stamp, T)> + '_ {
        self.entries.iter().copied()
    }

    /// Appends a sample. A stamp equal to the newest replaces it; an older stamp is ignored.
    pub fn push(&mut self, stamp: Stamp, value: T) {
        match self.entries.back() {
            Some(&(last, _)) if stamp < last => return,
            Some(&(last, _)) if stamp == last => {
                self.entries.pop_back();
            }
            _ => {}
        }
        if self.entries.len() == self.capacity {
            self.entries.pop_front();
        }
        self.entries.push_back((stamp, value));
    }

    /// The newest entry.
    pub fn latest(&self) -> Option<(Stamp, T)> {
        self.entries.back().copied()
    }

    /// The value at `stamp`, interpolated between the two entries around it; `None` when
    /// `stamp` lies outside the history.
    pub fn at(&self, stamp: Stamp) -> Option<T> {
        let (first, _) = *self.entries.front()?;
        let (last, last_value) = *self.entries.back()?;
        if stamp < first || stamp > last {
            return None;
        }
        if stamp == last {
            return Some(last_value);
        }
        let i = self.entries.partition_point(|&(t, _)| t <= stamp);
        let (t0, v0) = self.entries[i - 1];
        let (t1, v1) = self.entries[i];
        let s = (stamp.0 - t0.0) as f64 / (t1.0 - t0.0) as f64;
        Some(v0.interpolate(&v1, s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hardware::DriveStatus;

    const G: DriveGeometry = crate::drive_geometry::TEST_GEOMETRY;

    fn status(l: u32, r: u32) -> DriveStatus {
        DriveStatus {
            stamp: Stamp::ZERO,
            left_counts: l,
            right_counts: r,
            left_on: true,
            right_on: true,
            sonar_firing: false,
        }
    }

    #[test]
    fn turn_left_rotates_counter_clockwise_in_place() {
        let mut odo = Odometer::new(G, Pose2::IDENTITY);
        let tenths = G.tenths_for_turn(std::f64::consts::FRAC_PI_2).unwrap();
        odo.commanded(&DriveCommand::TurnLeft(tenths));
        for k in 1..=10 {
            odo.observe(&status(
                u32::from(tenths) * 10 * k,
                u32::from(tenths) * 10 * k,
            ));
        }
        let p = odo.pose();
        assert!(p.x.abs() < 1e-9 && p.y.abs() < 1e-9);
        let half_tenth = G.turn_for_counts(100.0) / 2.0;
        assert!(
            (p.theta - std::f64::consts::FRAC_PI_2).abs() <= half_tenth,
            "{}",
            p.theta
        );
    }

    #[test]
    fn counters_wrap_at_the_status_modulus() {
        let mut odo = Odometer::new(G, Pose2::IDENTITY);
        odo.commanded(&DriveCommand::WheelSpeeds {
            left: 30,
            right: 30,
        });
        odo.observe(&status(
            STATUS_COUNT_MODULUS - 50,
            STATUS_COUNT_MODULUS - 50,
        ));
        let before = odo.pose().x;
        odo.observe(&status(50, 50));
        let step = odo.pose().x - before;
        assert!(
            (step - 100.0 * G.metres_per_count()).abs() < 1e-12,
            "{step}"
        );
    }

    #[test]
    fn first_observation_without_command_only_sets_the_reference() {
        let mut odo = Odometer::new(G, Pose2::new(1.0, 2.0, 0.0));
        odo.observe(&status(5000, 5000));
        assert_eq!(odo.pose(), Pose2::new(1.0, 2.0, 0.0));
    }

    #[test]
    fn history_replaces_equal_stamps_and_ignores_older_ones() {
        let mut h = PoseHistory::new(3);
        h.push(Stamp(10), Pose2::new(1.0, 0.0, 0.0));
        h.push(Stamp(10), Pose2::new(2.0, 0.0, 0.0));
        h.push(Stamp(5), Pose2::new(9.0, 0.0, 0.0));
        assert_eq!(h.latest(), Some((Stamp(10), Pose2::new(2.0, 0.0, 0.0))));
        h.push(Stamp(20), Pose2::IDENTITY);
        h.push(Stamp(30), Pose2::IDENTITY);
        h.push(Stamp(40), Pose2::IDENTITY);
        assert!(
            h.at(Stamp(10)).is_none(),
            "oldest entry dropped at capacity"
        );
    }
}
