//! Issue 13: 3D reconstruction, end to end. Scenes from the pan-tilt laser become points, meshes
//! and merged models placed by the 2D localisation of level scans; the twin scores them against
//! its true surfaces. These tests check what must hold whatever the seed: the 2D matcher never
//! sees a tilted scan; noise-free points placed by the truth lie on the true surfaces; glass
//! leaves ghosts and black leaves holes in 3D as in 2D; the model rebuilt from a run's folder is
//! the model of the run; an independent reader (Python's `plyfile`) opens the PLY; the same seed
//! gives the same bytes; and the real backend's path (`twin serve` + `SerialRobot`) gives the
//! same scene.

use crate::common;

use robot::control::Step;
use sim::commands::reconstruct::{read_run_folder, reconstruct};
use sim::commands::run::{RunOptions, run_scenario};
use sim::config::{Outliers, Scenario};
use sim::record::{Placement, RunRecord};
use sim::world::WorldMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// survey-lab, run once for the tests that read it.
fn survey() -> &'static (Scenario, RunRecord) {
    static RUN: OnceLock<(Scenario, RunRecord)> = OnceLock::new();
    RUN.get_or_init(|| {
        let scenario = common::scenario("survey-lab");
        let record = run_scenario(&scenario, &RunOptions::default(), |_, _| {}).unwrap();
        (scenario, record)
    })
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("twin-issue-13-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn tilted_scans_never_reach_the_2d_localisation() {
    let (scenario, record) = survey();
    let mount = scenario.robot.mount();
    let loc = record.localisation.as_ref().unwrap();
    // Every scan knows where the head was; the scenes' scans are tilted through the range.
    assert!(record.scans.iter().all(|r| r.scan.head.is_some()));
    let level_tour_scans = record
        .scans
        .iter()
        .filter(|r| r.scene.is_none())
        .filter(|r| {
            let laser = mount.laser_on_base(r.scan.head).unwrap();
            laser.is_level(robot::localization::LEVEL_TOLERANCE_RAD)
        })
        .count();
    assert_eq!(
        level_tour_scans, 10,
        "2 station scans and 8 after the moves"
    );
    assert_eq!(
        loc.placed.len(),
        level_tour_scans,
        "only those were matched"
    );
    for p in &loc.placed {
        let r = record
            .scans
            .iter()
            .find(|r| r.scan.stamp == p.stamp)
            .unwrap();
        assert!(r.scene.is_none(), "a scene's scan was matched in 2D");
    }
    // Scenes at four pans 90° apart, each over 65° of tilt.
    let recon = record.reconstruction.as_ref().unwrap();
    let pans: Vec<f64> = recon
        .main()
        .model
        .scenes
        .iter()
        .map(|s| s.pan.to_degrees())
        .collect();
    assert_eq!(pans.len(), 8);
    for (k, pan) in pans.iter().enumerate() {
        let expected = [0.0, 90.7, 180.0, 270.7][k % 4];
        assert!((pan - expected).abs() < 1.0, "scene {k} at pan {pan}°");
    }
}

#[test]
fn noise_free_points_placed_by_the_truth_lie_on_the_true_surfaces() {
    // The lab with every surface matte (no mirror images), a noise-free laser: what is left is
    // the LMS's millimetre rounding.
    let mut scenario = common::scenario("scene-lab");
    let text = std::fs::read_to_string(common::repo().join("worlds/lab.toml")).unwrap();
    let matte = ["glass", "black", "metal"]
        .iter()
        .fold(text, |t, m| t.replace(&format!("\"{m}\""), "\"matte\""));
    let start = scenario.world.start;
    scenario.world = common::world_from(&matte);
    scenario.world.start = start;
    scenario.noise.laser_sigma_m = 0.0;
    scenario.noise.outliers = Outliers::NONE;
    let record = run_scenario(&scenario, &RunOptions::default(), |_, _| {}).unwrap();
    let recon = record.reconstruction.unwrap();
    let truth = recon.placed(Placement::Truth).unwrap();
    let a = truth.accuracy.as_ref().unwrap();
    assert_eq!(a.within_2cm, 1.0, "{a:?}");
    assert_eq!(
        a.phantom_area_m2, 0.0,
        "no depth jump under 20 cm in the lab: {a:?}"
    );
    // The chain of Eq. 4.1 in the robot crate and the twin's ray casts agree: every vertex is
    // within the rounding of the millimetre readings of its surface.
    let map = WorldMap::new(&scenario.world);
    let worst = truth
        .model
        .vertices
        .iter()
        .map(|v| map.distance_3d(v.map(f64::from)))
        .fold(0.0, f64::max);
    assert!(worst < 0.0006, "a vertex {worst} m off its surface");
}

