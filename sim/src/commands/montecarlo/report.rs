//! The study's reports: `summary.json`, `table.md` (laid out like the thesis's Table 5.1) and
//! `errors.svg` (the error distributions). All are computed from the rows of `trials.csv` as
//! written, so a run, a resumed run and merged shards give the same bytes.

use super::{StudyError, io_error};
use crate::config::Study;
use robot::localization::MatcherKind;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One row of `trials.csv`, as the reports need it.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// The trial.
    pub trial: u64,
    /// Its outlier rate.
    pub rate: f64,
    /// The matcher.
    pub matcher: MatcherKind,
    /// Heading error, degrees.
    pub e_theta_deg: f64,
    /// Translation error, millimetres.
    pub e_t_mm: f64,
    /// Iterations.
    pub iterations: u32,
    /// Converged.
    pub converged: bool,
    /// Heading error of the odometry guess, degrees.
    pub guess_e_theta_deg: f64,
    /// Translation error of the odometry guess, millimetres.
    pub guess_e_t_mm: f64,
}

/// Reads the rows of `trials.csv` (`text`, header first).
pub fn parse_rows(path: &Path, text: &str) -> Result<Vec<Record>, StudyError> {
    text.lines()
        .enumerate()
        .skip(1)
        .map(|(i, line)| {
            let bad = |message: &str| StudyError::BadRow {
                path: path.to_path_buf(),
                line: i + 1,
                message: message.into(),
            };
            let f: Vec<&str> = line.split(',').collect();
            if f.len() != super::TRIALS_HEADER.split(',').count() {
                return Err(bad("wrong number of fields"));
            }
            let number = |k: usize| f[k].parse::<f64>().map_err(|_| bad("a pose field"));
            let truth = robot::Pose2::new(number(5)?, number(6)?, number(7)?);
            let guess = robot::Pose2::new(number(8)?, number(9)?, number(10)?);
            let (guess_e_theta_deg, guess_e_t_mm) = super::errors(&truth, &guess);
            Ok(Record {
                guess_e_theta_deg,
                guess_e_t_mm,
                trial: f[0].parse().map_err(|_| bad("trial"))?,
                rate: f[2].parse().map_err(|_| bad("rate"))?,
                matcher: f[3].parse().map_err(|_| bad("matcher"))?,
                e_theta_deg: f[14].parse().map_err(|_| bad("e_theta_deg"))?,
                e_t_mm: f[15].parse().map_err(|_| bad("e_t_mm"))?,
                iterations: f[16].parse().map_err(|_| bad("iterations"))?,
                converged: f[17] == "1",
            })
        })
        .collect()
}

/// The figures of one matcher at one outlier rate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CellStats {
    /// The matcher.
    pub matcher: String,
    /// The outlier rate.
    pub rate: f64,
    /// Trials.
    pub trials: u64,
    /// Mean heading error, degrees.
    pub mean_e_theta_deg: f64,
    /// Sample standard deviation of the heading error, degrees.
    pub sd_e_theta_deg: f64,
    /// Largest heading error, degrees.
    pub max_e_theta_deg: f64,
    /// Mean translation error, millimetres.
    pub mean_e_t_mm: f64,
    /// Sample standard deviation of the translation error, millimetres.
    pub sd_e_t_mm: f64,
    /// Largest translation error, millimetres.
    pub max_e_t_mm: f64,
    /// Share of trials within 1° and 10 mm.
    pub within_1deg_10mm: f64,
    /// Share of trials whose match was flagged `converged` (trusted: its quality passed the
    /// matcher's trust rule).
    pub converged: f64,
    /// Mean translation error of the pose used when a match not trusted falls back to the
    /// odometry guess, as the map builder does, millimetres.
    pub fallback_mean_e_t_mm: f64,
    /// Share of trials within 1° and 10 mm with that fallback.
    pub fallback_within_1deg_10mm: f64,
    /// Mean iterations.
    pub mean_iterations: f64,
}

/// `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// The study.
    pub study: String,
    /// Master seed.
    pub seed: u64,
    /// Trials per rate.
    pub trials_per_rate: u64,
    /// Units of the figures.
    pub units: &'static str,
    /// One entry per rate and matcher, rates first.
    pub cells: Vec<CellStats>,
}

