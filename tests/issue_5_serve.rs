//! Issue 5, the twin's serial face: `twin serve` survives many connects and disconnects,
//! malformed lines and floods without growing its buffers; it offers a device on a
//! pseudo-terminal that the real backend opens like a serial port; and `twin drive` drives a
//! script through `twin serve` end to end, as the README shows.

use crate::common;

use robot::Clock;
use robot::hardware::{Batteries, DriveBase};
use robot::serial::{Endpoint, SerialConfig, SerialRobot};
use sim::Twin;
use sim::commands::serve::{Offer, ServeOptions, Served, Server, WallClock};
use sim::config::Scenario;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

fn twin() -> Twin {
    let s = Scenario::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenarios/lab-tour.toml"
    ))
    .unwrap();
    Twin::new(&s.world, &s.robot, &s.noise, s.seed).unwrap()
}

/// Runs `server` in a thread until the returned guard is dropped.
fn run(mut server: Server) -> (Arc<AtomicBool>, std::thread::JoinHandle<Server>) {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let handle = std::thread::spawn(move || {
        server.run(&flag, None, |_, _| {});
        server
    });
    (stop, handle)
}

/// Sends `*` and waits (wall time) for the `*` echo, skipping anything else.
fn ping(address: &str) -> bool {
    let Ok(mut s) = TcpStream::connect(address) else {
        return false;
    };
    s.set_read_timeout(Some(Duration::from_millis(100)))
        .unwrap();
    if s.write_all(b"*\n").is_err() {
        return false;
    }
    let mut seen = Vec::new();
    let mut buf = [0u8; 256];
    for _ in 0..30 {
        match s.read(&mut buf) {
            Ok(0) => return false,
            Ok(n) => seen.extend_from_slice(&buf[..n]),
            Err(_) => {}
        }
        if seen.windows(2).any(|w| w == b"*\n") {
            return true;
        }
    }
    eprintln!("ping saw {:?}", String::from_utf8_lossy(&seen));
    false
}

/// Reads what the server sends for a while before closing, so the close is orderly and the
/// server gets every byte written (closing with unread input would reset the connection).
fn linger(mut s: TcpStream) {
    let _ = s.shutdown(std::net::Shutdown::Write);
    s.set_read_timeout(Some(Duration::from_millis(50))).unwrap();
    let mut buf = [0u8; 4096];
    for _ in 0..40 {
        if let Ok(0) = s.read(&mut buf) {
            break;
        }
    }
}

#[test]
fn floods_garbage_and_many_reconnects_do_not_stop_the_server_or_grow_it() {
    let options = ServeOptions {
        speed: 10.0,
        base: Offer::Tcp("127.0.0.1:0".into()),
        pan_tilt: None,
        laser: Some(Offer::Tcp("127.0.0.1:0".into())),
        live: None,
    };
    let server = Server::new(twin(), &options).unwrap();
    let addresses = server.addresses();
    let base = addresses[0].1.strip_prefix("tcp:").unwrap().to_string();
    let laser = addresses[1].1.strip_prefix("tcp:").unwrap().to_string();
    let (stop, handle) = run(server);

    // Fifty clients that connect and vanish, some mid-line, some after a malformed line.
    for i in 0..50 {
        let mut s = TcpStream::connect(&base).unwrap();
        let junk: &[u8] = match i % 3 {
            0 => b"",
            1 => b"a12",
            _ => b"\xff\xfe garbage \x00\n#\n",
        };
        let _ = s.write_all(junk);
    }
    // A flood: a megabyte without a newline, then a megabyte of short malformed lines.
    {
        let mut s = TcpStream::connect(&base).unwrap();
        let _ = s.write_all(&vec![b'7'; 1 << 20]);
        let _ = s.write_all(&b"q9x\n\n\r\n".repeat(1 << 17));
        linger(s);
    }
    // The laser: a megabyte of noise with false telegram starts.
    {
        let mut s = TcpStream::connect(&laser).unwrap();
        let noise: Vec<u8> = (0..1u32 << 20)
            .map(|i| [0x02, 0x00, 0xff, 0x99][i as usize % 4])
            .collect();
        let _ = s.write_all(&noise);
        linger(s);
    }
    std::thread::sleep(Duration::from_millis(300));
    let answered = ping(&base);
    stop.store(true, Ordering::Relaxed);
    let server = handle.join().expect("the server did not panic");
    let stats = server.stats();
    assert!(
        answered,
        "the base still answers after the abuse: {stats:?}, lost lines {}",
        server.twin().board().lost_lines()
    );
    let (_, base_stats) = &stats[0];
    assert!(base_stats.connections >= 52, "{base_stats:?}");
    assert!(
        base_stats.bytes_dropped_in > 1 << 20,
        "the flood was dropped, not queued: {base_stats:?}"
    );
    assert!(
        server.twin().board().lost_lines() < 10_000,
        "the line only carries what 9600 bps can"
    );
    let (_, laser_stats) = &stats[1];
    assert_eq!(laser_stats.messages_in, 0, "noise is no telegram");
}

