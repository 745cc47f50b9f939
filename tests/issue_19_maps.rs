//! Issue 19, maps out: every run and every `twin map` writes its occupancy grid as `map.pgm` +
//! `map.yaml` in the ROS `map_server` convention, from the estimate's scans with free space
//! traced along each beam. Read back here by a reader written from the convention (not from the
//! writer): the header, the values, the origin; and held against the world's true walls.

use crate::common::{repo, scenario};
use sim::world::WorldMap;
use std::path::{Path, PathBuf};

/// `twin ARGS --out DIR` into a fresh folder named after `name`.
fn twin_into(name: &str, args: &[&str]) -> PathBuf {
    crate::common::twin_into(&format!("issue-19-{name}"), args)
}

/// A `map.yaml` + `map.pgm` as `map_server` reads them.
struct RosMap {
    resolution: f64,
    origin: [f64; 3],
    width: usize,
    height: usize,
    /// Row by row, top (largest y) first.
    pixels: Vec<u8>,
}

impl RosMap {
    fn read(dir: &Path) -> RosMap {
        let yaml = std::fs::read_to_string(dir.join("map.yaml")).expect("map.yaml");
        let field = |name: &str| -> String {
            yaml.lines()
                .find_map(|l| l.strip_prefix(&format!("{name}:")))
                .unwrap_or_else(|| panic!("map.yaml has no {name}: {yaml}"))
                .trim()
                .to_string()
        };
        assert_eq!(field("image"), "map.pgm");
        assert_eq!(field("negate"), "0");
        let thresholds = (
            field("occupied_thresh").parse::<f64>().unwrap(),
            field("free_thresh").parse::<f64>().unwrap(),
        );
        assert!(thresholds.0 > thresholds.1 && thresholds.0 < 1.0 && thresholds.1 > 0.0);
        let origin: Vec<f64> = field("origin")
            .trim_matches(|c| c == '[' || c == ']')
            .split(',')
            .map(|v| v.trim().parse().unwrap())
            .collect();
        let pgm = std::fs::read(dir.join("map.pgm")).expect("map.pgm");
        // P5, then width, height and maxval, with comments, then one whitespace byte.
        let mut tokens = Vec::new();
        let mut i = 0;
        while tokens.len() < 4 {
            while pgm[i].is_ascii_whitespace() {
                i += 1;
            }
            if pgm[i] == b'#' {
                while pgm[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            let start = i;
            while !pgm[i].is_ascii_whitespace() {
                i += 1;
            }
            tokens.push(String::from_utf8(pgm[start..i].to_vec()).unwrap());
        }
        assert_eq!(tokens[0], "P5");
        assert_eq!(tokens[3], "255");
        let (width, height) = (tokens[1].parse().unwrap(), tokens[2].parse().unwrap());
        let pixels = pgm[i + 1..].to_vec();
        assert_eq!(pixels.len(), width * height, "one byte per cell");
        RosMap {
            resolution: field("resolution").parse().unwrap(),
            origin: [origin[0], origin[1], origin[2]],
            width,
            height,
            pixels,
        }
    }

    /// The centre of cell (column, row from the top), map frame.
    fn centre(&self, column: usize, row: usize) -> [f64; 2] {
        let r = self.resolution;
        [
            self.origin[0] + (column as f64 + 0.5) * r,
            self.origin[1] + ((self.height - 1 - row) as f64 + 0.5) * r,
        ]
    }

    fn pixel_at(&self, p: [f64; 2]) -> u8 {
        let column = ((p[0] - self.origin[0]) / self.resolution).floor() as usize;
        let up = ((p[1] - self.origin[1]) / self.resolution).floor() as usize;
        self.pixels[(self.height - 1 - up) * self.width + column]
    }
}

/// The lab tour's grid: trinary values only, the start free, and what it calls occupied inside
/// the building lies on the lab's true walls (the estimate is a decimetre off at worst on this
/// tour).
#[test]
fn a_run_writes_a_ros_map_of_what_it_saw() {
    let dir = twin_into("lab-tour", &["run", "scenarios/lab-tour.toml", "--quiet"]);
    let map = RosMap::read(&dir);
    assert_eq!(map.resolution, 0.05);
    assert_eq!(map.origin[2], 0.0);
    assert!(map.pixels.iter().all(|&v| v == 0 || v == 205 || v == 254));
    let lab = scenario("lab-tour");
    let world = WorldMap::new(&lab.world);
    let start = [lab.world.start.x, lab.world.start.y];
    assert_eq!(map.pixel_at(start), 254, "the start is free");
    // Beyond the building the laser sees mirror images through its glass (the twin's optics,
    // as the real laser's): those cells are what the laser reported, not walls, and are left out.
    let (lo, hi) = lab.world.bounds();
    let inside = |p: [f64; 2]| p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1];
    let (mut occupied, mut on_walls, mut free) = (0, 0, 0);
    for row in 0..map.height {
        for column in 0..map.width {
            let v = map.pixels[row * map.width + column];
            let centre = map.centre(column, row);
            if !inside(centre) {
                continue;
            }
            let clearance = world.clearance(centre);
            if v == 0 {
                occupied += 1;
                on_walls += usize::from(clearance <= 0.2);
            } else if v == 254 {
                free += 1;
            }
        }
    }
    assert!(
        occupied > 500 && free > 10 * occupied,
        "{occupied} occupied, {free} free"
    );
    assert!(
        on_walls as f64 >= 0.9 * occupied as f64,
        "{on_walls} of {occupied} occupied cells lie within 20 cm of a wall"
    );
}

/// `twin map` writes the grid of a real log too.
#[test]
fn a_log_map_writes_a_ros_map() {
    let dir = twin_into(
        "belgioioso",
        &["map", "tests/data/corrected/belgioioso-corrected.log.gz"],
    );
    let map = RosMap::read(&dir);
    let occupied = map.pixels.iter().filter(|&&v| v == 0).count();
    let free = map.pixels.iter().filter(|&&v| v == 254).count();
    assert!(
        occupied > 1000 && free > occupied,
        "{occupied} occupied, {free} free"
    );
    // The first scan's base is the map's origin: free (a point inside a cell, not on a corner).
    assert_eq!(map.pixel_at([0.012, 0.013]), 254);
}

/// A world made from a map image (`worlds/lab-from-map.toml`: the lab tour's grid): from the
/// start, the laser reads within 15 cm of what it reads in the hand-written lab on most of the
/// beams the real lab sends back (80 % at this pose; the rest leak through gaps in the mapped
/// walls or meet mirror images the map drew).
#[test]
fn a_world_from_a_map_image_looks_like_the_world_it_mapped() {
    use sim::config::{Outliers, WorldDescription};
    use sim::devices::laser::LaserModel;
    let robot = crate::common::robot("pioneer-3dx");
    let lab = WorldDescription::load(repo().join("worlds/lab.toml")).unwrap();
    let from_map = WorldDescription::load(repo().join("worlds/lab-from-map.toml")).unwrap();
    assert!(from_map.walls.len() > 100, "{} walls", from_map.walls.len());
    let laser = LaserModel::new(&robot.laser, robot.laser_mount(), 0.0, Outliers::NONE);
    let scan = |world: &WorldDescription| {
        let map = WorldMap::new(world);
        let frame = laser.frame_on(lab.start);
        let mut rng = sim::rng::stream(1, "laser");
        laser
            .scan(&map, None, frame, robot::Stamp::ZERO, &mut rng)
            .ranges_mm
    };
    let (truth, mapped) = (scan(&lab), scan(&from_map));
    // Beams the real lab sends back (no return from its black desks and glass: nothing to map).
    let returned: Vec<(u16, u16)> = truth
        .iter()
        .zip(&mapped)
        .filter(|(a, _)| **a < 32_000)
        .map(|(a, b)| (*a, *b))
        .collect();
    let close = returned
        .iter()
        .filter(|(a, b)| (i32::from(*a) - i32::from(*b)).abs() <= 150)
        .count();
    assert!(returned.len() > 100, "{} beams return", returned.len());
    assert!(
        close as f64 >= 0.7 * returned.len() as f64,
        "{close} of {} returned beams within 15 cm",
        returned.len()
    );
}

/// A map file that is not one says which file, which line and what was expected.
#[test]
fn a_bad_map_file_is_named_with_its_line() {
    use sim::config::map_image::MapImage;
    let dir = std::env::temp_dir().join(format!("twin-issue-19-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases = [
        ("image: m.pgm\norigin: [0, 0, 0]\n", "resolution", None),
        (
            "image: m.pgm\nresolution: fast\norigin: [0, 0, 0]\n",
            "expected a number",
            Some(2),
        ),
        (
            "image: m.pgm\nresolution: 0.05\norigin: [0, 0]\n",
            "[x, y, yaw]",
            Some(3),
        ),
        (
            "image: none.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n",
            "none.pgm",
            Some(1),
        ),
        ("image: m.pgm\nresolution 0.05\n", "key: value", Some(2)),
    ];
    std::fs::write(dir.join("m.pgm"), b"P5\n2 2\n255\n\x00\xff").unwrap(); // truncated
    for (i, (yaml, expected, line)) in cases.into_iter().enumerate() {
        let path = dir.join(format!("case-{i}.yaml"));
        std::fs::write(&path, yaml).unwrap();
        let err = MapImage::load(&path).unwrap_err();
        let text = err.to_string();
        assert!(text.contains(&format!("case-{i}.yaml")), "{text}");
        assert!(text.contains(expected), "{text}");
        assert_eq!(err.line, line, "{text}");
    }
    let path = dir.join("truncated.yaml");
    std::fs::write(&path, "image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n").unwrap();
    let text = MapImage::load(&path).unwrap_err().to_string();
    assert!(text.contains("truncated"), "{text}");
}

/// A PNG map reads as the PGM does: a one-pixel black dot in white is one occupied cell, four
/// walls.
#[test]
fn a_png_map_reads_too() {
    use sim::config::Material;
    use sim::config::map_image::MapImage;
    let dir = std::env::temp_dir().join(format!("twin-issue-19-png-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, 3, 3);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        writer
            .write_image_data(&[255, 255, 255, 255, 0, 255, 255, 255, 255])
            .unwrap();
    }
    std::fs::write(dir.join("dot.png"), bytes).unwrap();
    std::fs::write(
        dir.join("dot.yaml"),
        "image: dot.png\nresolution: 0.1\norigin: [1.0, 2.0, 0.0]\n",
    )
    .unwrap();
    let map = MapImage::load(&dir.join("dot.yaml")).unwrap();
    assert_eq!(map.occupied.iter().filter(|&&o| o).count(), 1);
    let walls = map.walls(
        &sim::config::map_image::Palette::single(Material::Matte),
        [0.0, 2.0],
    );
    assert_eq!(walls.len(), 4);
    let xs: Vec<f64> = walls
        .iter()
        .flat_map(|w| w.points.iter().map(|p| p[0]))
        .collect();
    assert!(
        xs.iter()
            .all(|&x| (x - 1.1).abs() < 1e-9 || (x - 1.2).abs() < 1e-9),
        "{xs:?}"
    );
}

/// The lab drawn as a Stage bitmap (`worlds/maps/lab-stage.png`, each material in its own grey:
/// `sim::world::raster`) and read back through a world's `[map] bitmap` with its palette
/// (`worlds/lab-stage.toml`): the shipped image is what the rasteriser draws today (set
/// `REGENERATE_STAGE_BITMAP=1` to rewrite it), the walls come back with their materials, and the
/// laser reads the lab.
#[test]
fn a_stage_bitmap_with_a_palette_reads_back_as_the_lab() {
    use sim::config::{Material, Outliers, WorldDescription};
    use sim::devices::laser::LaserModel;
    use sim::world::raster::faces_bitmap;
    let lab = WorldDescription::load(repo().join("worlds/lab.toml")).unwrap();
    let drawn = faces_bitmap(&WorldMap::new(&lab), 0.05);
    let shipped = repo().join("worlds/maps/lab-stage.png");
    if std::env::var_os("REGENERATE_STAGE_BITMAP").is_some() {
        std::fs::write(&shipped, drawn.png()).unwrap();
        eprintln!(
            "wrote {}: size [{:.2}, {:.2}], center [{:.3}, {:.3}]",
            shipped.display(),
            drawn.size[0],
            drawn.size[1],
            drawn.center[0],
            drawn.center[1]
        );
    }
    let decoder = png::Decoder::new(std::io::Cursor::new(std::fs::read(&shipped).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut pixels).unwrap();
    assert_eq!(
        (reader.info().width as usize, reader.info().height as usize),
        (drawn.width, drawn.height)
    );
    assert!(
        pixels == drawn.pixels,
        "the shipped bitmap is not what the lab draws today"
    );

    let stage = WorldDescription::load(repo().join("worlds/lab-stage.toml")).unwrap();
    for material in [
        Material::Matte,
        Material::Glass,
        Material::Black,
        Material::Metal,
    ] {
        assert!(
            stage.walls.iter().any(|w| w.material == material),
            "no {material:?} wall came back"
        );
    }
    let robot = crate::common::robot("pioneer-3dx");
    let laser = LaserModel::new(&robot.laser, robot.laser_mount(), 0.0, Outliers::NONE);
    let (lab_map, stage_map) = (WorldMap::new(&lab), WorldMap::new(&stage));
    let (mut close, mut returned) = (0, 0);
    for start in [
        lab.start,
        robot::Pose2::new(4.0, 3.0, 1.0),
        robot::Pose2::new(12.0, 3.0, 3.0),
    ] {
        let scan = |map: &WorldMap| {
            let mut rng = sim::rng::stream(1, "laser");
            laser
                .scan(
                    map,
                    None,
                    laser.frame_on(start),
                    robot::Stamp::ZERO,
                    &mut rng,
                )
                .ranges_mm
        };
        for (a, b) in scan(&lab_map).into_iter().zip(scan(&stage_map)) {
            if a < 32_000 {
                returned += 1;
                close += usize::from((i32::from(a) - i32::from(b)).abs() <= 100);
            }
        }
    }
    assert!(returned > 300, "{returned} beams return");
    assert!(
        close as f64 >= 0.8 * returned as f64,
        "{close} of {returned} returned beams within 10 cm of the hand-written lab"
    );
}

/// A `[map]` that is neither one kind nor the other, or whose palette names a value or a
/// material that does not exist, is refused with the field.
#[test]
fn a_bad_map_table_names_its_field() {
    use sim::config::WorldDescription;
    let path = repo().join("worlds/bad-map.toml");
    let cases = [
        (
            "[map]\nyaml = \"maps/lab-tour.yaml\"\nbitmap = \"maps/lab-stage.png\"\n",
            "either `yaml`",
        ),
        ("[map]\nbitmap = \"maps/lab-stage.png\"\n", "map.size"),
        (
            "[map]\nbitmap = \"maps/lab-stage.png\"\nsize = [1, -2, 1]\n",
            "map.size",
        ),
        (
            "[map]\nbitmap = \"maps/lab-stage.png\"\nsize = [1, 2, 1]\npose = [0, 0, 0, 90]\n",
            "map.pose",
        ),
        (
            "[map]\nbitmap = \"maps/lab-stage.png\"\nsize = [1, 2, 1]\n[map.materials]\n\"300\" = \"glass\"\n",
            "map.materials.300",
        ),
        (
            "[map]\nyaml = \"maps/lab-tour.yaml\"\n[map.materials]\n\"0\" = \"velvet\"\n",
            "velvet",
        ),
        (
            "[map]\nbitmap = \"maps/none.png\"\nsize = [1, 2, 1]\n",
            "none.png",
        ),
    ];
    for (table, expected) in cases {
        let text = format!("name = \"bad\"\n[start]\nx = 0\ny = 0\n{table}");
        let err = WorldDescription::parse(&text, path.to_str().unwrap())
            .expect_err(table)
            .to_string();
        assert!(err.contains(expected), "{table}: {err}");
        assert!(err.contains("bad-map.toml"), "{err}");
    }
}

/// `twin run` builds the occupancy grid, the scans' lines, the recording, the trajectories and
/// the map picture's scan points on a thread of their own while the simulation goes on; the
/// files it writes are, byte for byte, the ones built from the run's record afterwards — with
/// the estimate (lab tour), by odometry (glass door), with scenes left out (scene lab) and with
/// the laser on the pan-tilt (thesis tour), across seeds.
#[test]
fn the_files_built_during_a_run_are_the_files_built_after_it() {
    use sim::commands::run::{RunOptions, run_scenario};
    let root = std::env::temp_dir().join(format!("twin-issue-19-stream-{}", std::process::id()));
    for (name, seed) in [
        ("lab-tour", 3),
        ("glass-door", 11),
        ("scene-lab", 5),
        ("lab-tour-thesis", 8),
    ] {
        let options = RunOptions {
            seed: Some(seed),
            stream: true,
            ..RunOptions::default()
        };
        let streamed = run_scenario(&scenario(name), &options, |_, _| {}).expect("the run");
        let built = streamed.streamed.as_ref().expect("built as it went");
        assert!(
            built.run_mcap.is_some() && built.dots.is_some() && built.tum.is_some(),
            "{name}: the recording, the picture's points and the trajectories built as it went"
        );
        let mut after = streamed.clone();
        after.streamed = None;
        let (a, b) = (
            root.join(format!("{name}-a")),
            root.join(format!("{name}-b")),
        );
        sim::output::write_all(&streamed, &scenario(name), &a).unwrap();
        sim::output::write_all(&after, &scenario(name), &b).unwrap();
        for file in [
            "map.pgm",
            "map.yaml",
            "scans.jsonl",
            "run.mcap",
            "map.svg",
            "truth.tum",
            "odometry.tum",
        ] {
            let (x, y) = (std::fs::read(a.join(file)), std::fs::read(b.join(file)));
            assert!(x.is_ok(), "{name}: {file} written");
            assert!(x.ok() == y.ok(), "{name} seed {seed}: {file} differs");
        }
    }
    std::fs::remove_dir_all(&root).ok();
}

/// What depends on the twin's truth — `run.mcap`, `map.svg`'s scan points, `truth.tum` — is kept
/// from the stream only if each kept scan's truth, noted as the scan came back, is the one the
/// record holds: a stream told no truth, or a truth a centimetre off, leaves those files to the
/// record, and they are the files of a run that did not stream; told the record's truths, it
/// keeps them, and they are the record's files too.
#[test]
fn a_stream_keeps_what_depends_on_the_truth_only_when_it_was_the_runs() {
    use sim::commands::run::{RunOptions, run_scenario};
    use sim::output::{ScanStream, write_all};
    let root = std::env::temp_dir().join(format!("twin-issue-19-truth-{}", std::process::id()));
    let scenario = scenario("glass-door");
    let options = RunOptions {
        seed: Some(6),
        ..RunOptions::default()
    };
    let record = run_scenario(&scenario, &options, |_, _| {}).expect("the run");
    assert!(record.streamed.is_none() && !record.scans.is_empty());
    let files = [
        "run.mcap",
        "map.svg",
        "truth.tum",
        "odometry.tum",
        "scans.jsonl",
        "map.pgm",
    ];
    let read = |dir: &Path| files.map(|f| std::fs::read(dir.join(f)).expect("written"));
    for (case, told) in [
        ("no truth", None),
        ("a truth 1 cm off", Some(0.01)),
        ("the run's truth", Some(0.0)),
    ] {
        let mut run = record.clone();
        let mut stream =
            ScanStream::start(&scenario, std::sync::Arc::clone(&run.world_map), Vec::new());
        let feed = stream.tape_feed();
        for exchange in &run.tape {
            feed.exchange(exchange);
        }
        for r in &run.scans {
            if let Some(off) = told {
                let truth = robot::Pose2::new(r.truth.x + off, r.truth.y, r.truth.theta);
                feed.truth(r.scan.stamp, truth, r.frame);
            }
            stream.kept(&r.scan, r.odometry, r.scene);
            if r.scene.is_none() {
                stream.grid(&r.scan, r.odometry);
            }
        }
        drop(feed);
        let built = stream.finish(&mut run, &scenario);
        let kept = told == Some(0.0);
        assert_eq!(built.run_mcap.is_some(), kept, "{case}: the recording");
        assert_eq!(built.dots.is_some(), kept, "{case}: the picture's points");
        assert_eq!(built.tum.is_some(), kept, "{case}: the trajectories");
        assert_eq!(
            run.scans.iter().all(|s| s.after_exchanges.is_some()),
            kept,
            "{case}: the scans' places among the exchanges"
        );
        // The same files as the record (with what the stream taught it) gives alone.
        let mut alone = run.clone();
        alone.streamed = None;
        run.streamed = Some(built);
        let (a, b) = (
            root.join(format!("{case}-a")),
            root.join(format!("{case}-b")),
        );
        write_all(&run, &scenario, &a).unwrap();
        write_all(&alone, &scenario, &b).unwrap();
        for (file, (x, y)) in files.iter().zip(read(&a).iter().zip(read(&b).iter())) {
            assert!(x == y, "{case}: {file} differs");
        }
    }
    std::fs::remove_dir_all(&root).ok();
}
