//! One laser scan as the SICK LMS reports it in millimetre mode.

use super::HeadAngles;
use crate::time::Stamp;

/// One scan: ranges in millimetres, beam `i` at angle `angle_min + i · angle_increment` in the
/// laser frame (x forward, y left, counter-clockwise). A reading `>= range_max_mm` means no
/// return (the LMS reports its maximum when the pulse does not come back).
///
/// ```
/// use robot::hardware::LaserScan;
/// use robot::Stamp;
/// let mut scan = LaserScan::sick_lms_half_degree(Stamp::ZERO, vec![32_000; 361]);
/// scan.ranges_mm[180] = 2_500; // straight ahead
/// assert_eq!(scan.range_m(180), Some(2.5));
/// assert_eq!(scan.range_m(0), None);
/// let (x, y) = scan.point(180).unwrap();
/// assert!((x - 2.5).abs() < 1e-12 && y.abs() < 1e-12);
/// ```
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LaserScan {
    /// When the scan was measured.
    pub stamp: Stamp,
    /// Angle of the first beam, radians.
    pub angle_min: f64,
    /// Angle between consecutive beams, radians.
    pub angle_increment: f64,
    /// The no-return value, millimetres.
    pub range_max_mm: u16,
    /// One reading per beam, millimetres.
    pub ranges_mm: Vec<u16>,
    /// Where the pan-tilt head pointed the laser when the scan was measured; `None` for a laser
    /// on a fixed mount, or when the backend could not tell (the head was moving unobserved).
    pub head: Option<HeadAngles>,
}

impl LaserScan {
    /// Beams of the thesis's configuration: 180° at 0.5°.
    pub const SICK_BEAMS: usize = 361;
    /// The no-return value of the thesis's configuration (32 m in millimetre mode).
    pub const SICK_RANGE_MAX_MM: u16 = 32_000;

    /// A scan in the thesis's configuration: 361 beams from −90° to +90° at 0.5°, 32 m maximum.
    pub fn sick_lms_half_degree(stamp: Stamp, ranges_mm: Vec<u16>) -> Self {
        LaserScan {
            stamp,
            angle_min: -std::f64::consts::FRAC_PI_2,
            angle_increment: std::f64::consts::PI / 360.0,
            range_max_mm: Self::SICK_RANGE_MAX_MM,
            ranges_mm,
            head: None,
        }
    }

    /// Number of beams.
    pub fn len(&self) -> usize {
        self.ranges_mm.len()
    }

    /// Whether the scan has no beams.
    pub fn is_empty(&self) -> bool {
        self.ranges_mm.is_empty()
    }

    /// Angle of beam `i`, radians.
    pub fn angle(&self, i: usize) -> f64 {
        self.angle_min + i as f64 * self.angle_increment
    }

    /// The maximum range, metres.
    pub fn range_max_m(&self) -> f64 {
        f64::from(self.range_max_mm) * 1e-3
    }

    /// Range of beam `i` in metres, or `None` when the beam returned nothing (or `i` is out of
    /// bounds).
    pub fn range_m(&self, i: usize) -> Option<f64> {
        let mm = *self.ranges_mm.get(i)?;
        (mm < self.range_max_mm).then(|| f64::from(mm) * 1e-3)
    }

    /// Beam `i`'s end point in the laser frame, metres, or `None` when it returned nothing.
    pub fn point(&self, i: usize) -> Option<(f64, f64)> {
        let r = self.range_m(i)?;
        let (s, c) = self.angle(i).sin_cos();
        Some((r * c, r * s))
    }

    /// All returned points in the laser frame, metres, with their beam index.
    pub fn points(&self) -> impl Iterator<Item = (usize, (f64, f64))> + '_ {
        (0..self.len()).filter_map(|i| self.point(i).map(|p| (i, p)))
    }
}
