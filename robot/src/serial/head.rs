//! Where the pan-tilt head was at a scan's stamp, from what the pan-tilt reported.
//!
//! The pan-tilt says where it is only when asked (`l`: positions since homing and the encoder
//! clicks since the last index pulse). Each report is kept as a sample of the head's angles; a
//! scan measured between two reports gets the angles interpolated between them, and a scan
//! measured after the last report gets that report's angles only if the head was at rest then and
//! no move has been commanded since. A command sent while the head rests is a sample too (the
//! head has not moved yet), so a scan between it and the next report is interpolated from rest.
//! Anything else — a scan while the head moved with no report after it — is unknown.

use crate::hardware::{HeadAngles, PanTiltStatus};
use crate::mount::HeadGeometry;
use crate::odometry::History;
use crate::time::Stamp;

/// The head's reported angles over time.
#[derive(Clone, Debug)]
pub(crate) struct HeadTrack {
    geometry: HeadGeometry,
    samples: History<HeadAngles>,
    /// The last report showed both motors off and nothing has been commanded since.
    at_rest: bool,
}

impl HeadTrack {
    /// Reports kept: a few minutes of polling at 20 Hz.
    const CAPACITY: usize = 4096;

    pub(crate) fn new(geometry: HeadGeometry) -> Self {
        HeadTrack {
            geometry,
            samples: History::new(Self::CAPACITY),
            at_rest: false,
        }
    }

    /// A status report.
    pub(crate) fn observe(&mut self, status: &PanTiltStatus) {
        let angles = self.geometry.angles(
            status.pan,
            status.pan_clicks,
            status.tilt,
            status.tilt_clicks,
        );
        self.samples.push(status.stamp, angles);
        self.at_rest = status.idle();
    }

    /// A move (`g` or `e`) acknowledged at `stamp`.
    pub(crate) fn commanded(&mut self, stamp: Stamp) {
        if self.at_rest
            && let Some((_, angles)) = self.samples.latest()
        {
            self.samples.push(stamp, angles);
        }
        self.at_rest = false;
    }

    /// The head's angles at `t`, if they can be told.
    pub(crate) fn at(&self, t: Stamp) -> Option<HeadAngles> {
        if let Some(angles) = self.samples.at(t) {
            return Some(angles);
        }
        match self.samples.latest() {
            Some((last, angles)) if t > last && self.at_rest => Some(angles),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn status(ms: u64, tilt: i16, clicks: i16, moving: bool) -> PanTiltStatus {
        PanTiltStatus {
            stamp: Stamp::from_millis(ms),
            pan: 0,
            pan_clicks: 0,
            tilt,
            tilt_clicks: clicks,
            left_limit: false,
            right_limit: false,
            lower_limit: false,
            pan_on: false,
            tilt_on: moving,
        }
    }

    #[test]
    fn scans_get_the_reported_angles_at_rest_and_none_while_moving_unobserved() {
        let head = HeadGeometry::THESIS;
        let step = head.tilt_per_position;
        let mut track = HeadTrack::new(head);
        assert_eq!(
            track.at(Stamp::from_millis(5)),
            None,
            "nothing reported yet"
        );
        track.observe(&status(100, 31, 0, false));
        assert_eq!(track.at(Stamp::from_millis(500)).unwrap().tilt, 0.0);
        // A move to position 41 is commanded at 600 ms: before it the head rested.
        track.commanded(Stamp::from_millis(600));
        assert_eq!(track.at(Stamp::from_millis(550)).unwrap().tilt, 0.0);
        assert_eq!(
            track.at(Stamp::from_millis(700)),
            None,
            "moving, not reported"
        );
        track.observe(&status(1600, 36, 0, true));
        let mid = track.at(Stamp::from_millis(1100)).unwrap().tilt;
        assert!(
            (mid - 2.5 * step).abs() < 1e-12,
            "interpolated from rest: {mid}"
        );
        assert_eq!(track.at(Stamp::from_millis(1700)), None, "still moving");
        // At rest past position 41 by 120 clicks of coast.
        track.observe(&status(2600, 41, 120, false));
        let rest = track.at(Stamp::from_millis(3000)).unwrap().tilt;
        assert!((rest - 10.12 * step).abs() < 1e-12, "{rest}");
    }
}
