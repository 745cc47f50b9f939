//! The SICK LMS laser rangefinder: 361 beams over 180° in the thesis's configuration, readings in
//! millimetres, the maximum value (32 m) when nothing comes back.
//!
//! A beam is measured in three stages:
//! 1. [`beam::trace`] follows the pulse through the world: what it meets, by which material, and
//!    whether it comes back (black surfaces, glass windows and mirrors, metal, grazing loss);
//! 2. Gaussian range noise is added to a pulse that came back, kept inside the valid range;
//! 3. [`crate::config::Outliers`] (drawn in [`outliers`]) may replace the reading by a random one.
//!
//! A reading with nothing coming back within range is the maximum (32 m).
//!
//! Timing follows the device: the mirror sweeps a scan in `sweep_s`, back to back, and in
//! continuous mode the LMS sends a scan as a telegram of `telegram_bytes` over its serial line
//! once the sweep is complete and the line is free. At 38400 bps a 732-byte telegram takes
//! 190.6 ms, longer than the 26.7 ms sweep, so the line sets the rate: when a telegram ends, the
//! next one carries the latest complete sweep. Scans are therefore 7 or 8 sweeps apart (190.6 ms
//! on average), and each reaches the host at least a sweep plus a transfer after its stamp.
//! All beams of a scan are measured at the scan's stamp, the start of its sweep.

pub mod beam;
pub mod outliers;

use crate::config::Outliers;
use crate::config::robot_file::LaserDescription;
use crate::rng::SimRng;
use crate::world::{FanCast, PlaneFan, WorldMap};
use beam::{Disc, Echo, Legs};
use core::time::Duration;
use outliers::OutlierCuts;
use rand_distr::{Distribution, StandardNormal};
use robot::hardware::LaserScan;
use robot::{Pose2, Stamp};

/// When scans are taken and when they reach the host.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct LaserTiming {
    /// Time the mirror takes for one scan; sweeps follow each other from time zero.
    pub sweep: Duration,
    /// Time one telegram takes on the serial line.
    pub transfer: Duration,
}

impl LaserTiming {
    /// The timing of a laser that sweeps in `sweep` and sends `telegram_bytes` at `baud`.
    pub fn new(sweep: Duration, telegram_bytes: u32, baud: u32) -> Self {
        LaserTiming {
            sweep: sweep.max(Duration::from_nanos(1)),
            transfer: robot::protocol::serial_time(telegram_bytes as usize, baud),
        }
    }

    /// Mean time between scans: the sweep or the transfer, whichever is longer.
    pub fn mean_period(&self) -> Duration {
        self.sweep.max(self.transfer)
    }

    /// The stamp of the first scan sent: the sweep that starts one sweep after power-on.
    pub fn first_scan(&self) -> Stamp {
        Stamp::ZERO + self.sweep
    }

    /// When the telegram of the scan stamped `stamp` reaches the host, the line being free from
    /// `line_free`: it is sent when the sweep is complete and the line is free.
    pub fn delivery(&self, stamp: Stamp, line_free: Stamp) -> Stamp {
        (stamp + self.sweep).max(line_free) + self.transfer
    }

    /// The stamp of the scan sent after the one stamped `stamp`, the line being free again at
    /// `line_free`: the latest sweep complete by then, or the next sweep if none is newer.
    pub fn next_scan(&self, stamp: Stamp, line_free: Stamp) -> Stamp {
        let sweep = self.sweep.as_nanos() as u64;
        let complete = line_free.0 / sweep;
        let latest = Stamp(complete.saturating_sub(1) * sweep);
        latest.max(stamp + self.sweep)
    }
}

/// Where the laser is and where it looks: its optical centre in the world, the heading of its
/// middle beam and the tilt of its scan plane (positive up).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LaserFrame {
    /// Optical centre, world frame, metres.
    pub origin: [f64; 3],
    /// Heading of the middle beam, radians counter-clockwise.
    pub yaw: f64,
    /// Tilt of the scan plane about the laser's left axis, radians (positive: forward beams rise).
    pub tilt: f64,
}

impl LaserFrame {
    /// The world direction of the beam at `angle` in the scan plane.
    pub fn direction(&self, angle: f64) -> [f64; 3] {
        let (sa, ca) = angle.sin_cos();
        let (forward, left) = self.axes();
        [0, 1, 2].map(|k| ca * forward[k] + sa * left[k])
    }

