//! `summary.json`: the figures of a run.

use crate::record::{LocalisationRecord, RunRecord, WRONG_MATCH};
use robot::localization::MatchStats;
use serde::Serialize;
use std::path::Path;

/// The figures of a run. `wall_seconds` and `real_time_factor` depend on the machine; everything
/// else on the scenario and seed only.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// World name.
    pub world: String,
    /// Robot name.
    pub robot: String,
    /// Seed used.
    pub seed: u64,
    /// Simulated seconds.
    pub sim_seconds: f64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// Simulated seconds per wall-clock second.
    pub real_time_factor: f64,
    /// Length of the true path, metres.
    pub distance_m: f64,
    /// Distance between final odometry and final truth, metres.
    pub final_odometry_error_m: f64,
    /// Heading error of the final odometry, degrees.
    pub final_odometry_error_deg: f64,
    /// Scans written.
    pub scans: usize,
    /// Script steps carried out.
    pub steps: usize,
    /// Contacts with walls.
    pub collisions: u32,
    /// Motions that ended a few counts short with the motors on, stopped by the tour with `p`.
    pub stalled_motions: usize,
    /// State of charge of the motor batteries at the end.
    pub motor_battery_charge: f64,
    /// How well the scan-matching estimate followed the truth, when the run localised.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub localisation: Option<LocalisationSummary>,
    /// How each `goto` or `explore` step ended, against the truth.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub navigation: Vec<crate::record::NavigationResult>,
}

/// The scan-matching estimate against the truth, at every scan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LocalisationSummary {
    /// The matcher.
    pub matcher: String,
    /// Position error of the estimate at the last scan, metres.
    pub final_error_m: f64,
    /// Heading error of the estimate at the last scan, degrees.
    pub final_error_deg: f64,
    /// RMS position error over all scans, metres.
    pub rms_error_m: f64,
    /// RMS heading error over all scans, degrees.
    pub rms_error_deg: f64,
    /// The odometry's RMS position error over the same scans, metres, for comparison.
    pub odometry_rms_error_m: f64,
    /// Matches made, trusted and converged, and the mean iterations.
    #[serde(flatten)]
    pub stats: MatchStats,
    /// Trusted matches more than 5 cm or 1° from the true motion ([`WRONG_MATCH`]).
    pub wrong_trusted: usize,
    /// The largest distance of a trusted match's answer from the true motion, metres …
    pub worst_trusted_error_m: f64,
    /// … and the largest heading difference, degrees (each over every trusted match).
    pub worst_trusted_error_deg: f64,
    /// Matches relied on across a corridor ([`MatchStats::held_across`]) more than 5 cm across
    /// their free direction or 1° in heading from the true motion
    /// ([`held_across_match_errors`](crate::record::held_across_match_errors)).
    pub wrong_held_across: usize,
    /// The largest distance across its free direction of such a match from the true motion,
    /// metres …
    pub worst_held_across_error_m: f64,
    /// … and the largest heading difference, degrees.
    pub worst_held_across_error_deg: f64,
    /// Wall-clock milliseconds spent localising per scan (machine-dependent).
    pub wall_ms_per_scan: f64,
}

/// `(final m, final °, RMS m, RMS °)` of the estimate against the truth at each scan.
pub fn estimate_errors(record: &RunRecord, loc: &LocalisationRecord) -> (f64, f64, f64, f64) {
    let errors: Vec<(f64, f64)> = loc.errors(&record.scans).collect();
    let (last_m, last_rad) = errors.last().copied().unwrap_or_default();
    let n = errors.len().max(1) as f64;
    let rms =
        |f: fn(&(f64, f64)) -> f64| (errors.iter().map(|e| f(e).powi(2)).sum::<f64>() / n).sqrt();
    (
        last_m,
        last_rad.to_degrees(),
        rms(|e| e.0),
        rms(|e| e.1).to_degrees(),
    )
}

impl LocalisationSummary {
    /// The figures of a run's localisation.
    pub fn of(record: &RunRecord, loc: &LocalisationRecord) -> Self {
        let (final_error_m, final_error_deg, rms_error_m, rms_error_deg) =
            estimate_errors(record, loc);
        let n = record.scans.len().max(1) as f64;
        let odometry_rms_error_m = (record
            .scans
            .iter()
            .map(|s| s.odometry.distance(&s.truth).powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
        let judged = loc.judge_trusted(&record.scans, WRONG_MATCH);
        let across = loc.judge_held_across(&record.scans, WRONG_MATCH);
        LocalisationSummary {
            matcher: loc.matcher.to_string(),
            final_error_m,
            final_error_deg,
            rms_error_m,
            rms_error_deg,
            odometry_rms_error_m,
            stats: MatchStats::of(&loc.placed),
            wrong_trusted: judged.wrong,
            worst_trusted_error_m: judged.worst_m,
            worst_trusted_error_deg: judged.worst_rad.to_degrees(),
            wrong_held_across: across.wrong,
            worst_held_across_error_m: across.worst_m,
            worst_held_across_error_deg: across.worst_rad.to_degrees(),
            wall_ms_per_scan: loc.wall_seconds * 1e3 / n,
        }
    }
}

impl Summary {
    /// The summary of a run in a world and with a robot named `(world, robot)`.
    pub fn of(record: &RunRecord, (world, robot): (&str, &str)) -> Self {
        Summary {
            scenario: record.scenario.clone(),
            world: world.to_string(),
            robot: robot.to_string(),
            seed: record.seed,
            sim_seconds: record.sim_seconds(),
            wall_seconds: record.wall_seconds,
            real_time_factor: record.real_time_factor(),
            distance_m: record.distance_m,
            final_odometry_error_m: record.final_odometry_error_m(),
            final_odometry_error_deg: record.final_odometry_error_deg(),
            scans: record.scans.len(),
            steps: record.steps,
            collisions: record.collisions,
            stalled_motions: record.stalled_motions,
            motor_battery_charge: record.battery_charge.1,
            localisation: record
                .localisation
                .as_ref()
                .map(|loc| LocalisationSummary::of(record, loc)),
            navigation: record.navigation_results(),
        }
    }

    /// Writes the summary as pretty JSON.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        robot::logs::write_file(path, text)
    }
}
