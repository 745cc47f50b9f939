//! Issue 5, the swap: the same scripted tour run directly on `SimRobot` and through
//! `SerialRobot` → TCP → the twin's serial face (`sim::commands::serve`), and the real backend surviving a
//! dropped connection and a burst of garbage mid-tour.
//!
//! The served twin runs 10× faster than real time, so these tests take a few wall seconds each.
//! Their tolerance comes from the protocol's quantisation (see `ODOMETRY_TOLERANCE_M`).

use robot::control::{TourEvent, run_tour};
use robot::serial::{Endpoint, SerialConfig, SerialRobot};
use robot::{Clock, Pose2};
use sim::commands::serve::{Offer, ServeOptions, Served, Server, WallClock};
use sim::config::Scenario;
use sim::{SimRobot, Twin};
use std::io::{Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

/// How much faster than real time the served twin runs.
const SPEED: f64 = 10.0;

/// Stop-and-go odometry reads the counters at rest, so timing drops out of it except through
/// the motion itself: a command reaches the firmware at another point of its 1.024 ms tick and of
/// the twin's 8.192 ms step, which can change the ramp's last tick and the coast after the brake
/// by a count or so per wheel. The `l` reply carries hundredths of a turn (one count): per motion
/// a count on each wheel moves the pose by at most a count's travel (0.33 mm on the Pioneer
/// wheel), and a count of difference turns it by 0.33 mm / 0.33 m track = 1 mrad, which over the
/// next 0.5 m moves the pose 0.5 mm. Over the 9 motions here that bounds the difference by
/// about 9 × (0.33 + 0.5 × 4.5) ≈ 2.3 cm and 9 mrad; the test asks for 2.5 cm and 0.6°.
/// Measured: no difference at all, here and over the whole default tour (README).
const ODOMETRY_TOLERANCE_M: f64 = 0.025;
const ODOMETRY_TOLERANCE_DEG: f64 = 0.6;

fn scenario() -> Scenario {
    let mut s = Scenario::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenarios/lab-tour.toml"
    ))
    .expect("the default scenario loads");
    s.steps.truncate(10); // the ramp and 9 motions: moves, a ±25° pair
    s
}

struct Run {
    odometry: Pose2,
    scans: usize,
}

fn direct(scenario: &Scenario) -> Run {
    let mut robot = SimRobot::from_scenario(scenario).unwrap();
    let report = run_tour(
        &mut robot,
        scenario.robot.geometry(),
        scenario.world.start,
        &scenario.steps,
        &scenario.tour,
        |_: TourEvent<'_>| {},
    )
    .unwrap();
    Run {
        odometry: report.final_odometry,
        scans: report.scans,
    }
}

/// A served twin on free local ports, running in its own thread until dropped.
struct ServedTwin {
    base: String,
    laser: String,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Vec<String>>>,
}

impl Drop for ServedTwin {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn serve(scenario: &Scenario) -> ServedTwin {
    let twin = Twin::new(
        &scenario.world,
        &scenario.robot,
        &scenario.noise,
        scenario.seed,
    )
    .unwrap();
    let options = ServeOptions {
        speed: SPEED,
        base: Offer::Tcp("127.0.0.1:0".into()),
        pan_tilt: None,
        laser: Some(Offer::Tcp("127.0.0.1:0".into())),
        live: None,
    };
    let mut server = Server::new(twin, &options).unwrap();
    let addresses = server.addresses();
    let find = |d: Served| {
        addresses
            .iter()
            .find(|(x, _)| *x == d)
            .map(|(_, a)| a.clone())
            .unwrap()
    };
    let stop = Arc::new(AtomicBool::new(false));
    let thread = {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            let mut log = Vec::new();
            server.run(&stop, None, |_, line| log.push(line.to_string()));
            log
        })
    };
    ServedTwin {
        base: find(Served::Base),
        laser: find(Served::Laser),
        stop,
        thread: Some(thread),
    }
}

fn serial_config(base: &str, laser: &str, scenario: &Scenario) -> SerialConfig {
    let mut config = SerialConfig::new(base.parse::<Endpoint>().unwrap());
    config.laser = Some(laser.parse().unwrap());
    config.base_baud = scenario.robot.drive.serial_baud;
    config.laser_baud = scenario.robot.laser.baud;
    config
}

fn through_serial(robot: &mut SerialRobot, scenario: &Scenario) -> Run {
    let report = run_tour(
        robot,
        scenario.robot.geometry(),
        scenario.world.start,
        &scenario.steps,
        &scenario.tour,
        |_: TourEvent<'_>| {},
    )
    .unwrap_or_else(|e| panic!("tour through the serial backend failed: {e}"));
    Run {
        odometry: report.final_odometry,
        scans: report.scans,
    }
}

fn assert_same(direct: &Run, serial: &Run) {
    let d = direct.odometry.distance(&serial.odometry);
    let a = robot::geometry::wrap_angle(direct.odometry.theta - serial.odometry.theta)
        .to_degrees()
        .abs();
    eprintln!(
        "direct {:?}, serial {:?}: {d:.4} m, {a:.3} deg apart",
        direct.odometry, serial.odometry
    );
    assert!(
        d < ODOMETRY_TOLERANCE_M && a < ODOMETRY_TOLERANCE_DEG,
        "odometry differs by {d:.4} m / {a:.3}° (direct {:?}, serial {:?})",
        direct.odometry,
        serial.odometry
    );
    assert_eq!(direct.scans, serial.scans, "same number of scans");
}