    /// The scan plane's unit axes in the world: the middle beam's direction and the first
    /// beam's opposite (the laser's left). A beam at angle `a` points along
    /// `cos a · forward + sin a · left`.
    pub fn axes(&self) -> ([f64; 3], [f64; 3]) {
        let (st, ct) = self.tilt.sin_cos();
        let (sy, cy) = self.yaw.sin_cos();
        ([cy * ct, sy * ct, st], [-sy, cy, 0.0])
    }

    /// The world point `range` metres along the beam at `angle`.
    pub fn point(&self, angle: f64, range: f64) -> [f64; 3] {
        let d = self.direction(angle);
        [0, 1, 2].map(|k| self.origin[k] + d[k] * range)
    }

    /// The laser's pose in the plane relative to a base at `base`: its optical centre and
    /// heading in the base frame.
    pub fn mount_on(&self, base: Pose2) -> Pose2 {
        base.relative(&Pose2::new(self.origin[0], self.origin[1], self.yaw))
    }

    /// The same frame on the base when the base is at `to` instead of `from` (to draw a scan
    /// where odometry puts the robot).
    pub fn carried(&self, from: Pose2, to: Pose2) -> LaserFrame {
        let at = to.compose(&self.mount_on(from));
        LaserFrame {
            origin: [at.x, at.y, self.origin[2]],
            yaw: at.theta,
            tilt: self.tilt,
        }
    }
}

/// How a scan's beams are cast: the same readings either way, to the last bit.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Casting {
    /// The beams' first legs in one sweep of the world's faces (the default), compiled for
    /// the widest registers the processor has: AVX-512, else AVX2 ([`crate::wide`]); each beam
    /// on its own down the tree, as [`Casting::PerBeam`], in a world no fan is swept or walked
    /// in ([`WorldMap::casts_fans`]).
    Sweep,
    /// The same sweep compiled for AVX2 where the processor has it, even if it has AVX-512.
    SweepAvx2,
    /// The same sweep compiled for the baseline processor whatever this one has: to check
    /// that both builds read the same.
    SweepBaseline,
    /// Each beam cast on its own down the world's tree: the reference the sweep is tested and
    /// benchmarked against.
    PerBeam,
}

/// A laser model: geometry, noise and timing.
#[derive(Clone, Debug)]
pub struct LaserModel {
    mount: Pose2,
    height: f64,
    angle_min: f64,
    angle_increment: f64,
    range_max_m: f64,
    range_max_mm: u16,
    sigma_m: f64,
    outliers: OutlierCuts,
    /// The largest valid reading, metres: one millimetre short of the maximum.
    valid_max_m: f64,
    timing: LaserTiming,
    /// Rate of its serial line, bits per second.
    baud: u32,
    /// The beams' angles in the scan plane.
    beams: PlaneFan,
    /// How the beams are cast.
    casting: Casting,
}

impl LaserModel {
    /// A laser as described, mounted at `mount` on the base, with range noise `sigma_m` and
    /// `outliers`.
    pub fn new(desc: &LaserDescription, mount: Pose2, sigma_m: f64, outliers: Outliers) -> Self {
        let beams = usize::from(desc.beams);
        let fov = desc.fov_deg.get().to_radians();
        let angle_min = -fov / 2.0;
        let angle_increment = fov / (beams - 1) as f64;
        let range_max_mm = (desc.range_max_m.get() * 1000.0).round() as u16;
        let angles: Vec<f64> = (0..beams)
            .map(|i| angle_min + i as f64 * angle_increment)
            .collect();
        LaserModel {
            mount,
            height: desc.z_m.get(),
            angle_min,
            angle_increment,
            range_max_m: desc.range_max_m.get(),
            range_max_mm,
            sigma_m,
            outliers: outliers.cuts(),
            valid_max_m: f64::from(range_max_mm.saturating_sub(1)) * 1e-3,
            timing: LaserTiming::new(
                Duration::from_secs_f64(desc.sweep_s.get()),
                desc.telegram_bytes,
                desc.baud,
            ),
            baud: desc.baud,
            beams: PlaneFan::new(angles),
            casting: Casting::Sweep,
        }
    }

