//! Monte Carlo study files (`studies/*.toml`): what `twin montecarlo` compares, in which world,
//! with which robot and noise, over how many trials.
//!
//! ```toml
//! name = "table-5-1"
//! world = "../worlds/orthogonal.toml"       # default: ../worlds/orthogonal.toml
//! robot = "../scenarios/robots/pioneer-3dx.toml"
//! matchers = ["ls", "lorentz", "lorentz-lines", "mbicp"]
//! outlier_rates = [0.02, 0.20]              # uniform outliers, share of the readings
//! trials_per_rate = 10000
//! seed = 2007
//! clearance_m = 0.8                         # start poses at least this far from walls
//!
//! [motion]                                  # each trial: one of these, equally likely
//! advance_m = 0.5                           # advance or retreat this far
//! turn_deg = 25                             # or turn left or right this much
//!
//! [noise]                                   # as in scenarios: slip, wheel errors, laser σ
//! slip_sigma_sqrt_m = 0.003
//! ```
//!
//! Paths are relative to the study file. The whole text is kept: a resumed run and the shards
//! of a study check they belong to the same one.

use super::error::{ConfigError, Source};
use super::robot_file::RobotDescription;
use super::scenario::{NoiseFile, NoiseSettings, load_named};
use super::values::{NonNegative, Positive};
use super::world::WorldDescription;
use crate::config::Outliers;
use robot::localization::{MatcherKind, UnknownMatcher};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// The motions a trial draws from.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct MotionSettings {
    /// Advance or retreat distance, metres (0: no straight motions).
    pub advance_m: f64,
    /// Turn angle, degrees (0: no turns).
    pub turn_deg: f64,
}

/// A validated study.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// Short name.
    pub name: String,
    /// What it measures.
    pub description: String,
    /// The world.
    pub world: WorldDescription,
    /// The robot.
    pub robot: RobotDescription,
    /// The matchers compared, in the order of the outputs.
    pub matchers: Vec<MatcherKind>,
    /// Uniform outlier rates, each a share of the readings in `[0, 1)`.
    pub outlier_rates: Vec<f64>,
    /// Trials at each rate.
    pub trials_per_rate: u64,
    /// Master seed: every trial's randomness derives from it and the trial's number.
    pub seed: u64,
    /// Least distance from a start pose to any wall, metres.
    pub clearance_m: f64,
    /// The motions.
    pub motion: MotionSettings,
    /// Slip, wheel errors and laser σ (outliers come from `outlier_rates`).
    pub noise: NoiseSettings,
    /// The file it was read from.
    pub path: PathBuf,
    /// The file's text.
    pub text: String,
}

impl Study {
    /// Trials in the whole study.
    pub fn total_trials(&self) -> u64 {
        self.trials_per_rate * self.outlier_rates.len() as u64
    }

    /// The same study with `trials` trials per rate (`twin montecarlo --trials`): a smaller
    /// study of the same design, with its own table. Its text (kept in the output folder, which
    /// it then owns) says so: `trials_per_rate` is rewritten, or added when the file left it out.
    /// `trials` is at least 1 (clap's range on `--trials`).
    pub fn with_trials_per_rate(mut self, trials: u64) -> Self {
        let trials = trials.max(1);
        let line = format!("trials_per_rate = {trials}  # twin montecarlo --trials {trials}");
        let mut replaced = false;
        let mut text: Vec<String> = self
            .text
            .lines()
            .map(|l| {
                if !replaced && l.trim_start().starts_with("trials_per_rate") {
                    replaced = true;
                    line.clone()
                } else {
                    l.to_string()
                }
            })
            .collect();
        if !replaced {
            // Top-level keys must come before the first table.
            let at = text
                .iter()
                .position(|l| l.trim_start().starts_with('['))
                .unwrap_or(text.len());
            text.insert(at, line);
        }
        self.text = text.join("\n") + "\n";
        self.trials_per_rate = trials;
        self
    }

