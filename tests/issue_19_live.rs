//! Issue 19, live view: `twin run --live` publishes the run's topics over the Foxglove WebSocket
//! protocol, paced to the wall clock. A WebSocket client (tungstenite's, speaking the protocol
//! from its specification) connects, reads `serverInfo` and the advertised channels, subscribes
//! to `/scan` and the latched `/tf_static`, and decodes every message it gets: one `/scan` per
//! scan of the run, stamped as the run stamped it, with the same ranges.

use crate::common::scenario;
use robot::logs::ros2::CdrReader;
use sim::commands::live::{LiveServer, SUBPROTOCOL};
use sim::commands::run::{Live, RunOptions, run_scenario};
use std::collections::HashMap;
use std::net::TcpStream;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tungstenite::Message;
use tungstenite::client::IntoClientRequest;
use tungstenite::stream::MaybeTlsStream;

type Client = tungstenite::WebSocket<MaybeTlsStream<TcpStream>>;

fn connect(addr: std::net::SocketAddr) -> Client {
    let mut request = format!("ws://{addr}").into_client_request().unwrap();
    request
        .headers_mut()
        .insert("Sec-WebSocket-Protocol", SUBPROTOCOL.parse().unwrap());
    let (ws, response) = tungstenite::connect(request).unwrap();
    assert_eq!(response.headers()["Sec-WebSocket-Protocol"], SUBPROTOCOL);
    if let MaybeTlsStream::Plain(s) = ws.get_ref() {
        s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    }
    ws
}

fn json(message: Message) -> serde_json::Value {
    serde_json::from_str(message.to_text().expect("a text message")).unwrap()
}