    /// The same laser with its beams cast as `casting` says.
    pub fn with_casting(self, casting: Casting) -> Self {
        LaserModel { casting, ..self }
    }

    /// The beams' angles in the scan plane.
    pub fn beams(&self) -> &PlaneFan {
        &self.beams
    }

    /// The laser's pose on the base.
    pub fn mount(&self) -> Pose2 {
        self.mount
    }

    /// Sweep and transfer times.
    pub fn timing(&self) -> LaserTiming {
        self.timing
    }

    /// Rate of the laser's serial line, bits per second.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// The maximum range, metres.
    pub fn range_max_m(&self) -> f64 {
        self.range_max_m
    }

    /// The laser's frame when fixed on a base at `base` (world frame).
    pub fn frame_on(&self, base: Pose2) -> LaserFrame {
        let at = base.compose(&self.mount);
        LaserFrame {
            origin: [at.x, at.y, self.height],
            yaw: at.theta,
            tilt: 0.0,
        }
    }

    /// Measures one scan from `frame`. `body` is the robot's own body, which reflected beams can
    /// meet.
    ///
    /// The beams' first legs are cast in one sweep of the world ([`WorldMap::cast_plane_fan`]);
    /// the result is the same, to the last bit, as with each beam cast on its own
    /// ([`Casting::PerBeam`]).
    pub fn scan(
        &self,
        map: &WorldMap,
        body: Option<Disc>,
        frame: LaserFrame,
        stamp: Stamp,
        rng: &mut SimRng,
    ) -> LaserScan {
        self.scan_among(map, body, &[], frame, stamp, rng)
    }

    /// [`LaserModel::scan`] among other robots' bodies, which the beams meet too.
    pub fn scan_among(
        &self,
        map: &WorldMap,
        body: Option<Disc>,
        others: &[Disc],
        frame: LaserFrame,
        stamp: Stamp,
        rng: &mut SimRng,
    ) -> LaserScan {
        let pulses = beam::Pulses::new(map, body, self.range_max_m).among(others);
        // The default takes the reference's way in a world whose fans are cast ray by ray down
        // the tree anyway: the same readings (tested), without the sweep's bookkeeping.
        let per_beam = match self.casting {
            Casting::PerBeam => true,
            Casting::Sweep => !map.casts_fans(),
            Casting::SweepAvx2 | Casting::SweepBaseline => false,
        };
        if per_beam {
            let pulses = pulses.down_tree();
            let ranges_mm = self
                .directions(frame)
                .into_iter()
                .map(|dir| {
                    let echo = pulses.trace(frame.origin, dir, rng);
                    self.reading_mm(echo, rng)
                })
                .collect();
            return self.telegram(stamp, ranges_mm);
        }
        // The sweep's buffers are kept from one scan to the next, one set per thread.
        thread_local! {
            static FAN: core::cell::RefCell<Buffers> = core::cell::RefCell::new(Default::default());
        }
        let (ranges_mm, local) = FAN.with_borrow_mut(|buffers| {
            #[cfg(target_arch = "x86_64")]
            match self.casting {
                Casting::Sweep if crate::wide::avx512() => {
                    // SAFETY: the processor runs AVX-512 (F, VL, DQ, BW), checked just above.
                    return unsafe { self.sweep_scan_avx512(map, pulses, frame, buffers, rng) };
                }
                Casting::Sweep | Casting::SweepAvx2 if crate::wide::avx2() => {
                    // SAFETY: the processor runs AVX2, checked just above.
                    return unsafe { self.sweep_scan_avx2(map, pulses, frame, buffers, rng) };
                }
                _ => {}
            }
            self.sweep_scan(map, pulses, frame, buffers, rng)
        });
        *rng = local;
        self.telegram(stamp, ranges_mm)
    }

    /// [`LaserModel::sweep_scan`] compiled for AVX-512 ([`crate::wide`]): the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw")]
    fn sweep_scan_avx512(
        &self,
        map: &WorldMap,
        pulses: beam::Pulses<'_>,
        frame: LaserFrame,
        buffers: &mut Buffers,
        rng: &SimRng,
    ) -> (Vec<u16>, SimRng) {
        self.sweep_scan(map, pulses, frame, buffers, rng)
    }