/// Mean, sample standard deviation and maximum.
fn moments(values: &[f64]) -> (f64, f64, f64) {
    let n = values.len() as f64;
    if values.is_empty() {
        return (0.0, 0.0, 0.0);
    }
    let mean = values.iter().sum::<f64>() / n;
    let var = if values.len() > 1 {
        values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    let max = values.iter().copied().fold(0.0, f64::max);
    (mean, var.sqrt(), max)
}

impl Summary {
    /// The figures of `records` (in `trials.csv` order).
    pub fn of(study: &Study, records: &[Record]) -> Self {
        let mut cells = Vec::new();
        for &rate in &study.outlier_rates {
            // The odometry guess first (the rows of the first matcher carry each trial once),
            // then the matchers that start from it.
            let guess = Some(study.matchers[0]).into_iter().map(|m| (m, true));
            for (matcher, is_guess) in guess.chain(study.matchers.iter().map(|&m| (m, false))) {
                let rows: Vec<&Record> = records
                    .iter()
                    .filter(|r| r.rate == rate && r.matcher == matcher)
                    .collect();
                let pick = |r: &&Record| {
                    if is_guess {
                        (r.guess_e_theta_deg, r.guess_e_t_mm)
                    } else {
                        (r.e_theta_deg, r.e_t_mm)
                    }
                };
                let theta: Vec<f64> = rows.iter().map(|r| pick(r).0).collect();
                let t: Vec<f64> = rows.iter().map(|r| pick(r).1).collect();
                let (mean_e_theta_deg, sd_e_theta_deg, max_e_theta_deg) = moments(&theta);
                let (mean_e_t_mm, sd_e_t_mm, max_e_t_mm) = moments(&t);
                let n = rows.len().max(1) as f64;
                let share =
                    |f: &dyn Fn(&Record) -> bool| rows.iter().filter(|r| f(r)).count() as f64 / n;
                let within = theta
                    .iter()
                    .zip(&t)
                    .filter(|(a, b)| **a <= 1.0 && **b <= 10.0);
                let within_1deg_10mm = within.count() as f64 / n;
                // The pose a user of the flag keeps: the match when trusted, else the guess.
                let used: Vec<(f64, f64)> = rows
                    .iter()
                    .map(|r| {
                        if is_guess || r.converged {
                            pick(r)
                        } else {
                            (r.guess_e_theta_deg, r.guess_e_t_mm)
                        }
                    })
                    .collect();
                let fallback_mean_e_t_mm = used.iter().map(|u| u.1).sum::<f64>() / n;
                let fallback_within_1deg_10mm =
                    used.iter().filter(|u| u.0 <= 1.0 && u.1 <= 10.0).count() as f64 / n;
                let (converged, mean_iterations) = if is_guess {
                    (1.0, 0.0)
                } else {
                    (
                        share(&|r| r.converged),
                        rows.iter().map(|r| f64::from(r.iterations)).sum::<f64>() / n,
                    )
                };
                cells.push(CellStats {
                    matcher: if is_guess {
                        "odometry (the guess)".to_string()
                    } else {
                        matcher.to_string()
                    },
                    rate,
                    trials: rows.len() as u64,
                    mean_e_theta_deg,
                    sd_e_theta_deg,
                    max_e_theta_deg,
                    mean_e_t_mm,
                    sd_e_t_mm,
                    max_e_t_mm,
                    within_1deg_10mm,
                    converged,
                    fallback_mean_e_t_mm,
                    fallback_within_1deg_10mm,
                    mean_iterations,
                });
            }
        }
        Summary {
            study: study.name.clone(),
            seed: study.seed,
            trials_per_rate: study.trials_per_rate,
            units: "e_theta in degrees, e_t in millimetres; sd is the sample standard deviation",
            cells,
        }
    }

    /// The table, laid out like the thesis's Table 5.1, in Markdown.
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "| method | outliers | trials | mean e_θ (°) | sd e_θ (°) | max e_θ (°) | mean e_t (mm) | sd e_t (mm) | max e_t (mm) | within 1° and 10 mm | trusted | with fallback: mean e_t (mm), within 1° and 10 mm |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|");
        for c in &self.cells {
            let _ = writeln!(
                s,
                "| {} | {} % | {} | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} | {:.2} | {:.1} % | {:.1} % | {:.2}, {:.1} % |",
                c.matcher,
                format_rate(c.rate),
                c.trials,
                c.mean_e_theta_deg,
                c.sd_e_theta_deg,
                c.max_e_theta_deg,
                c.mean_e_t_mm,
                c.sd_e_t_mm,
                c.max_e_t_mm,
                100.0 * c.within_1deg_10mm,
                100.0 * c.converged,
                c.fallback_mean_e_t_mm,
                100.0 * c.fallback_within_1deg_10mm,
            );
        }
        s
    }
}

