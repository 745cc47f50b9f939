//! Issue 14: bad input never panics, hangs or poisons an output. Property tests mutate every
//! kind of input the project reads — worlds, robots, scenarios, studies, logs, `twin match`
//! lines, the microcontrollers' reply lines and SICK telegrams, and what the matchers are given —
//! and one test per class of the campaign's findings pins it down.
//!
//! The cases per property are proptest's (`PROPTEST_CASES`, 256 by default, fewer where a case
//! runs the twin); a longer campaign is the same file with more cases (README, "Fuzzing").

use proptest::prelude::*;
use robot::Pose2;
use robot::localization::{MatcherKind, RangeScan};
use robot::logs::{LogFormat, parse_log};
use sim::commands::montecarlo::{RunOptions, StudyError, run_study};
use sim::config::{RobotDescription, Scenario, Study, WorldDescription};
use sim::world::WorldMap;
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twin-issue-14-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A file of the repository with its relative paths made absolute, so a mutated copy can live
/// in a scratch folder.
fn absolute(path: &str) -> String {
    let text = std::fs::read_to_string(repo().join(path)).unwrap();
    let folder = repo().join(path).parent().unwrap().to_path_buf();
    text.replace("\"../", &format!("\"{}/../", folder.display()))
        .replace("\"robots/", &format!("\"{}/robots/", folder.display()))
}

/// Numbers a fuzzer likes: huge, tiny, subnormal, negative, not numbers at all.
const EXTREMES: &[&str] = &[
    "1e308",
    "-1e308",
    "1e38",
    "4e9",
    "0",
    "-0.0",
    "1e-320",
    "nan",
    "inf",
    "-1",
    "1e20",
    "3.5e15",
    "0.0000001",
    "99999999999999999999",
    "1e12",
    "65536",
    "-3600.5",
];

/// One mutation of a text: `kind` picks what, `at` where, `extreme` which number.
#[derive(Clone, Debug)]
struct Mutation {
    kind: u8,
    at: usize,
    extreme: usize,
    garbage: String,
}

fn mutation() -> impl Strategy<Value = Mutation> {
    (0u8..6, any::<usize>(), 0..EXTREMES.len(), "[ -~]{0,12}").prop_map(
        |(kind, at, extreme, garbage)| Mutation {
            kind,
            at,
            extreme,
            garbage,
        },
    )
}