    /// [`LaserModel::sweep_scan`] compiled for AVX2 ([`crate::wide`]): the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn sweep_scan_avx2(
        &self,
        map: &WorldMap,
        pulses: beam::Pulses<'_>,
        frame: LaserFrame,
        buffers: &mut Buffers,
        rng: &SimRng,
    ) -> (Vec<u16>, SimRng) {
        self.sweep_scan(map, pulses, frame, buffers, rng)
    }

    /// The readings of a scan from `frame`, its beams' first legs cast in one sweep, and the
    /// generator's state after them.
    #[inline(always)]
    fn sweep_scan(
        &self,
        map: &WorldMap,
        pulses: beam::Pulses<'_>,
        frame: LaserFrame,
        Buffers { fan, legs }: &mut Buffers,
        rng: &SimRng,
    ) -> (Vec<u16>, SimRng) {
        map.cast_plane_fan(
            frame.origin,
            frame.axes(),
            &self.beams,
            self.range_max_m,
            fan,
        );
        legs.clear();
        let plain = pulses.plain();
        // The generator's state in a local the loop can keep in registers, put back after.
        let mut local = rng.clone();
        let rng = &mut local;
        let rays = fan.columns();
        let mut ranges_mm = vec![0u16; fan.len()];
        for (k, ((((&x, &y), &z), (&t, &face)), reading)) in rays
            .x
            .iter()
            .zip(rays.y)
            .zip(rays.z)
            .zip(rays.t.iter().zip(rays.face))
            .zip(&mut ranges_mm)
            .enumerate()
        {
            // A level beam's first face is read off the sweep's columns; any other beam is
            // followed from its first surface, built, in a call apart (the same echo, the
            // same draws).
            let echo = if plain && z == 0.0 && face != u32::MAX {
                pulses.off_face(frame.origin, [x, y, z], (t, face as usize), legs, rng)
            } else {
                let (echo, after) = pulses.beam_apart(fan, k, legs, rng.clone());
                *rng = after;
                echo
            };
            *reading = self.reading_mm(echo, rng);
        }
        (ranges_mm, local)
    }

    /// The world direction of every beam from `frame`, first beam first.
    pub fn directions(&self, frame: LaserFrame) -> Vec<[f64; 3]> {
        let (forward, left) = frame.axes();
        self.beams.directions(forward, left)
    }

    fn telegram(&self, stamp: Stamp, ranges_mm: Vec<u16>) -> LaserScan {
        LaserScan {
            stamp,
            angle_min: self.angle_min,
            angle_increment: self.angle_increment,
            range_max_mm: self.range_max_mm,
            ranges_mm,
            head: None,
        }
    }

    /// What the receiver reports for an echo: noise, then perhaps an outlier, in millimetres.
    #[inline(always)]
    pub fn reading_mm(&self, echo: Echo, rng: &mut SimRng) -> u16 {
        let echo = match self.outliers.draw(echo, self.range_max_m, rng) {
            Some(outlier) => outlier,
            None => match echo {
                Echo::Range(r) => {
                    let noise: f64 = StandardNormal.sample(rng);
                    Echo::Range(r + self.sigma_m * noise)
                }
                Echo::Lost => Echo::Lost,
            },
        };
        match echo {
            Echo::Lost => self.range_max_mm,
            Echo::Range(r) => {
                // Kept within the valid range (`clamp` but for its check of the bounds: the
                // same for every `r`, NaN included), rounded to the nearest millimetre (half
                // up) without a call into libm.
                (r.max(0.0).min(self.valid_max_m) * 1000.0 + 0.5) as u16
            }
        }
    }
}

/// What a scan's sweep keeps from one scan to the next, one set per thread: the fan and the
/// legs' cones.
#[derive(Default)]
struct Buffers {
    fan: FanCast,
    legs: Legs,
}