fn format_rate(rate: f64) -> String {
    let pct = (rate * 1e4).round() / 100.0;
    format!("{pct}")
}

/// Writes `summary.json`, `table.md` and `errors.svg` into `dir`.
pub fn write_reports(
    study: &Study,
    summary: &Summary,
    records: &[Record],
    dir: &Path,
) -> Result<Vec<PathBuf>, StudyError> {
    let files = ["summary.json", "table.md", "errors.svg"].map(|f| dir.join(f));
    let mut json = serde_json::to_string_pretty(summary).map_err(|e| StudyError::Io {
        path: files[0].clone(),
        source: e.into(),
    })?;
    json.push('\n');
    robot::logs::write_file(&files[0], json).map_err(io_error(&files[0]))?;
    let table = format!(
        "# {}\n\n{} trials per rate, seed {}; e_θ in degrees, e_t in millimetres, sd the sample standard deviation.\n\n{}",
        study.name,
        study.trials_per_rate,
        study.seed,
        summary.table()
    );
    robot::logs::write_file(&files[1], table).map_err(io_error(&files[1]))?;
    robot::logs::write_file(&files[2], errors_svg(study, records)).map_err(io_error(&files[2]))?;
    Ok(files.to_vec())
}

/// Colours of the matchers, in `MatcherKind::ALL` order.
const COLOURS: [&str; 5] = ["#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#8c564b"];

fn colour_of(kind: MatcherKind, k: usize) -> &'static str {
    COLOURS[MatcherKind::ALL
        .iter()
        .position(|m| *m == kind)
        .unwrap_or(k)
        % COLOURS.len()]
}