#[test]
fn a_client_subscribes_to_the_scans_and_decodes_every_one() {
    let scenario = scenario("lab-tour");
    let speed = 400.0;
    let live = Live::new(Arc::new(LiveServer::start("127.0.0.1:0").unwrap()), speed);
    live.announce(&scenario);
    let mut ws = connect(live.server.addr());
    let info = json(ws.read().unwrap());
    assert_eq!(info["op"], "serverInfo");
    let advertise = json(ws.read().unwrap());
    assert_eq!(advertise["op"], "advertise");
    let channels: HashMap<String, &serde_json::Value> = advertise["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c["topic"].as_str().unwrap().to_string(), c))
        .collect();
    for topic in [
        "/scan",
        "/odom",
        "/tf",
        "/tf_static",
        "/clock",
        "/estimate",
        "/ground_truth",
    ] {
        let c = channels
            .get(topic)
            .unwrap_or_else(|| panic!("{topic}: {advertise}"));
        assert_eq!(c["encoding"], "cdr");
        assert_eq!(c["schemaEncoding"], "ros2msg");
    }
    assert_eq!(channels["/scan"]["schemaName"], "sensor_msgs/msg/LaserScan");
    ws.send(Message::text(
        serde_json::json!({"op": "subscribe", "subscriptions": [
            {"id": 10, "channelId": channels["/scan"]["id"]},
            {"id": 11, "channelId": channels["/tf_static"]["id"]},
            {"id": 12, "channelId": channels["/ground_truth"]["id"]},
        ]})
        .to_string(),
    ))
    .unwrap();
    while live.server.subscriptions() < 3 {
        std::thread::sleep(Duration::from_millis(2));
    }

    let options = RunOptions {
        live: Some(live.clone()),
        ..RunOptions::default()
    };
    let started = Instant::now();
    let run = std::thread::spawn(move || run_scenario(&scenario, &options, |_, _| {}).unwrap());
    // Short reads: the last message may come before the run has finished, and then no other
    // message comes to wake the reader; a quiet socket is the time to look at the run again.
    if let MaybeTlsStream::Plain(s) = ws.get_ref() {
        s.set_read_timeout(Some(Duration::from_millis(100)))
            .unwrap();
    }
    let quiet = |e: &tungstenite::Error| {
        matches!(e, tungstenite::Error::Io(io)
            if matches!(io.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut))
    };
    let mut scans = Vec::new();
    let mut truths = Vec::new();
    let mut statics = 0;
    let record = loop {
        match ws.read() {
            Ok(Message::Binary(frame)) => {
                assert_eq!(frame[0], 1, "message data");
                let id = u32::from_le_bytes(frame[1..5].try_into().unwrap());
                let at = u64::from_le_bytes(frame[5..13].try_into().unwrap());
                match id {
                    10 => {
                        let scan = CdrReader::new(&frame[13..]).unwrap().laser_scan().unwrap();
                        assert_eq!(scan.header.stamp.0, at);
                        scans.push(scan);
                    }
                    11 => {
                        let tf = CdrReader::new(&frame[13..]).unwrap().tf().unwrap();
                        assert!(tf.0.iter().any(|t| t.child_frame_id == "laser"));
                        statics += 1;
                    }
                    12 => {
                        let pose = CdrReader::new(&frame[13..])
                            .unwrap()
                            .pose_stamped()
                            .unwrap();
                        assert_eq!(pose.header.stamp.0, at);
                        truths.push(pose);
                    }
                    other => panic!("subscription {other} was never made"),
                }
            }
            Ok(_) => {}
            Err(e) if quiet(&e) && started.elapsed() < Duration::from_secs(120) => {}
            Err(e) => panic!(
                "the connection failed before the run ended ({} scans read, the run {}): {e}",
                scans.len(),
                if run.is_finished() {
                    "finished"
                } else {
                    "still going"
                }
            ),
        }
        if run.is_finished() && scans.len() >= 46 {
            break run.join().unwrap();
        }
    };
    let wall = started.elapsed().as_secs_f64();
    if let MaybeTlsStream::Plain(s) = ws.get_ref() {
        s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    }
    // The rest of the queue, then the server closes.
    let server = Arc::try_unwrap(live.server).expect("the run let go of the server");
    let closing = std::thread::spawn(move || server.stop());
    while let Ok(message) = ws.read() {
        if let Message::Binary(frame) = message {
            let reader = CdrReader::new(&frame[13..]).unwrap();
            match u32::from_le_bytes(frame[1..5].try_into().unwrap()) {
                10 => scans.push(reader.laser_scan().unwrap()),
                12 => truths.push(reader.pose_stamped().unwrap()),
                _ => {}
            }
        }
    }
    closing.join().unwrap();

    assert!(
        statics >= 1,
        "the latched /tf_static reached a late subscriber"
    );
    assert_eq!(
        scans.len(),
        record.scans.len(),
        "one /scan per scan of the run"
    );
    for (got, want) in scans.iter().zip(&record.scans) {
        assert_eq!(got.header.stamp, want.scan.stamp);
        assert_eq!(got.ranges.len(), want.scan.ranges_mm.len());
        for (r, &mm) in got.ranges.iter().zip(&want.scan.ranges_mm) {
            if mm >= want.scan.range_max_mm {
                assert!(r.is_infinite());
            } else {
                assert_eq!(*r, (f64::from(mm) * 1e-3) as f32);
            }
        }
    }
    // The twin's truth at every scan, as the run recorded it (issue 19: it was left out).
    assert_eq!(
        truths.len(),
        record.scans.len(),
        "one /ground_truth per scan"
    );
    for (got, want) in truths.iter().zip(&record.scans) {
        assert_eq!(got.header.stamp, want.scan.stamp);
        assert_eq!(got.header.frame_id, "map");
        let (x, y) = (got.pose.translation[0], got.pose.translation[1]);
        assert!(
            (x - want.truth.x).abs() < 1e-9 && (y - want.truth.y).abs() < 1e-9,
            "truth ({x}, {y}) against {:?}",
            want.truth
        );
    }
    // Paced: the run waited for the wall clock to reach each scan's stamp / speed.
    let last = record.scans.last().unwrap().scan.stamp.secs_f64();
    assert!(
        wall >= last / speed,
        "{wall} s for a last scan at {last} s at {speed}x"
    );
}

/// `twin serve --live`: the served twin publishes what its laser measures and where the robot
/// truly is, whether or not a client reads the laser's serial face.
#[test]
fn the_served_twin_publishes_its_scans_and_its_truth() {
    use sim::commands::serve::{Offer, ServeOptions, ServedLive, Server};
    let scenario = scenario("lab-tour");
    let server = Arc::new(LiveServer::start("127.0.0.1:0").unwrap());
    let options = ServeOptions {
        speed: 10.0,
        base: Offer::Tcp("127.0.0.1:0".into()),
        pan_tilt: None,
        laser: None,
        live: Some(ServedLive {
            server: server.clone(),
            mount: scenario.robot.mount(),
            scan_period_s: 0.19,
        }),
    };
    let twin = sim::Twin::new(&scenario.world, &scenario.robot, &scenario.noise, 5).unwrap();
    let mut served = Server::new(twin, &options).unwrap();
    let mut ws = connect(server.addr());
    assert_eq!(json(ws.read().unwrap())["op"], "serverInfo");
    let advertise = json(ws.read().unwrap());
    let id = |topic: &str| {
        advertise["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["topic"] == topic)
            .unwrap_or_else(|| panic!("{topic}: {advertise}"))["id"]
            .clone()
    };
    ws.send(Message::text(
        serde_json::json!({"op": "subscribe", "subscriptions": [
            {"id": 1, "channelId": id("/scan")},
            {"id": 2, "channelId": id("/ground_truth")},
        ]})
        .to_string(),
    ))
    .unwrap();
    while server.subscriptions() < 2 {
        std::thread::sleep(Duration::from_millis(2));
    }
    let stop = std::sync::atomic::AtomicBool::new(false);
    served.run(&stop, Some(Duration::from_secs(3)), |_, _| {});
    drop(served);
    drop(options);
    Arc::try_unwrap(server).expect("one owner left").stop();
    let (mut scans, mut truths) = (Vec::new(), Vec::new());
    while let Ok(message) = ws.read() {
        if let Message::Binary(frame) = message {
            let reader = CdrReader::new(&frame[13..]).unwrap();
            match u32::from_le_bytes(frame[1..5].try_into().unwrap()) {
                1 => scans.push(reader.laser_scan().unwrap()),
                2 => truths.push(reader.pose_stamped().unwrap()),
                other => panic!("subscription {other}"),
            }
        }
    }
    // 3 s at one scan per 0.19 s (38,400 bps): 14 to 16 scans, each with its truth.
    assert!((12..=17).contains(&scans.len()), "{} scans", scans.len());
    assert_eq!(truths.len(), scans.len());
    // The robot stands where the world starts it (nothing drives it).
    let start = scenario.world.start;
    for t in &truths {
        let p = t.pose.to_planar();
        assert!(p.distance(&start) < 0.01, "{p:?} against {start:?}");
        assert_eq!(t.header.frame_id, "map");
    }
    assert!(scans.iter().all(|s| s.ranges.len() == 361));
    assert!(
        scans
            .windows(2)
            .all(|w| w[0].header.stamp < w[1].header.stamp)
    );
}