/// An LMS at 0.3 m, 361 beams over 180°, 38400 bps, for tests.
#[cfg(test)]
pub(crate) fn lms_description(sigma: f64) -> LaserDescription {
    use crate::config::values::{Finite, Positive, Seconds, Sigma};
    LaserDescription {
        x_m: Finite(0.0),
        y_m: Finite(0.0),
        yaw_deg: Finite(0.0),
        z_m: Positive(0.3),
        beams: 361,
        fov_deg: Positive(180.0),
        range_max_m: Positive(32.0),
        sigma_m: Sigma(sigma),
        baud: 38_400,
        sweep_s: Seconds(0.02667),
        telegram_bytes: 732,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::WorldDescription;

    fn lms(sigma: f64) -> LaserModel {
        LaserModel::new(
            &lms_description(sigma),
            Pose2::new(0.1, 0.0, 0.0),
            sigma,
            Outliers::NONE,
        )
    }

    fn corridor() -> WorldMap {
        let text = r#"
name = "corridor"
[start]
x = 0
y = 0
[[wall]]
points = [[-1, 1], [40, 1]]
[[wall]]
points = [[-1, -2], [40, -2]]
"#;
        WorldMap::new(&WorldDescription::parse(text, "c.toml").unwrap())
    }

    #[test]
    fn noiseless_ranges_match_trigonometry() {
        let laser = lms(0.0);
        let mut rng = crate::rng::stream(1, "laser");
        let scan = laser.scan(
            &corridor(),
            None,
            laser.frame_on(Pose2::IDENTITY),
            Stamp::ZERO,
            &mut rng,
        );
        assert_eq!(scan.len(), 361);
        // Beam 360 points left (+90°) to the wall at y = 1 from (0.1, 0): 1 m.
        assert_eq!(scan.ranges_mm[360], 1000);
        // Beam 0 points right to y = -2: 2 m.
        assert_eq!(scan.ranges_mm[0], 2000);
        // Beam at +30° (index 240) meets y = 1 at 1 / sin 30° = 2 m.
        assert_eq!(scan.ranges_mm[240], 2000);
        // Straight ahead the corridor is 40 m long: beyond 32 m, no return.
        assert_eq!(scan.ranges_mm[180], 32_000);
        assert_eq!(scan.range_m(180), None);
    }

    #[test]
    fn noise_has_the_configured_spread_and_stays_valid() {
        let laser = lms(0.01);
        let mut rng = crate::rng::stream(3, "laser");
        let mut errors = Vec::new();
        for k in 0..200 {
            let scan = laser.scan(
                &corridor(),
                None,
                laser.frame_on(Pose2::IDENTITY),
                Stamp(k),
                &mut rng,
            );
            errors.push(f64::from(scan.ranges_mm[360]) * 1e-3 - 1.0);
            assert_eq!(scan.ranges_mm[180], 32_000, "no-return stays the maximum");
        }
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        let sd =
            (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / errors.len() as f64).sqrt();
        assert!(mean.abs() < 0.003, "{mean}");
        assert!((sd - 0.01).abs() < 0.002, "{sd}");
    }

    #[test]
    fn timing_is_set_by_the_serial_line() {
        let t = lms(0.0).timing();
        assert_eq!(t.transfer, Duration::from_nanos(190_625_000));
        assert_eq!(t.mean_period(), t.transfer);
        // Back-to-back telegrams: stamps fall on sweep starts, 7 or 8 sweeps apart, and average
        // to the transfer time.
        let sweep = t.sweep.as_nanos() as u64;
        let (mut stamp, mut line_free) = (t.first_scan(), Stamp::ZERO);
        let first = stamp;
        for _ in 0..100 {
            let delivery = t.delivery(stamp, line_free);
            assert!(delivery >= stamp + t.sweep + t.transfer);
            line_free = delivery;
            let next = t.next_scan(stamp, line_free);
            let gap = (next.0 - stamp.0) / sweep;
            assert_eq!((next.0 - stamp.0) % sweep, 0);
            assert!(gap == 7 || gap == 8, "{gap} sweeps");
            stamp = next;
        }
        let mean = (stamp.0 - first.0) as f64 / 100.0;
        assert!(
            (mean - 190_625_000.0).abs() < sweep as f64 / 100.0 + 1.0,
            "{mean}"
        );
        let fast = LaserTiming::new(Duration::from_micros(26_670), 732, 500_000);
        assert_eq!(
            fast.next_scan(
                Stamp::ZERO + fast.sweep,
                fast.delivery(Stamp::ZERO + fast.sweep, Stamp::ZERO)
            ),
            Stamp::ZERO + fast.sweep * 2,
            "at 500 kbaud the sweep sets the rate"
        );
    }
}