/// The cumulative distributions of e_θ (top) and e_t (bottom) per rate (columns), one curve per
/// matcher and one (dashed) for the odometry guess they start from, on logarithmic axes.
fn errors_svg(study: &Study, records: &[Record]) -> String {
    use crate::output::figure::{Layers, Swatch, open_svg, xml_escape};
    let (pw, ph, margin) = (420.0, 260.0, 70.0);
    let cols = study.outlier_rates.len();
    let width = margin + cols as f64 * (pw + margin);
    let column = 190.0;
    let columns = (((width - margin) / column).floor() as usize).max(1);
    let entries = study.matchers.len() + 1;
    let legend_rows = entries.div_ceil(columns);
    let top = 60.0 + 20.0 * legend_rows as f64 + 30.0;
    let height = top + 2.0 * (ph + margin);
    let mut layers = Layers::default();
    let axes = [
        ("e_θ (degrees)", -3.0, 2.0),
        ("e_t (millimetres)", -1.0, 4.0),
    ];
    let mut curves: Vec<String> = vec![String::new(); entries];
    for (row, (label, lo, hi)) in axes.iter().enumerate() {
        for (col, &rate) in study.outlier_rates.iter().enumerate() {
            let x0 = margin + col as f64 * (pw + margin);
            let y0 = top + row as f64 * (ph + margin);
            let mut frame = String::new();
            let _ = write!(
                frame,
                r##"<rect x="{x0}" y="{y0}" width="{pw}" height="{ph}" fill="none" stroke="#888"/>"##
            );
            let _ = write!(
                frame,
                r#"<text x="{}" y="{}">{label}, {} % outliers</text>"#,
                x0,
                y0 - 14.0,
                format_rate(rate)
            );
            let _ = write!(
                frame,
                r##"<text x="{:.1}" y="{:.1}" text-anchor="middle" fill="#555" transform="rotate(-90 {:.1} {:.1})">share of trials</text>"##,
                x0 - 40.0,
                y0 + ph / 2.0,
                x0 - 40.0,
                y0 + ph / 2.0
            );
            let mut decade = *lo;
            while decade <= *hi + 1e-9 {
                let gx = x0 + (decade - lo) / (hi - lo) * pw;
                let _ = write!(
                    frame,
                    r##"<line x1="{gx:.1}" y1="{y0}" x2="{gx:.1}" y2="{}" stroke="#eee"/><text x="{gx:.1}" y="{}" text-anchor="middle">{}</text>"##,
                    y0 + ph,
                    y0 + ph + 14.0,
                    10f64.powf(decade)
                );
                decade += 1.0;
            }
            let _ = write!(
                frame,
                r##"<text x="{:.1}" y="{:.1}" text-anchor="middle" fill="#555">{label}, logarithmic</text>"##,
                x0 + pw / 2.0,
                y0 + ph + 30.0
            );
            for q in [0.0, 0.5, 1.0] {
                let gy = y0 + ph * (1.0 - q);
                let _ = write!(
                    frame,
                    r#"<text x="{}" y="{:.1}" text-anchor="end">{q}</text>"#,
                    x0 - 4.0,
                    gy + 4.0
                );
            }
            layers.plain(&frame);
            let kinds = std::iter::once(None).chain(study.matchers.iter().map(Some));
            for (k, kind) in kinds.enumerate() {
                let first = study.matchers[0];
                let mut values: Vec<f64> = records
                    .iter()
                    .filter(|r| r.rate == rate && r.matcher == *kind.unwrap_or(&first))
                    .map(|r| match (kind, row) {
                        (None, 0) => r.guess_e_theta_deg,
                        (None, _) => r.guess_e_t_mm,
                        (Some(_), 0) => r.e_theta_deg,
                        (Some(_), _) => r.e_t_mm,
                    })
                    .collect();
                if values.is_empty() {
                    continue;
                }
                values.sort_by(f64::total_cmp);
                let n = values.len();
                let step = (n / 300).max(1);
                let mut d = String::new();
                for (i, v) in values.iter().enumerate() {
                    if i % step != 0 && i + 1 != n {
                        continue;
                    }
                    let lx = v.max(10f64.powf(*lo)).log10().clamp(*lo, *hi);
                    let px = x0 + (lx - lo) / (hi - lo) * pw;
                    let py = y0 + ph * (1.0 - (i + 1) as f64 / n as f64);
                    let _ = write!(
                        d,
                        "{}{px:.1},{py:.1} ",
                        if d.is_empty() { "M" } else { "L" }
                    );
                }
                let (colour, dash) = match kind {
                    None => ("#555", r#" stroke-dasharray="6 4""#),
                    Some(kind) => (colour_of(*kind, k), ""),
                };
                let _ = write!(
                    curves[k],
                    r#"<path d="{}" fill="none" stroke="{colour}" stroke-width="2"{dash}/>"#,
                    d.trim_end()
                );
            }
        }
    }
    layers.add(
        "odometry",
        "odometry (the guess)",
        Swatch::Line("#555", 2.0, Some("6 4")),
        &curves[0],
    );
    for (k, kind) in study.matchers.iter().enumerate() {
        let colour = colour_of(*kind, k + 1);
        layers.add(
            &format!("matcher-{kind}"),
            kind.to_string(),
            Swatch::Line(colour, 2.0, None),
            &curves[k + 1],
        );
    }
    let mut s = open_svg(width, height, 12);
    let _ = writeln!(
        s,
        r#"<text x="{margin}" y="24" font-size="16">{}: share of trials with an error at most x ({} trials per rate)</text>"#,
        xml_escape(&study.name),
        study.trials_per_rate
    );
    s.push_str(layers.body());
    s.push_str(&layers.legend(margin, 50.0, columns, column));
    s.push_str("</svg>\n");
    s
}