    /// Reads a study and the world and robot it names.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ConfigError> {
        let source = Source::read(path.as_ref())?;
        Self::from_source(&source)
    }

    fn from_source(source: &Source) -> Result<Self, ConfigError> {
        let file: StudyFile = source.parse()?;
        let default_world = Spanned::new(0..0, "../worlds/orthogonal.toml".to_string());
        let world = load_named(
            source,
            file.world.as_ref().unwrap_or(&default_world),
            "world",
            |p| WorldDescription::load(p),
        )?;
        let robot = load_named(source, &file.robot, "robot", |p| RobotDescription::load(p))?;
        let mut noise = NoiseSettings::defaults_for(&robot);
        if let Some(n) = &file.noise {
            n.apply(&mut noise, source)?;
        }
        noise.outliers = Outliers::NONE;
        let names = file.matchers.as_ref().map_or_else(
            || vec!["ls", "lorentz", "lorentz-lines", "mbicp"],
            |m| m.get_ref().iter().map(String::as_str).collect(),
        );
        let span = file.matchers.as_ref().map_or(0..0, |m| m.span());
        let mut matchers = Vec::new();
        for name in names {
            let kind: MatcherKind = name.parse().map_err(|e: UnknownMatcher| {
                source.error(span.clone(), Some("matchers".into()), e.to_string())
            })?;
            if matchers.contains(&kind) {
                return Err(source.error(
                    span.clone(),
                    Some("matchers".into()),
                    format!("{kind} is named twice"),
                ));
            }
            matchers.push(kind);
        }
        if matchers.is_empty() {
            return Err(source.error(span, Some("matchers".into()), "name at least one matcher"));
        }
        let rates = file
            .outlier_rates
            .as_ref()
            .map_or_else(|| vec![0.02, 0.20], |r| r.get_ref().clone());
        let span = file.outlier_rates.as_ref().map_or(0..0, |r| r.span());
        if rates.is_empty() || rates.iter().any(|r| !(0.0..1.0).contains(r)) {
            return Err(source.error(
                span,
                Some("outlier_rates".into()),
                format!("expected one or more shares in [0, 1), found {rates:?}"),
            ));
        }
        let trials = file.trials_per_rate.unwrap_or(10_000);
        if !(1..=100_000_000).contains(&trials) {
            return Err(source.error_in_file(
                Some("trials_per_rate".into()),
                format!("expected 1..=100000000 trials, found {trials}"),
            ));
        }
        let motion = file.motion.as_ref();
        let motion = MotionSettings {
            advance_m: motion
                .and_then(|m| m.advance_m)
                .map_or(0.5, NonNegative::get),
            turn_deg: motion
                .and_then(|m| m.turn_deg)
                .map_or(25.0, NonNegative::get),
        };
        if motion.advance_m == 0.0 && motion.turn_deg == 0.0 {
            return Err(source.error_in_file(
                Some("motion".into()),
                "a trial needs a motion: advance_m or turn_deg above 0",
            ));
        }
        Ok(Study {
            name: file.name,
            description: file.description,
            world,
            robot,
            matchers,
            outlier_rates: rates,
            trials_per_rate: trials,
            seed: file.seed,
            clearance_m: file.clearance_m.map_or(0.8, Positive::get),
            motion,
            noise,
            path: source.path.clone(),
            text: source.text.clone(),
        })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyFile {
    name: String,
    #[serde(default)]
    description: String,
    world: Option<Spanned<String>>,
    robot: Spanned<String>,
    matchers: Option<Spanned<Vec<String>>>,
    outlier_rates: Option<Spanned<Vec<f64>>>,
    trials_per_rate: Option<u64>,
    seed: u64,
    clearance_m: Option<Positive>,
    motion: Option<MotionFile>,
    noise: Option<NoiseFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MotionFile {
    advance_m: Option<NonNegative>,
    turn_deg: Option<NonNegative>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn study(text: &str) -> Result<Study, ConfigError> {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../studies/test.toml");
        Study::from_source(&Source::text(text, &path))
    }

    const HEAD: &str = "name = \"t\"\nrobot = \"../scenarios/robots/pioneer-3dx.toml\"\nseed = 1\n";

    #[test]
    fn defaults_are_the_thesis_study() {
        let s = study(HEAD).unwrap();
        assert_eq!(s.world.name, "orthogonal");
        assert_eq!(s.outlier_rates, vec![0.02, 0.20]);
        assert_eq!(s.trials_per_rate, 10_000);
        assert_eq!(s.matchers.len(), 4);
        assert_eq!((s.motion.advance_m, s.motion.turn_deg), (0.5, 25.0));
        assert_eq!(s.total_trials(), 20_000);
    }

    #[test]
    fn bad_fields_are_named() {
        let e = study(&format!("{HEAD}matchers = [\"lorentz\", \"magic\"]\n")).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("matchers"));
        assert_eq!(e.line, Some(4));
        let e = study(&format!("{HEAD}outlier_rates = [0.02, 1.5]\n")).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("outlier_rates"));
        let e = study(&format!("{HEAD}[motion]\nadvance_m = 0\nturn_deg = 0\n")).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("motion"));
        let e = study(&format!("{HEAD}trails_per_rate = 5\n")).unwrap_err();
        assert!(e.message.contains("trails_per_rate"), "{e}");
    }
}