#[test]
fn the_same_tour_through_serial_tcp_and_twin_serve_ends_at_the_same_odometry() {
    let scenario = scenario();
    let direct = direct(&scenario);
    let served = serve(&scenario);
    let clock: Arc<dyn Clock> = Arc::new(WallClock::new(SPEED));
    let mut robot =
        SerialRobot::open(serial_config(&served.base, &served.laser, &scenario), clock).unwrap();
    let serial = through_serial(&mut robot, &scenario);
    assert_same(&direct, &serial);
    assert!(direct.scans >= 9, "one scan per motion");
}

/// A TCP proxy between the backend and the served base that, once the device has sent
/// `garbage_after` bytes, slips a burst of garbage into the stream towards the backend, and once
/// it has sent `drop_after` bytes, closes the backend's connection. Later connections pass
/// through untouched.
struct FaultyProxy {
    address: String,
    injected: Arc<AtomicUsize>,
}

fn faulty_proxy(upstream: String, garbage_after: usize, drop_after: usize) -> FaultyProxy {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = format!("tcp:{}", listener.local_addr().unwrap());
    let injected = Arc::new(AtomicUsize::new(0));
    let faults = Arc::clone(&injected);
    std::thread::spawn(move || {
        let upstream = upstream.strip_prefix("tcp:").unwrap().to_string();
        for (n, client) in listener.incoming().enumerate() {
            let Ok(client) = client else { return };
            let Ok(device) = TcpStream::connect(&upstream) else {
                return;
            };
            let first = n == 0;
            let faults = Arc::clone(&faults);
            // Host → device: as is.
            let (mut from_client, mut to_device) =
                (client.try_clone().unwrap(), device.try_clone().unwrap());
            std::thread::spawn(move || {
                let _ = std::io::copy(&mut from_client, &mut to_device);
                let _ = to_device.shutdown(Shutdown::Both);
            });
            // Device → host: with the faults, on the first connection.
            let (mut from_device, mut to_client) = (device, client);
            let sent = Mutex::new(0usize);
            std::thread::spawn(move || {
                let mut buf = [0u8; 256];
                loop {
                    let n = match from_device.read(&mut buf) {
                        Ok(0) | Err(_) => break,
                        Ok(n) => n,
                    };
                    if to_client.write_all(&buf[..n]).is_err() {
                        break;
                    }
                    let mut total = sent.lock().unwrap();
                    let before = *total;
                    *total += n;
                    if first && before < garbage_after && *total >= garbage_after {
                        // Noise on the line: a partial line, bytes that are not text, a
                        // line that is no reply, and a run far longer than any line.
                        let mut noise = b"l3.1\x00\xff\x13 7\n#?%\nnoise\n".to_vec();
                        noise.extend(std::iter::repeat_n(b'x', 700));
                        noise.push(b'\n');
                        let _ = to_client.write_all(&noise);
                        faults.fetch_add(1, Ordering::Relaxed);
                    }
                    if first && before < drop_after && *total >= drop_after {
                        faults.fetch_add(1, Ordering::Relaxed);
                        let _ = to_client.shutdown(Shutdown::Both);
                        let _ = from_device.shutdown(Shutdown::Both);
                        break;
                    }
                }
            });
        }
    });
    FaultyProxy { address, injected }
}

#[test]
fn the_backend_survives_a_dropped_connection_and_garbage_mid_tour() {
    let scenario = scenario();
    let direct = direct(&scenario);
    let served = serve(&scenario);
    // The tour's replies total ~450 bytes, fewer when a loaded machine polls less: garbage
    // after ~100, the drop after ~250, so both come well before the tour's last reply.
    let proxy = faulty_proxy(served.base.clone(), 100, 250);
    let clock: Arc<dyn Clock> = Arc::new(WallClock::new(SPEED));
    let mut robot = SerialRobot::open(
        serial_config(&proxy.address, &served.laser, &scenario),
        clock,
    )
    .unwrap();
    let serial = through_serial(&mut robot, &scenario);
    assert_eq!(
        proxy.injected.load(Ordering::Relaxed),
        2,
        "both faults happened"
    );
    let events = robot.take_events();
    let report: Vec<String> = events.iter().map(ToString::to_string).collect();
    eprintln!("{}", report.join("\n"));
    assert!(
        report.iter().any(|e| e.contains("base: link dropped")),
        "the drop is reported: {report:#?}"
    );
    assert!(
        report
            .iter()
            .filter(|e| e.contains("base: connected"))
            .count()
            >= 2,
        "the backend reconnected: {report:#?}"
    );
    assert!(
        report
            .iter()
            .any(|e| e.contains("skipped") || e.contains("discarded")),
        "the garbage is reported: {report:#?}"
    );
    assert_same(&direct, &serial);
}