#[test]
fn a_device_on_a_pseudo_terminal_opens_like_a_serial_port() {
    let options = ServeOptions {
        speed: 10.0,
        base: Offer::Pty,
        pan_tilt: None,
        laser: None,
        live: None,
    };
    let server = Server::new(twin(), &options).unwrap();
    let (device, path) = server.addresses()[0].clone();
    assert_eq!(device, Served::Base);
    assert!(path.starts_with("/dev/"), "a device path: {path}");
    let (stop, handle) = run(server);
    let endpoint: Endpoint = path.parse().unwrap();
    assert!(matches!(endpoint, Endpoint::Serial(_)));
    let clock: Arc<dyn Clock> = Arc::new(WallClock::new(10.0));
    let mut robot = SerialRobot::open(SerialConfig::new(endpoint), clock).unwrap();
    let batteries = robot.battery_voltages().unwrap();
    assert!(batteries.motor_24_mv > 20_000, "{batteries:?}");
    let status = robot.drive_status().unwrap();
    assert!(status.is_idle());
    robot.advance(20).unwrap();
    stop.store(true, Ordering::Relaxed);
    let server = handle.join().unwrap();
    assert!(
        server.stats()[0].1.messages_in >= 4,
        "*, t, l and a went through"
    );
}

/// Reads `twin serve`'s address lines ("base      tcp:127.0.0.1:PORT").
fn addresses(child: &mut std::process::Child) -> Vec<(String, String)> {
    let stdout = child.stdout.take().unwrap();
    let mut lines = BufReader::new(stdout).lines();
    let mut out = Vec::new();
    for line in lines.by_ref() {
        let line = line.unwrap();
        let mut parts = line.split_whitespace();
        if let (Some(device), Some(address)) = (parts.next(), parts.next())
            && address.starts_with("tcp:")
        {
            out.push((device.to_string(), address.to_string()));
            if out.len() == 2 {
                break;
            }
        }
    }
    // Keep draining so the server never blocks on a full pipe.
    std::thread::spawn(move || for _ in lines {});
    out
}

