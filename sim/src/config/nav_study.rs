//! Navigation study files (`studies/goto-*.toml`): a closed-loop scenario run over many seeds,
//! start poses and noise conditions by `twin montecarlo`.
//!
//! ```toml
//! name = "goto-lab"
//! scenario = "../scenarios/goto-lab.toml"  # world, robot, sonar, localisation, goals
//! trials_per_condition = 50
//! seed = 2026
//! start_radius_m = 0.8                     # starts drawn within this of the scenario's start,
//! clearance_m = 0.6                        # at least this far from walls, heading uniform
//! success_m = 0.5                          # a goal counts as reached within this (truth)
//!
//! [[condition]]                            # each condition: the scenario's noise, overridden
//! name = "outliers 2 %"
//! noise = { outliers = "thesis-2pct" }     # as a scenario's [noise]
//! use_sonar = true                         # false: the controller ignores the ring
//! method = "histogram"                     # or "direct", the baseline (no way round)
//! ```
//!
//! Paths are relative to the study file; the whole text is kept, as for the scan-matching
//! study, so a resumed run and the shards check they belong to the same study.

use super::error::{ConfigError, Source};
use super::scenario::{NoiseFile, Scenario, load_named};
use super::values::{NonNegative, Positive};
use serde::Deserialize;
use std::path::PathBuf;

/// One noise condition of a navigation study.
#[derive(Clone, Debug, PartialEq)]
pub struct NavCondition {
    /// Its name in the table.
    pub name: String,
    /// The scenario with this condition's noise and sonar use.
    pub scenario: Scenario,
}

/// A validated navigation study.
#[derive(Clone, Debug, PartialEq)]
pub struct NavStudy {
    /// Short name.
    pub name: String,
    /// What it measures.
    pub description: String,
    /// The conditions, each a variant of the scenario.
    pub conditions: Vec<NavCondition>,
    /// Trials per condition.
    pub trials_per_condition: u64,
    /// Master seed.
    pub seed: u64,
    /// Starts are drawn within this distance of the scenario's start, metres.
    pub start_radius_m: f64,
    /// Least distance from a start to any wall, metres.
    pub clearance_m: f64,
    /// A goal counts as reached when the robot truly ends within this of it, metres.
    pub success_m: f64,
    /// The file it was read from.
    pub path: PathBuf,
    /// The file's text.
    pub text: String,
}

impl NavStudy {
    /// Whether `text` is a navigation study (it names a scenario) rather than a scan-matching
    /// one.
    pub fn is_navigation(text: &str) -> bool {
        toml::from_str::<toml::Table>(text).is_ok_and(|t| t.contains_key("scenario"))
    }

    /// Trials in the whole study.
    pub fn total_trials(&self) -> u64 {
        self.trials_per_condition * self.conditions.len() as u64
    }

    /// The same study with `trials` trials per condition (`twin montecarlo --trials`), its text
    /// saying so.
    pub fn with_trials_per_condition(mut self, trials: u64) -> Self {
        let trials = trials.max(1);
        let line = format!("trials_per_condition = {trials}  # twin montecarlo --trials {trials}");
        self.text = self
            .text
            .lines()
            .map(|l| {
                if l.trim_start().starts_with("trials_per_condition") {
                    line.clone()
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n")
            + "\n";
        self.trials_per_condition = trials;
        self
    }

    /// Reads a study and the scenario it names.
    pub fn load(path: impl AsRef<std::path::Path>) -> Result<Self, ConfigError> {
        let source = Source::read(path.as_ref())?;
        let file: NavStudyFile = source.parse()?;
        let scenario = load_named(&source, &file.scenario, "scenario", |p| Scenario::load(p))?;
        if !scenario
            .steps
            .iter()
            .any(|s| matches!(s, robot::control::Step::Goto { .. }))
        {
            return Err(source.error(
                file.scenario.span(),
                Some("scenario".into()),
                format!(
                    "{} has no `goto X Y` step: a navigation study measures goals reached",
                    file.scenario.get_ref()
                ),
            ));
        }
        if file.condition.is_empty() {
            return Err(source.error_in_file(
                Some("condition".into()),
                "a study needs at least one [[condition]]",
            ));
        }
        if !(1..=100_000_000).contains(&file.trials_per_condition) {
            return Err(source.error_in_file(
                Some("trials_per_condition".into()),
                format!(
                    "expected 1 to 100000000 trials, found {}",
                    file.trials_per_condition
                ),
            ));
        }
        let mut conditions = Vec::new();
        for (i, c) in file.condition.iter().enumerate() {
            if c.name.trim().is_empty() || c.name.contains([',', '\n', '"']) {
                return Err(source.error_in_file(
                    Some(format!("condition[{i}].name")),
                    "expected a name without commas, quotes or line breaks",
                ));
            }
            if conditions.iter().any(|k: &NavCondition| k.name == c.name) {
                return Err(source.error_in_file(
                    Some(format!("condition[{i}].name")),
                    format!("condition {:?} is named twice", c.name),
                ));
            }
            let mut scenario = scenario.clone();
            if let Some(noise) = &c.noise {
                noise.apply(&mut scenario.noise, &source)?;
            }
            if c.use_sonar == Some(false) {
                scenario.tour.navigation.sonar = None;
            }
            if let Some(method) = &c.method {
                scenario.tour.navigation.method = method.parse().map_err(|e: String| {
                    source.error_in_file(Some(format!("condition[{i}].method")), e)
                })?;
            }
            conditions.push(NavCondition {
                name: c.name.clone(),
                scenario,
            });
        }
        Ok(NavStudy {
            name: file.name,
            description: file.description,
            conditions,
            trials_per_condition: file.trials_per_condition,
            seed: file.seed,
            start_radius_m: file.start_radius_m.map_or(0.0, NonNegative::get),
            clearance_m: file.clearance_m.map_or(0.6, Positive::get),
            success_m: file.success_m.map_or(0.5, Positive::get),
            path: source.path.clone(),
            text: source.text.clone(),
        })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NavStudyFile {
    name: String,
    #[serde(default)]
    description: String,
    scenario: toml::Spanned<String>,
    trials_per_condition: u64,
    seed: u64,
    start_radius_m: Option<NonNegative>,
    clearance_m: Option<Positive>,
    success_m: Option<Positive>,
    #[serde(default)]
    condition: Vec<ConditionFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ConditionFile {
    name: String,
    noise: Option<NoiseFile>,
    use_sonar: Option<bool>,
    method: Option<String>,
}