/// The byte ranges of the numbers in `text`.
fn numbers(text: &str) -> Vec<std::ops::Range<usize>> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let starts = bytes[i].is_ascii_digit()
            && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
        if starts {
            let from = if i > 0 && bytes[i - 1] == b'-' {
                i - 1
            } else {
                i
            };
            let mut j = i;
            while j < bytes.len()
                && (bytes[j].is_ascii_digit() || matches!(bytes[j], b'.' | b'e' | b'-' | b'_'))
            {
                j += 1;
            }
            out.push(from..j);
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

fn mutate(text: &str, m: &Mutation) -> String {
    let lines: Vec<&str> = text.lines().collect();
    match m.kind {
        // A number replaced by an extreme one (twice as likely as the rest).
        0 | 1 => {
            let spans = numbers(text);
            if spans.is_empty() {
                return text.to_string();
            }
            let span = spans[m.at % spans.len()].clone();
            format!(
                "{}{}{}",
                &text[..span.start],
                EXTREMES[m.extreme],
                &text[span.end..]
            )
        }
        // A line dropped.
        2 => {
            let k = m.at % lines.len().max(1);
            let kept: Vec<&str> = lines
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != k)
                .map(|(_, l)| *l)
                .collect();
            kept.join("\n")
        }
        // Truncated.
        3 => {
            let mut cut = m.at % (text.len() + 1);
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            text[..cut].to_string()
        }
        // A line duplicated.
        4 => {
            let k = m.at % lines.len().max(1);
            let mut out: Vec<&str> = lines.clone();
            if let Some(l) = lines.get(k) {
                out.insert(k, l);
            }
            out.join("\n")
        }
        // Garbage inserted at a line start.
        _ => {
            let k = m.at % (lines.len() + 1);
            let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
            out.insert(k, m.garbage.clone());
            out.join("\n")
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// A world file, mutated: refused with a located error, or accepted and buildable.
    #[test]
    fn a_mutated_world_is_refused_or_built(m in mutation()) {
        let text = mutate(&std::fs::read_to_string(repo().join("worlds/lab.toml")).unwrap(), &m);
        match WorldDescription::parse(&text, "worlds/lab.toml") {
            Ok(world) => {
                let map = WorldMap::new(&world);
                let d = map.distance_3d([world.start.x, world.start.y, 0.3]);
                prop_assert!(d.is_finite());
            }
            Err(e) => prop_assert!(e.to_string().starts_with("worlds/lab.toml")),
        }
    }

    /// A robot file, mutated: refused with a located error, or accepted.
    #[test]
    fn a_mutated_robot_is_refused_or_read(m in mutation(), thesis in any::<bool>()) {
        let name = if thesis { "thesis-roca.toml" } else { "pioneer-3dx.toml" };
        let path = repo().join("scenarios/robots").join(name);
        let text = mutate(&std::fs::read_to_string(&path).unwrap(), &m);
        if let Err(e) = RobotDescription::parse(&text, name) {
            prop_assert!(e.to_string().starts_with(name), "{e}");
        }
    }

    /// Log lines, mutated: refused naming the file and line, or read.
    #[test]
    fn a_mutated_log_is_refused_or_read(m in mutation(), n in 1usize..4) {
        let text: String = std::fs::read_to_string(repo().join("tests/data/mit-csail.clf"))
            .unwrap()
            .lines()
            .take(40 * n)
            .map(|l| format!("{l}\n"))
            .collect();
        let text = mutate(&text, &m);
        match parse_log(&text, LogFormat::Carmen, "x.clf") {
            Ok(log) => prop_assert!(log.scans() > 0),
            Err(e) => prop_assert!(e.to_string().starts_with("x.clf"), "{e}"),
        }
    }

    /// The other two log formats (App. C.1's `.script`, RobotLogger's `.log`), mutated: refused
    /// naming the file and line, or read.
    #[test]
    fn mutated_script_and_robotlogger_logs_are_refused_or_read(m in mutation(), copies in 1usize..6) {
        let script = "POS 976052857 337284: 0.000000 0.000000 -0.140850\n\
                      LASER-RANGE 976052857 337530 0 3 180.0: 1070.0 2000.0 1050.0\n\
                      POS 976055548 522255: -5088.399900 -3582.500000 -214.577450\n";
        let robotlogger = "odometry:      2011 05 19 22 22 50.728448:0,0,0,-1.96721e-44,0,0,0\n\
                           laser-scan:    2011 05 19 22 22 50.728448:-4.7457e-08,-1.08569,6.36921e-08,0.935997\n\
                           laser-geometry: 0.03,0,0,1,1,1\n";
        for (text, format, file) in [
            (script, LogFormat::Script, "a.script"),
            (robotlogger, LogFormat::RobotLogger, "r.log"),
        ] {
            let text = mutate(&text.repeat(copies), &m);
            match parse_log(&text, format, file) {
                Ok(log) => prop_assert!(log.scans() > 0),
                Err(e) => prop_assert!(e.to_string().starts_with(file), "{e}"),
            }
        }
    }

    /// Any line to `twin match` gets one answer: the match, or an error naming the line.
    #[test]
    fn twin_match_answers_every_line(m in mutation(), number in 1usize..10_000) {
        let scan = |r: f64| format!(
            r#"{{"angle_min": -1.5, "angle_increment": 0.05, "range_max": 30, "ranges": [{}]}}"#,
            (0..61).map(|i| format!("{}", r + 0.01 * f64::from(i % 7))).collect::<Vec<_>>().join(", ")
        );
        let line = format!(r#"{{"ref": {}, "cur": {}, "guess": [0.1, 0.0, 0.02]}}"#, scan(2.0), scan(2.1));
        let line = mutate(&line, &m).replace('\n', " ");
        for kind in MatcherKind::ALL {
            let reply = sim::commands::map::match_line(number, &line, kind.build().as_ref());
            let json: serde_json::Value = serde_json::from_str(&reply).unwrap();
            match json.get("error") {
                Some(e) => {
                    let prefix = format!("line {number}: ");
                    prop_assert!(e.as_str().unwrap().starts_with(&prefix));
                }
                None => {
                    for k in ["x", "y", "theta"] {
                        prop_assert!(json[k].as_f64().is_some_and(f64::is_finite), "{reply}");
                    }
                }
            }
        }
    }

    /// The microcontrollers' reply lines and the laser's telegrams, any bytes: an error or a
    /// value, never a panic.
    #[test]
    fn reply_lines_and_telegrams_never_panic(line in "[ -~]{0,40}", bytes in proptest::collection::vec(any::<u8>(), 0..800)) {
        use robot::protocol::{base, pan_tilt, sick};
        let _ = base::parse_status(&line, robot::Stamp::ZERO);
        let _ = base::parse_battery(&line, robot::Stamp::ZERO);
        let _ = base::parse_command_text(&line);
        let _ = base::parse_ack(&line, 'a');
        let _ = pan_tilt::parse_status(&line, robot::Stamp::ZERO);
        let _ = line.parse::<robot::control::Step>();
        if let Ok((telegram, _)) = sick::Telegram::decode(&bytes)
            && let Ok(values) = sick::MeasuredValues::from_telegram(&telegram)
            && let Ok(scan) = values.to_scan(robot::Stamp::ZERO, 32_000)
        {
            prop_assert!(scan.ranges_mm.len() <= 401);
            prop_assert!(scan.angle_increment > 0.0);
        }
    }
}

/// A range that is any finite number, most of them absurd.
fn any_range() -> impl Strategy<Value = f64> {
    prop_oneof![
        0.1f64..20.0,
        Just(0.0),
        Just(1e200),
        Just(1e308),
        Just(-1e308),
        Just(f64::MIN_POSITIVE),
        -1e6f64..1e6,
    ]
}

fn any_angle() -> impl Strategy<Value = f64> {
    prop_oneof![
        -3.2f64..3.2,
        Just(1e308),
        Just(-1e300),
        Just(1e-300),
        Just(0.0)
    ]
}

fn any_scan() -> impl Strategy<Value = RangeScan> {
    (
        any_angle(),
        any_angle(),
        prop_oneof![Just(30.0), Just(1e308), 0.5f64..80.0],
        proptest::collection::vec(any_range(), 0..80),
    )
        .prop_map(|(min, inc, max, ranges)| RangeScan::new(min, inc, max, ranges))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Finite numbers of any size: every matcher answers, with a finite pose or the guess.
    #[test]
    fn every_matcher_answers_any_finite_input(
        reference in any_scan(),
        current in any_scan(),
        guess in (prop_oneof![-1.0f64..1.0, Just(1e200), Just(-1e5)], -1.0f64..1.0, any_angle()),
    ) {
        let guess = Pose2::new(guess.0, guess.1, guess.2);
        for kind in MatcherKind::ALL {
            let result = kind.build().match_scans(&reference, &current, guess);
            let p = result.pose;
            prop_assert!(
                (p.x.is_finite() && p.y.is_finite() && p.theta.is_finite()) || p == guess,
                "{kind:?}: {p:?}"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// A scenario, mutated: refused with a located error, or run — and then no output file
    /// holds NaN or infinity.
    #[test]
    fn an_accepted_scenario_writes_no_nan(m in mutation()) {
        let dir = scratch(&format!("scenario-{}", m.at % 1000));
        let text = mutate(&absolute("scenarios/wall-collision.toml"), &m);
        let path = dir.join("s.toml");
        std::fs::write(&path, &text).unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_twin"))
            .args(["run", "-q", path.to_str().unwrap(), "--out"])
            .arg(dir.join("out"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        prop_assert!(!stderr.contains("panicked"), "{stderr}");
        if Scenario::load(&path).is_ok() {
            for entry in std::fs::read_dir(dir.join("out")).unwrap() {
                let file = entry.unwrap().path();
                let Ok(content) = std::fs::read_to_string(&file) else { continue };
                for word in ["NaN", "nan", "inf"] {
                    let found = content
                        .split(|c: char| !c.is_ascii_alphanumeric())
                        .any(|w| w == word || w == "-inf");
                    prop_assert!(!found, "{} holds {word}", file.display());
                }
            }
        } else {
            prop_assert!(stderr.contains("s.toml"), "{stderr}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A study, mutated: refused, or two of its trials run (or refused with a clear error).
    #[test]
    fn a_mutated_study_is_refused_or_runs(m in mutation()) {
        let dir = scratch(&format!("study-{}", m.at % 1000));
        let text = mutate(&absolute("studies/table-5-1.toml"), &m);
        let path = dir.join("study.toml");
        std::fs::write(&path, &text).unwrap();
        if let Ok(study) = Study::load(&path) {
            let options = RunOptions { threads: 1, max_trials: Some(2), ..RunOptions::default() };
            if let Err(e) = run_study(&study, &dir.join("out"), &options, |_, _| {}) {
                prop_assert!(!e.to_string().is_empty());
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// Class 2: values checked as numbers but used in single precision or as durations.
#[test]
fn absurd_physical_values_are_refused_naming_the_field() {
    let dir = scratch("absurd");
    let world = std::fs::read_to_string(repo().join("worlds/lab.toml")).unwrap();
    let robot = std::fs::read_to_string(repo().join("scenarios/robots/pioneer-3dx.toml")).unwrap();
    let cases: Vec<(&str, String, &str)> = vec![
        ("world", world.replacen("[16, 0]", "[1e38, 0]", 1), "points"),
        (
            "world",
            world.replacen("heading_deg = 0.0", "heading_deg = 1e308", 1),
            "start",
        ),
        ("world", world.replacen("x = 1.6", "x = 1e6", 1), "start"),
        (
            "robot",
            robot.replace("sweep_s = ", "sweep_s = 1e308 #"),
            "laser.sweep_s",
        ),
        (
            "robot",
            robot.replace("telegram_bytes = 732", "telegram_bytes = 0"),
            "laser.telegram_bytes",
        ),
        (
            "robot",
            robot.replace("rays = ", "rays = 0 #"),
            "sonar.rays",
        ),
        (
            "robot",
            robot.replace("mass_kg = ", "mass_kg = 1e-320 #"),
            "body.mass_kg",
        ),
    ];
    for (kind, text, field) in &cases {
        assert_ne!(
            text,
            if *kind == "world" { &world } else { &robot },
            "the case {field} changed its file"
        );
        let err = match *kind {
            "world" => WorldDescription::parse(text, "w.toml").unwrap_err(),
            _ => RobotDescription::parse(text, "r.toml").unwrap_err(),
        };
        assert!(
            err.field.as_deref().is_some_and(|f| f.contains(field)),
            "{field}: {err}"
        );
    }
    // A scenario's durations and pauses.
    let scenario = absolute("scenarios/lab-tour.toml");
    for (extra, field) in [
        ("[tour]\npacing = \"polling\"\npoll_s = 1e20\n", "poll_s"),
        ("", "pause"),
    ] {
        let text = if extra.is_empty() {
            scenario.replacen("steps = [", "steps = [\"pause 1e12\", ", 1)
        } else {
            format!("{scenario}\n{extra}")
        };
        let path = dir.join("s.toml");
        std::fs::write(&path, text).unwrap();
        let err = Scenario::load(&path).unwrap_err().to_string();
        assert!(err.contains(field), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Class 3: a study no start pose can satisfy ends with an error; a changed row of the progress
/// log is detected and its trial run again.
#[test]
fn an_impossible_study_fails_and_a_tampered_log_row_is_redone() {
    let dir = scratch("study");
    let small = absolute("studies/table-5-1.toml")
        .replace("trials_per_rate = 10000", "trials_per_rate = 6");
    let path = dir.join("study.toml");
    std::fs::write(
        &path,
        small.replace("clearance_m = 0.8", "clearance_m = 50"),
    )
    .unwrap();
    let study = Study::load(&path).unwrap();
    let options = RunOptions {
        threads: 1,
        ..RunOptions::default()
    };
    let err = run_study(&study, &dir.join("impossible"), &options, |_, _| {}).unwrap_err();
    assert!(matches!(err, StudyError::Trial { .. }), "{err}");
    assert!(err.to_string().contains("clearance_m"), "{err}");

    std::fs::write(&path, &small).unwrap();
    let study = Study::load(&path).unwrap();
    run_study(&study, &dir.join("single"), &options, |_, _| {}).unwrap();
    let tampered = dir.join("tampered");
    run_study(&study, &tampered, &options, |_, _| {}).unwrap();
    // A well-formed but wrong row in the middle of the log: a matcher's estimate changed.
    let log = tampered.join("progress/trials.log");
    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let k = lines.len() / 2;
    let mut fields: Vec<String> = lines[k].split(',').map(str::to_string).collect();
    fields[5] = "0.5".into();
    lines[k] = fields.join(",");
    std::fs::write(&log, lines.join("\n") + "\n").unwrap();
    std::fs::remove_file(tampered.join("trials.csv")).unwrap();
    let again = run_study(&study, &tampered, &options, |_, _| {}).unwrap();
    assert_eq!(again.ran, 1, "the tampered trial runs again");
    for file in ["trials.csv", "summary.json"] {
        assert_eq!(
            std::fs::read(dir.join("single").join(file)).unwrap(),
            std::fs::read(tampered.join(file)).unwrap(),
            "{file}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Class 4: a client that floods `twin serve` and hangs up leaves nothing for the next one.
#[test]
fn a_new_client_of_twin_serve_inherits_nothing() {
    use sim::Twin;
    use sim::commands::serve::{Offer, ServeOptions, Server};
    use std::io::{Read, Write};
    use std::net::TcpStream;
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::time::Duration;
    let s = Scenario::load(repo().join("scenarios/lab-tour.toml")).unwrap();
    let twin = Twin::new(&s.world, &s.robot, &s.noise, s.seed).unwrap();
    let options = ServeOptions {
        speed: 1.0,
        base: Offer::Tcp("127.0.0.1:0".into()),
        pan_tilt: None,
        laser: None,
        live: None,
    };
    let mut server = Server::new(twin, &options).unwrap();
    let address = server.addresses()[0]
        .1
        .strip_prefix("tcp:")
        .unwrap()
        .to_string();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let handle = std::thread::spawn(move || server.run(&flag, None, |_, _| {}));
    std::thread::sleep(Duration::from_millis(300));
    // The first client asks for a hundred status lines and hangs up without reading them.
    let mut first = TcpStream::connect(&address).unwrap();
    first.write_all(&b"l\n".repeat(100)).unwrap();
    std::thread::sleep(Duration::from_millis(50));
    drop(first);
    std::thread::sleep(Duration::from_millis(100));
    // The second hears nothing until it speaks, then the answer to what it said.
    let mut second = TcpStream::connect(&address).unwrap();
    second
        .set_read_timeout(Some(Duration::from_millis(100)))
        .unwrap();
    let mut heard = Vec::new();
    let mut buf = [0u8; 4096];
    for _ in 0..8 {
        if let Ok(n) = second.read(&mut buf) {
            heard.extend_from_slice(&buf[..n]);
        }
    }
    assert!(
        heard.is_empty(),
        "stale replies: {:?}",
        String::from_utf8_lossy(&heard)
    );
    second.write_all(b"*\n").unwrap();
    for _ in 0..20 {
        if let Ok(n) = second.read(&mut buf) {
            heard.extend_from_slice(&buf[..n]);
        }
        if heard.ends_with(b"\n") {
            break;
        }
    }
    assert_eq!(heard, b"*\n", "{:?}", String::from_utf8_lossy(&heard));
    stop.store(true, Ordering::Relaxed);
    handle.join().unwrap();
}

/// Class 5: a closed pipe ends `twin run` quietly; class 6: a log without scans is an error.
#[test]
fn a_closed_pipe_ends_quietly_and_an_empty_log_is_refused() {
    use std::process::{Command, Stdio};
    let dir = scratch("pipe");
    let mut child = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args([
            "run",
            repo().join("scenarios/lab-tour.toml").to_str().unwrap(),
            "--out",
        ])
        .arg(dir.join("out"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && !stderr.contains("panicked"),
        "{stderr}"
    );

    let empty = dir.join("empty.clf");
    std::fs::write(&empty, "# nothing\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["map", empty.to_str().unwrap(), "--out"])
        .arg(dir.join("map"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("no scans"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Class 4, the end of `twin serve`: SIGTERM stops it cleanly, with its statistics printed.
#[test]
fn twin_serve_prints_its_statistics_when_terminated() {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args([
            "serve",
            repo().join("scenarios/lab-tour.toml").to_str().unwrap(),
        ])
        .args(["--base", "tcp:127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Wait until it serves (its addresses are printed), then terminate it.
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    while out.read_line(&mut line).unwrap() > 0 && !line.contains("tcp:") {}
    // The shell's own `kill`: no package beyond /bin/sh needed.
    let killed = Command::new("sh")
        .args(["-c", &format!("kill -TERM {}", child.id())])
        .status()
        .unwrap();
    assert!(killed.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut out, &mut rest).unwrap();
    let status = child.wait().unwrap();
    assert!(status.success(), "{status:?}: {rest}");
    assert!(rest.contains("base: 0 connection(s)"), "{rest}");
}

/// Class 4, the edge of `twin serve`: a robot whose laser no LMS variant matches is refused
/// before anything is served (the host would read its scans' field from their count), named
/// with what it has.
#[test]
fn twin_serve_refuses_a_laser_the_lms_telegrams_cannot_carry() {
    let dir = scratch("serve-laser");
    let robot = absolute("scenarios/robots/pioneer-3dx.toml")
        .replace("beams = 361", "beams = 100")
        .replace("fov_deg = 180.0", "fov_deg = 90.0");
    assert!(robot.contains("beams = 100") && robot.contains("fov_deg = 90.0"));
    std::fs::write(dir.join("robot.toml"), robot).unwrap();
    let scenario = absolute("scenarios/lab-tour.toml").replace(
        &format!(
            "\"{}/robots/pioneer-3dx.toml\"",
            repo().join("scenarios").display()
        ),
        &format!("\"{}\"", dir.join("robot.toml").display()),
    );
    // A valid laser would be served until terminated: the scenario must name the new robot.
    assert!(scenario.contains("robot.toml"), "{scenario}");
    let path = dir.join("s.toml");
    std::fs::write(&path, scenario).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["serve", path.to_str().unwrap(), "--base", "tcp:127.0.0.1:0"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("an LMS") && stderr.contains("100 beams over 90°"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Class 6: a `[[check]]` error names the line of the key that is wrong, not the table's.
#[test]
fn check_errors_point_at_their_key() {
    let dir = scratch("check-lines");
    let base = absolute("scenarios/lab-tour.toml");
    let lines_before = base.lines().count();
    for (table, key_line, field) in [
        (
            "[[check]]\nnote = \"x\"\nkind = \"colisions\"\nmax = 2\n",
            3,
            "kind",
        ),
        (
            "[[check]]\nkind = \"scans\"\nnote = \"x\"\nmax_m = 3\n",
            4,
            "max_m",
        ),
        ("[[check]]\nkind = \"scans\"\nmin = 5\nmax = 2\n", 3, "min"),
    ] {
        let path = dir.join("s.toml");
        std::fs::write(&path, format!("{base}\n{table}")).unwrap();
        let err = Scenario::load(&path).unwrap_err();
        assert_eq!(err.line, Some(lines_before + 1 + key_line), "{err}");
        assert!(
            err.field.as_deref().is_some_and(|f| f.ends_with(field)),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scan whose beams wind round more than a turn is refused naming the scan; a full turn of
/// 1° beams with the closing beam (361 of them) and a half-turn SICK scan are matched.
#[test]
fn twin_match_refuses_a_scan_that_winds_round() {
    let scan = |n: usize, increment: f64| {
        let ranges: Vec<String> = (0..n)
            .map(|i| format!("{}", 2.0 + 0.01 * (i % 9) as f64))
            .collect();
        format!(
            r#"{{"angle_min": -3.14, "angle_increment": {increment}, "range_max": 30, "ranges": [{}]}}"#,
            ranges.join(", ")
        )
    };
    let matcher = MatcherKind::LorentzLines.build();
    let line = |reference: &str| {
        let request = format!(
            r#"{{"ref": {reference}, "cur": {}, "guess": [0, 0, 0]}}"#,
            scan(361, 0.0087)
        );
        let reply = sim::commands::map::match_line(7, &request, matcher.as_ref());
        serde_json::from_str::<serde_json::Value>(&reply).unwrap()
    };
    let wound = line(&scan(200_000, 0.0087));
    let error = wound["error"].as_str().expect("an error");
    assert!(
        error.starts_with("line 7: ref: expected beams within a turn, found 200000 beams"),
        "{error}"
    );
    for fine in [scan(361, 1f64.to_radians()), scan(361, 0.5f64.to_radians())] {
        let reply = line(&fine);
        assert!(reply.get("error").is_none(), "{reply}");
        assert!(reply["x"].as_f64().is_some_and(f64::is_finite), "{reply}");
    }
}