#[test]
fn twin_drive_runs_a_script_through_twin_serve() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let dir = std::env::temp_dir().join(format!("twin-drive-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("short.toml");
    std::fs::write(
        &script,
        format!(
            r#"name = "short-drive"
world = "{root}/worlds/lab.toml"
robot = "{root}/scenarios/robots/pioneer-3dx.toml"
seed = 7
[script]
steps = ["move 0.5", "turn 25", "move 0.5"]
"#
        ),
    )
    .unwrap();
    let twin = env!("CARGO_BIN_EXE_twin");
    let mut serve = std::process::Command::new(twin)
        .args([
            "serve",
            script.to_str().unwrap(),
            "--base",
            "tcp:127.0.0.1:0",
        ])
        .args([
            "--laser",
            "tcp:127.0.0.1:0",
            "--speed",
            "10",
            "--duration",
            "600",
            "-q",
        ])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let offered = addresses(&mut serve);
    let find = |d: &str| offered.iter().find(|(x, _)| x == d).unwrap().1.clone();
    let out = dir.join("out");
    let drive = std::process::Command::new(twin)
        .args(["drive", script.to_str().unwrap(), "--base", &find("base")])
        .args([
            "--laser",
            &find("laser"),
            "--time-scale",
            "10",
            "--matcher",
            "lorentz",
        ])
        .args(["--out", out.to_str().unwrap(), "-q"])
        .output()
        .unwrap();
    let _ = serve.kill();
    let _ = serve.wait();
    assert!(
        drive.status.success(),
        "twin drive failed: {}",
        String::from_utf8_lossy(&drive.stderr)
    );
    for file in [
        "odometry.tum",
        "estimate.tum",
        "scans.jsonl",
        "map.svg",
        "summary.json",
    ] {
        assert!(out.join(file).is_file(), "{file} written");
    }
    let odometry = std::fs::read_to_string(out.join("odometry.tum")).unwrap();
    let poses: Vec<Vec<f64>> = odometry
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(poses.len(), 3, "one scan per motion");
    let moved = (poses[2][1] - poses[0][1]).hypot(poses[2][2] - poses[0][2]);
    assert!(
        (0.4..0.6).contains(&moved),
        "the last move took the base 0.5 m: {moved}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["scans"], 3);
    assert_eq!(summary["matcher"], "lorentz");
}

#[test]
fn the_pan_tilt_homes_and_moves_through_the_serial_face_as_on_the_twin() {
    let scenario = Scenario::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenarios/tilted-scan.toml"
    ))
    .unwrap();
    let direct =
        sim::commands::run::run_scenario(&scenario, &Default::default(), |_, _| {}).unwrap();
    let (drive, events) = common::drive_served(&scenario, 20.0);
    let drive = drive.unwrap_or_else(|e| panic!("{e}; events: {events:#?}"));
    assert!(
        events.iter().any(|e| e.what.contains("homing")),
        "the backend waited for the power-up homing: {events:#?}"
    );
    let (serial, direct_head) = (drive.pan_tilt.unwrap(), direct.pan_tilt.unwrap());
    assert_eq!(
        (serial.pan, serial.tilt),
        (direct_head.pan, direct_head.tilt),
        "the head reached the same position"
    );
    assert_eq!((serial.pan, serial.tilt), (0, 10));
    assert_eq!(drive.scans.len(), direct.scans.len());
    // scans.jsonl places the laser where the head was put, as `twin run` does from the truth.
    let dir = std::env::temp_dir().join(format!("twin-drive-head-{}", std::process::id()));
    sim::commands::drive::write_drive(&drive, &scenario, &events, &dir).unwrap();
    // Its recording reads back in the Python MCAP reader (issue 19), the head's transforms and
    // the link's events with it.
    let report = crate::issue_19_recording::python_reads(&dir);
    assert_eq!(
        report["rosout"].as_u64(),
        Some(events.len() as u64),
        "{report}"
    );
    assert_eq!(
        report["head_transforms_checked"].as_u64(),
        Some(drive.scans.len() as u64),
        "{report}"
    );
    let text = std::fs::read_to_string(dir.join("scans.jsonl")).unwrap();
    let first: sim::output::ScanLine = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    let expected = sim::output::ScanLine::of(&direct.scans[0], &scenario.robot.mount());
    let (tilt, z) = (first.laser_tilt.unwrap(), first.laser_z.unwrap());
    assert!(
        (tilt - expected.laser_tilt.unwrap()).abs() < 0.01,
        "{first:?}"
    );
    assert!((z - expected.laser_z.unwrap()).abs() < 0.005);
    assert!(
        (tilt.to_degrees() + 13.65).abs() < 0.5,
        "tilted 13.65° down"
    );
    // Every scan of the drive knows where the head was, from the pan-tilt's reports.
    assert!(drive.scans.iter().all(|(s, _, _)| s.head.is_some()));
}
