//! Issue 16: `twin view` in a real browser. Headless Chromium (the distribution's package,
//! software WebGL) opens the page of a run's folder; the page's self-check (`?selftest`) renders,
//! counts what the canvas drew, presses the thesis's keys (§4.5, App. D.2) and reports the
//! virtual robot's state back to the server, which prints it; the test reads it there.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twin-issue-16-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The browser: `chromium` (Debian) or `chromium-browser`, or `$CHROMIUM`.
fn chromium() -> String {
    if let Ok(path) = std::env::var("CHROMIUM") {
        return path;
    }
    for name in ["chromium", "chromium-browser", "google-chrome"] {
        if Command::new(name)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
        {
            return name.to_string();
        }
    }
    panic!(
        "no Chromium found: the browser test needs it (`apt-get install -y chromium`, as .ci/run does, or set CHROMIUM)"
    );
}

/// Kills the child when dropped.
struct Killed(Child);
impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Serves `dir`, opens `?selftest` in headless Chromium and returns the page's report.
fn selftest(dir: &Path, name: &str) -> serde_json::Value {
    let mut view = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["view", dir.to_str().unwrap(), "--port", "0"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = view.stdout.take().unwrap();
    let view = Killed(view);
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let first = rx
        .recv_timeout(Duration::from_secs(10))
        .expect("twin view prints its address");
    let url = first
        .split_whitespace()
        .find(|w| w.starts_with("http://127.0.0.1:"))
        .unwrap_or_else(|| panic!("an address on 127.0.0.1 in {first:?}"))
        .to_string();
    let profile = scratch(&format!("{name}-profile"));
    let browser = Killed(
        Command::new(chromium())
            .args([
                "--headless=new",
                "--no-sandbox",
                "--use-gl=swiftshader",
                "--enable-unsafe-swiftshader",
                "--window-size=800,600",
                "--no-first-run",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg(format!("{url}?selftest"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let deadline = std::time::Instant::now() + Duration::from_secs(240);
    let report = loop {
        let left = deadline.saturating_duration_since(std::time::Instant::now());
        match rx.recv_timeout(left) {
            Ok(line) => {
                if let Some(json) = line.strip_prefix("selftest ") {
                    break json.to_string();
                }
            }
            Err(_) => panic!("no self-test report from the page within 240 s"),
        }
    };
    drop(browser);
    drop(view);
    serde_json::from_str(&report).unwrap_or_else(|e| panic!("{e}: {report}"))
}

fn num(v: &serde_json::Value, path: &[&str]) -> f64 {
    let mut v = v;
    for p in path {
        v = &v[*p];
    }
    v.as_f64()
        .unwrap_or_else(|| panic!("{path:?} is a number: {v}"))
}

#[test]
fn the_page_draws_the_run_and_the_thesis_keys_move_its_camera() {
    let dir = scratch("scene");
    let scenario = sim::config::Scenario::load(repo().join("scenarios/scene-lab.toml")).unwrap();
    let record = sim::commands::run::run_scenario(
        &scenario,
        &sim::commands::run::RunOptions::default(),
        |_, _| {},
    )
    .unwrap();
    sim::output::write_all(&record, &scenario, &dir).unwrap();
    assert!(dir.join("world.json").is_file() && dir.join("model.ply").is_file());
    let r = selftest(&dir, "scene");
    // The canvas drew something other than the background, in many colours.
    assert!(num(&r, &["pixels", "drawn"]) > 1000.0, "{r}");
    assert!(num(&r, &["pixels", "colours"]) >= 8.0, "{r}");
    assert_eq!(r["model"], true, "the 3D model loaded: {r}");
    assert_eq!(r["messages"].as_array().map(Vec::len), Some(0), "{r}");
    assert!(num(&r, &["scans"]) > 100.0, "{r}");
    // The thesis's steps (App. D.2): 0.57125 units of 0.1 m, 2.34987°, 21.774°, 3.409°.
    let deg = std::f64::consts::PI / 180.0;
    let b = &r["before"];
    let up = &r["keys"]["ArrowUp"];
    let moved = (num(up, &["x"]) - num(b, &["x"])).hypot(num(up, &["y"]) - num(b, &["y"]));
    assert!(
        (moved - 0.057125).abs() < 1e-9,
        "ArrowUp moves 5.7125 cm: {r}"
    );
    let turned = num(&r["keys"]["ArrowLeft"], &["theta"]) - num(b, &["theta"]);
    assert!(
        (turned - 2.34987 * deg).abs() < 1e-9,
        "ArrowLeft turns 2.35°: {r}"
    );
    assert!(
        (num(&r["keys"]["a"], &["pan"]) - 21.774 * deg).abs() < 1e-9,
        "{r}"
    );
    assert!(
        (num(&r["keys"]["w"], &["tilt"]) - 3.409 * deg).abs() < 1e-9,
        "{r}"
    );
    assert!(
        (num(&r["keys"]["w40"], &["tilt"]) - 90.0 * deg).abs() < 1e-9,
        "tilt stops at 90°: {r}"
    );
    assert_eq!(r["keys"]["o"]["perspective"], false, "{r}");
    assert_eq!(r["keys"]["p"]["perspective"], true, "{r}");
    assert_eq!(r["keys"]["x"]["points"], true, "{r}");
    assert_eq!(r["keys"]["c"]["edges"], true, "{r}");
    assert_eq!(r["keys"]["f"]["fill"], false, "{r}");
    // The gamepad's left stick forward is the up arrow.
    let before_pad = &r["keys"]["f"];
    let pad = &r["keys"]["gamepadForward"];
    let moved = (num(pad, &["x"]) - num(before_pad, &["x"]))
        .hypot(num(pad, &["y"]) - num(before_pad, &["y"]));
    assert!(
        (moved - 0.057125).abs() < 1e-9,
        "the gamepad moves the robot: {r}"
    );
    // The save button's PNG.
    assert_eq!(r["png"]["type"], "data:image/png", "{r}");
    assert!(num(&r, &["png", "bytes"]) > 10_000.0, "{r}");
    assert!(
        num(&r, &["fps"]) > 0.0 && num(&r, &["firstFrameMs"]) > 0.0,
        "{r}"
    );
}

#[test]
fn a_folder_without_the_world_says_so_in_the_page_and_a_non_run_is_refused() {
    let dir = scratch("bare");
    std::fs::write(
        dir.join("summary.json"),
        r#"{"scenario": "bare", "seed": 1}"#,
    )
    .unwrap();
    std::fs::write(dir.join("truth.tum"), "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n").unwrap();
    let r = selftest(&dir, "bare");
    let messages = r["messages"].to_string();
    assert!(messages.contains("world.json is missing"), "{r}");
    assert!(messages.contains("scans.jsonl is missing"), "{r}");
    // Not a run's folder: a clear error, no server.
    let empty = scratch("empty");
    let o = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["view", empty.to_str().unwrap(), "--port", "0"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("not a run's output folder (no summary.json)"),
        "{err}"
    );
}