#[test]
fn glass_leaves_ghosts_and_black_leaves_holes_in_3d() {
    let (scenario, record) = survey();
    let recon = record.reconstruction.as_ref().unwrap();
    let main = recon.main();
    let a = main.accuracy.as_ref().unwrap();
    let share = |name: &str| {
        a.coverage_by_material
            .iter()
            .find(|(m, _, _)| m == name)
            .unwrap_or_else(|| panic!("no {name} in {:?}", a.coverage_by_material))
            .1
    };
    assert!(
        share("black") < 0.8 * share("matte"),
        "black desks lose the beams met obliquely: {:?}",
        a.coverage_by_material
    );
    assert!(
        share("glass") < 0.1,
        "glass is seen through or mirrors: {:?}",
        a.coverage_by_material
    );
    // Behind the closed glass door (y = 6.5, x 3.05–4.55): vertices far from every surface,
    // the mirror images of the room.
    let map = WorldMap::new(&scenario.world);
    let ghosts = main
        .model
        .vertices
        .iter()
        .filter(|v| v[1] > 6.6 && map.distance_3d(v.map(f64::from)) > 0.15)
        .count();
    assert!(ghosts > 200, "{ghosts} ghost vertices behind the glass");
    // They are ghosts, not a badly placed station: the truth-placed model has them too.
    let truth = recon.placed(Placement::Truth).unwrap();
    assert!(truth.accuracy.as_ref().unwrap().ghost_area_m2 > 1.0);
}

