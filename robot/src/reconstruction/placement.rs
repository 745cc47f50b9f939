//! Where the base stood for each scan of a scene, by the 2D localisation (thesis §5.3.3).
//!
//! The scans of a scene are tilted, so the 2D localisation never placed them; it placed the level
//! scans around them. A scene's scan is put where the last level scan placed before it (the
//! station scan a `scene` or `survey` step takes first) puts the base, moved by what the odometry
//! counted between the two — nothing, for a robot standing still, so the scene inherits the
//! station's estimate exactly. Before any level scan, the first one after it is used instead.

use crate::geometry::Pose2;
use crate::localization::Placed;
use crate::time::Stamp;

/// Places scans by the level scans the localisation placed.
#[derive(Clone, Copy, Debug)]
pub struct EstimatePlacement<'a> {
    placed: &'a [Placed],
}

impl<'a> EstimatePlacement<'a> {
    /// The level scans as the localisation placed them, in order.
    pub fn new(placed: &'a [Placed]) -> Self {
        EstimatePlacement { placed }
    }

    /// The base's estimated pose at `stamp`, when the odometry read `odometry`; `None` when
    /// nothing was placed.
    pub fn at(&self, stamp: Stamp, odometry: Pose2) -> Option<Pose2> {
        let after = self.placed.partition_point(|p| p.stamp <= stamp);
        let anchor = if after > 0 {
            &self.placed[after - 1]
        } else {
            self.placed.first()?
        };
        Some(
            anchor
                .estimate
                .compose(&anchor.odometry.relative(&odometry)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn placed(ms: u64, estimate: Pose2, odometry: Pose2) -> Placed {
        Placed {
            stamp: Stamp::from_millis(ms),
            estimate,
            odometry,
            matched: None,
            reference: None,
            trusted: false,
            held_across: false,
            mount: Pose2::IDENTITY,
        }
    }

    #[test]
    fn a_scene_inherits_its_station_scan_and_what_odometry_added() {
        let levels = [
            placed(0, Pose2::new(0.0, 0.0, 0.0), Pose2::new(0.0, 0.0, 0.0)),
            placed(1000, Pose2::new(1.0, 0.1, 0.05), Pose2::new(1.05, 0.0, 0.0)),
        ];
        let place = EstimatePlacement::new(&levels);
        // Standing at the second station: exactly its estimate.
        let at = place.at(Stamp::from_millis(1500), Pose2::new(1.05, 0.0, 0.0));
        assert_eq!(at, Some(Pose2::new(1.0, 0.1, 0.05)));
        // Had the odometry counted 10 cm more, the estimate moves 10 cm along its heading.
        let moved = place
            .at(Stamp::from_millis(1500), Pose2::new(1.15, 0.0, 0.0))
            .unwrap();
        assert!((moved.x - (1.0 + 0.1 * 0.05f64.cos())).abs() < 1e-12);
        // Before the first level scan, the first one anchors.
        assert!(place.at(Stamp::ZERO, Pose2::IDENTITY).is_some());
        assert_eq!(
            EstimatePlacement::new(&[]).at(Stamp::ZERO, Pose2::IDENTITY),
            None
        );
    }
}