#[test]
fn the_model_rebuilt_from_the_run_folder_is_the_model_of_the_run() {
    let (scenario, record) = survey();
    let dir = temp_dir("rebuild");
    sim::output::write_all(record, scenario, &dir).unwrap();
    let folder = read_run_folder(&dir).unwrap();
    let map = WorldMap::new(&scenario.world);
    let rebuilt = reconstruct(
        &folder.inputs,
        folder.placed.as_deref(),
        &scenario.reconstruction.mesh,
        Some(&map),
        false,
    )
    .unwrap()
    .unwrap();
    let original = record.reconstruction.as_ref().unwrap();
    for placement in [Placement::Estimate, Placement::Odometry, Placement::Truth] {
        let (a, b) = (
            original.placed(placement).unwrap(),
            rebuilt.placed(placement).unwrap(),
        );
        // Poses come back from TUM files (1 µm, 1e-9 in the quaternion): the same points, and
        // the same polygons but for the odd one whose edge is within a micrometre of 200 mm.
        assert_eq!(a.model.vertices.len(), b.model.vertices.len());
        let ((qa, of), (ta, _)) = a.model.counts();
        let ((qb, of_b), (tb, _)) = b.model.counts();
        assert_eq!(of, of_b);
        assert!(
            qa.abs_diff(qb) <= 5 && ta.abs_diff(tb) <= 10,
            "{placement:?}: {qa}/{ta} vs {qb}/{tb}"
        );
        let (sa, sb) = (a.accuracy.as_ref().unwrap(), b.accuracy.as_ref().unwrap());
        assert!((sa.median_m - sb.median_m).abs() < 1e-4, "{placement:?}");
        assert!((sa.coverage - sb.coverage).abs() < 1e-3, "{placement:?}");
    }
    // And through the command line, with the figures in reconstruction.json.
    let out = dir.join("again");
    let status = Command::new(env!("CARGO_BIN_EXE_twin"))
        .args(["reconstruct", dir.to_str().unwrap(), "--quiet", "--world"])
        .arg(common::repo().join("worlds/lab.toml"))
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    let (first, again) = (
        read(&dir.join("reconstruction.json")),
        read(&out.join("reconstruction.json")),
    );
    let triangles = |v: &serde_json::Value| v["totals"]["triangles"][0].as_u64().unwrap();
    assert!(triangles(&first).abs_diff(triangles(&again)) <= 10);
    assert_eq!(
        first["totals"]["triangles"][1],
        again["totals"]["triangles"][1]
    );
    assert_eq!(first["scenes"].as_array().unwrap().len(), 8);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_independent_reader_opens_the_ply() {
    let (scenario, record) = survey();
    let dir = temp_dir("ply");
    sim::output::write_all(record, scenario, &dir).unwrap();
    let model = &record.reconstruction.as_ref().unwrap().main().model;
    let script = r#"
import sys
from plyfile import PlyData
d = PlyData.read(sys.argv[1])
v, f = d['vertex'], d['face']
n = (v['nx']**2 + v['ny']**2 + v['nz']**2) ** 0.5
print(len(v), len(f), int(max(max(t) for t in f['vertex_indices'])),
      float(v['x'][0]), float(v['y'][0]), float(v['z'][0]),
      float(abs(n - 1).max()), int(v['scene'].max()))
"#;
    let output = Command::new("python3")
        .args(["-c", script])
        .arg(dir.join("model.ply"))
        .output()
        .expect("python3 runs (.ci/run installs it with plyfile)");
    assert!(
        output.status.success(),
        "plyfile could not read model.ply (pip install plyfile): {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let text = String::from_utf8(output.stdout).unwrap();
    let fields: Vec<f64> = text
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    assert_eq!(fields[0] as usize, model.vertices.len());
    assert_eq!(fields[1] as usize, model.triangles.len());
    assert!((fields[2] as usize) < model.vertices.len());
    for k in 0..3 {
        assert_eq!(fields[3 + k] as f32, model.vertices[0][k]);
    }
    assert!(fields[6] < 1e-5, "normals are unit vectors");
    assert_eq!(fields[7] as usize, model.scenes.len() - 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_same_seed_gives_the_same_model_bytes() {
    let scenario = common::scenario("scene-lab");
    let bytes = |seed: u64| {
        let options = RunOptions {
            seed: Some(seed),
            ..RunOptions::default()
        };
        let record = run_scenario(&scenario, &options, |_, _| {}).unwrap();
        let dir = temp_dir(&format!("bytes-{seed}-{:?}", std::thread::current().id()));
        sim::output::write_all(&record, &scenario, &dir).unwrap();
        let read = |name: &str| std::fs::read(dir.join(name)).unwrap();
        let files = (
            read("model.ply"),
            read("reconstruction.json"),
            read("model.png"),
        );
        let _ = std::fs::remove_dir_all(&dir);
        files
    };
    let (a, b, c) = (bytes(5), bytes(5), bytes(6));
    assert!(
        a == b,
        "same seed, same model.ply, reconstruction.json and model.png"
    );
    assert!(a.0 != c.0, "another seed draws other noise");
}

#[test]
fn the_real_backends_path_gives_the_same_scene() {
    // A short scene (21 tilts) to keep the served run at a few seconds of wall time.
    let mut scenario = common::scenario("scene-lab");
    scenario.steps = vec!["scene 0 20 40".parse::<Step>().unwrap()];
    scenario.checks.clear();
    let direct = run_scenario(&scenario, &RunOptions::default(), |_, _| {}).unwrap();
    let (drive, events) = common::drive_served(&scenario, 20.0);
    let drive = drive.unwrap_or_else(|e| panic!("{e}; events: {events:#?}"));
    // Every scan of the scene knows where the head was, from the pan-tilt's own reports.
    let scene_scans: Vec<_> = drive.scans.iter().filter(|(_, _, s)| s.is_some()).collect();
    assert_eq!(scene_scans.len(), 21);
    assert!(scene_scans.iter().all(|(s, _, _)| s.head.is_some()));
    // Written as a drive, rebuilt by the same command as a twin run.
    let dir = temp_dir("served");
    sim::commands::drive::write_drive(&drive, &scenario, &[], &dir).unwrap();
    let folder = read_run_folder(&dir).unwrap();
    let map = WorldMap::new(&scenario.world);
    let served = reconstruct(
        &folder.inputs,
        None,
        &scenario.reconstruction.mesh,
        Some(&map),
        false,
    )
    .unwrap()
    .unwrap();
    let served = served.placed(Placement::Odometry).unwrap();
    let direct = direct.reconstruction.unwrap();
    let direct = direct.placed(Placement::Odometry).unwrap();
    let ((_, _), (t_served, of)) = served.model.counts();
    let ((_, _), (t_direct, of_direct)) = direct.model.counts();
    assert_eq!(of, of_direct);
    let (s, d) = (t_served as f64 / of as f64, t_direct as f64 / of as f64);
    assert!((s - d).abs() < 0.02, "valid share {s} served, {d} direct");
    let (sa, da) = (
        served.accuracy.as_ref().unwrap(),
        direct.accuracy.as_ref().unwrap(),
    );
    // The head's angles from the reports (positions and clicks) against the twin's truth: the
    // same surfaces to within a few millimetres.
    assert!(
        sa.median_m < da.median_m + 0.003,
        "{} vs {}",
        sa.median_m,
        da.median_m
    );
    assert!((sa.coverage - da.coverage).abs() < 0.01);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_input_is_refused_with_the_file_line_and_field() {
    let dir = temp_dir("bad");
    std::fs::create_dir_all(&dir).unwrap();
    let twin = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_twin"))
            .args(args)
            .output()
            .unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let d = dir.to_str().unwrap();
    // No scans at all.
    let (ok, err) = twin(&["reconstruct", d]);
    assert!(!ok && err.contains("scans.jsonl"), "{err}");
    // A garbled line is named by its number.
    std::fs::write(
        dir.join("scans.jsonl"),
        "{\"t\": 1.0, \"angle_min\": -1.5, \"angle_increment\": 0.01, \"range_max\": 32, \"ranges\": [1.0], \"odometry\": [0, 0, 0], \"scene\": 0}\n{\"t\": 2.0, \"ranges\": \n",
    )
    .unwrap();
    let (ok, err) = twin(&["reconstruct", d]);
    assert!(!ok && err.contains("scans.jsonl:2:"), "{err}");
    // Scans of no scene.
    std::fs::write(
        dir.join("scans.jsonl"),
        "{\"t\": 1.0, \"angle_min\": -1.5, \"angle_increment\": 0.01, \"range_max\": 32, \"ranges\": [1.0], \"odometry\": [0, 0, 0]}\n",
    )
    .unwrap();
    let (ok, err) = twin(&["reconstruct", d]);
    assert!(!ok && err.contains("no scan of a 3D scene"), "{err}");
    // Absurd options.
    let (ok, err) = twin(&["reconstruct", d, "--max-mm", "1e300"]);
    assert!(!ok && err.contains("--max-mm"), "{err}");
    let (ok, err) = twin(&["reconstruct", d, "--sweep"]);
    assert!(!ok && err.contains("--world"), "{err}");
    // A truncated estimate.tum.
    std::fs::write(dir.join("estimate.tum"), "# t x y z qx qy qz qw\n1.0 0 0\n").unwrap();
    let (ok, err) = twin(&["reconstruct", d]);
    assert!(!ok && err.contains("estimate.tum:2:"), "{err}");
    std::fs::remove_file(dir.join("estimate.tum")).unwrap();
    // Finite but absurd numbers are refused by name, never turned into points at infinity.
    std::fs::write(
        dir.join("scans.jsonl"),
        "{\"t\": 1.0, \"angle_min\": -1.5, \"angle_increment\": 0.01, \"range_max\": 32, \"ranges\": [1.0], \"odometry\": [0, 0, 0], \"laser_mount\": [0, 0, 0], \"laser_z\": 1e300, \"laser_tilt\": 0, \"scene\": 0}\n",
    )
    .unwrap();
    let (ok, err) = twin(&["reconstruct", d]);
    assert!(
        !ok && err.contains("scans.jsonl:1: laser_z = 1e300"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
    // Scenario files: a model check without scenes, an unknown rule.
    let root = common::repo().join("scenarios");
    let base = std::fs::read_to_string(root.join("tilted-scan.toml"))
        .unwrap()
        .replace("\"../worlds/", &format!("\"{}/../worlds/", root.display()))
        .replace("\"robots/", &format!("\"{}/robots/", root.display()));
    let scratch = temp_dir("scenario");
    std::fs::create_dir_all(&scratch).unwrap();
    let scenario = |extra: &str| {
        let path = scratch.join("scratch.toml");
        std::fs::write(&path, format!("{base}\n{extra}")).unwrap();
        Scenario::load(&path).map(|_| ()).map_err(|e| e.to_string())
    };
    let err = scenario("[[check]]\nkind = \"point_error\"\nmax_m = 0.01\n").unwrap_err();
    assert!(
        err.contains("check[2]") && err.contains("`scene` or `survey`"),
        "{err}"
    );
    let err = scenario("[reconstruction]\nrule = \"magic\"\n").unwrap_err();
    assert!(
        err.contains("reconstruction.rule") && err.contains("incidence"),
        "{err}"
    );
    let err = scenario("[reconstruction]\nmax_mm = 1e300\n").unwrap_err();
    assert!(err.contains("reconstruction.max_mm"), "{err}");
    let _ = std::fs::remove_dir_all(&scratch);
}
