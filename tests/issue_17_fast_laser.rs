//! Issue 17: the laser's sweep (every beam's first leg cast in one pass over the faces) answers
//! exactly what the reference — each beam cast down the world's tree — answers: the same
//! surface, the same distance to 1e-9 m, and whole scans identical reading for reading with every
//! material's optics and the outliers on, among other robots' bodies, from random poses (level
//! and tilted, any heading) in every bundled world.

use rand::{RngExt, SeedableRng};
use robot::{Pose2, Stamp};
use sim::config::{Outliers, WorldDescription};
use sim::devices::laser::beam::Disc;
use sim::devices::laser::{Casting, LaserFrame, LaserModel};
use sim::world::{FAN_MAX_FACES, FanCast, Hit, WorldMap};

/// Every world in `worlds/`, and the lab grown with boxes to just under the sweep's limit.
fn worlds() -> Vec<(String, WorldDescription)> {
    let folder = crate::common::repo().join("worlds");
    let mut worlds: Vec<(String, WorldDescription)> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| {
            let w = WorldDescription::load(&p).unwrap_or_else(|e| panic!("{e}"));
            (p.file_name().unwrap().to_string_lossy().into_owned(), w)
        })
        .collect();
    worlds.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(worlds.len() >= 6, "the bundled worlds are found");
    let lab = std::fs::read_to_string(folder.join("lab.toml")).unwrap();
    let cluttered = sim::world::clutter::lab_with_boxes(&lab, 80);
    let cluttered = WorldDescription::parse(&cluttered, "lab-80-boxes.toml").unwrap();
    assert!(WorldMap::new(&cluttered).faces().len() <= FAN_MAX_FACES);
    worlds.push(("lab + 80 boxes".into(), cluttered));
    worlds
}

/// A random laser frame over the world: anywhere in its bounds (inside furniture too), any
/// heading, level or tilted up to ±40°, at heights from the floor to above the tables.
fn random_frame(world: &WorldDescription, rng: &mut impl RngExt) -> LaserFrame {
    let (min, max) = world.bounds();
    let tilt = if rng.random_bool(0.5) {
        0.0
    } else {
        rng.random_range(-40f64..40.0).to_radians()
    };
    LaserFrame {
        origin: [
            rng.random_range(min[0] - 1.0..max[0] + 1.0),
            rng.random_range(min[1] - 1.0..max[1] + 1.0),
            rng.random_range(0.05..1.5),
        ],
        yaw: rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
        tilt,
    }
}

fn same(fast: &Option<Hit>, reference: &Option<Hit>) -> bool {
    match (fast, reference) {
        (None, None) => true,
        (Some(f), Some(r)) => {
            f.surface == r.surface
                && f.material == r.material
                && f.normal == r.normal
                && (f.distance - r.distance).abs() <= 1e-9
        }
        _ => false,
    }
}

/// [`same`], and the same distance to the last bit.
fn identical(fast: &Option<Hit>, reference: &Option<Hit>) -> bool {
    same(fast, reference) && fast.map(|h| h.distance) == reference.map(|h| h.distance)
}

#[test]
fn the_sweep_meets_what_each_beam_meets_alone() {
    let lms = crate::common::robot("pioneer-3dx").laser;
    let model = LaserModel::new(&lms, Pose2::IDENTITY, 0.0, Outliers::NONE);
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(17);
    let (mut rays, mut hits) = (0usize, 0usize);
    for (name, world) in worlds() {
        let map = WorldMap::new(&world);
        let mut fan = Vec::new();
        for _ in 0..150 {
            let frame = random_frame(&world, &mut rng);
            let dirs = model.directions(frame);
            map.cast_fan(frame.origin, &dirs, 32.0, &mut fan);
            let mut plane = FanCast::default();
            let (beams, axes) = (model.beams(), frame.axes());
            map.cast_plane_fan(frame.origin, axes, beams, 32.0, &mut plane);
            for (k, (dir, fast)) in dirs.iter().zip(&fan).enumerate() {
                let reference = map.cast_down_tree(frame.origin, *dir, 32.0);
                assert!(
                    same(fast, &reference) && same(&plane.hit(&map, k), &reference),
                    "{name}, {frame:?}, beam {k}: sweep {fast:?}, in the plane {:?}, reference {reference:?}",
                    plane.hit(&map, k)
                );
                rays += 1;
                hits += usize::from(fast.is_some());
            }
        }
    }
    assert!(
        hits > rays / 2,
        "most beams meet something: {hits} of {rays}"
    );
}

#[test]
fn small_fans_at_any_heading_and_range_match_too() {
    // Sonar-like fans of 7 rays over 15°, headings all round (the pseudo-angles wrap at +x),
    // ranges short enough that many faces are out of reach.
    let world = crate::common::world("lab");
    let map = WorldMap::new(&world);
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(3);
    let mut fan = Vec::new();
    for _ in 0..2000 {
        let frame = random_frame(&world, &mut rng);
        let heading = frame.yaw;
        let dirs: Vec<[f64; 3]> = (0..7)
            .map(|i| {
                let a = heading + (f64::from(i) - 3.0) * 2.5f64.to_radians();
                [a.cos(), a.sin(), 0.0]
            })
            .collect();
        let max = rng.random_range(0.5..12.0);
        map.cast_fan(frame.origin, &dirs, max, &mut fan);
        for (dir, fast) in dirs.iter().zip(&fan) {
            let reference = map.cast_down_tree(frame.origin, *dir, max);
            assert!(
                same(fast, &reference),
                "{frame:?} {dir:?}: {fast:?} vs {reference:?}"
            );
        }
    }
}

#[test]
fn whole_scans_equal_the_reference_reading_for_reading() {
    let lms = crate::common::robot("pioneer-3dx").laser;
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(2);
    let mut compared = 0;
    for (name, world) in worlds() {
        let map = WorldMap::new(&world);
        for outliers in ["none", "thesis-2pct", "thesis-20pct"] {
            let model = LaserModel::new(
                &lms,
                Pose2::IDENTITY,
                0.01,
                Outliers::preset(outliers).unwrap(),
            );
            let reference = model.clone().with_casting(Casting::PerBeam);
            let baseline = model.clone().with_casting(Casting::SweepBaseline);
            let avx2 = model.clone().with_casting(Casting::SweepAvx2);
            for k in 0..40u64 {
                let frame = random_frame(&world, &mut rng);
                // The robot's own body, which reflected beams can meet.
                let body = Some(Disc {
                    center: [frame.origin[0] - 0.1, frame.origin[1]],
                    radius: 0.25,
                    height: 0.5,
                });
                let seed = rng.random::<u64>();
                let mut a = sim::rng::substream(seed, k);
                let mut b = sim::rng::substream(seed, k);
                let mut c = sim::rng::substream(seed, k);
                let mut d = sim::rng::substream(seed, k);
                // Other robots around, which every leg meets too.
                let others: Vec<Disc> = (0..rng.random_range(0..4))
                    .map(|_| Disc {
                        center: [
                            frame.origin[0] + rng.random_range(-3.0..3.0),
                            frame.origin[1] + rng.random_range(-3.0..3.0),
                        ],
                        radius: 0.25,
                        height: 0.5,
                    })
                    .collect();
                let fast = model.scan_among(&map, body, &others, frame, Stamp(k), &mut a);
                let reference = reference.scan_among(&map, body, &others, frame, Stamp(k), &mut b);
                // The sweep as compiled for this processor (AVX-512 or AVX2 where it has them),
                // for AVX2 and for the baseline one.
                let base = baseline.scan_among(&map, body, &others, frame, Stamp(k), &mut c);
                let four = avx2.scan_among(&map, body, &others, frame, Stamp(k), &mut d);
                assert_eq!(fast, reference, "{name}, {outliers}, {frame:?}");
                assert_eq!(
                    base, reference,
                    "baseline build: {name}, {outliers}, {frame:?}"
                );
                assert_eq!(four, reference, "AVX2 build: {name}, {outliers}, {frame:?}");
                let draws = [a, b, c, d].map(|mut r| r.random::<u64>());
                assert!(
                    draws.iter().all(|&x| x == draws[0]),
                    "the same draws were made"
                );
                compared += 1;
            }
        }
    }
    assert!(compared >= 7 * 3 * 40);
}

/// The default casts each beam on its own, as the reference does, only in a world whose fans
/// would go down the tree ray by ray anyway: many faces thinly spread over a mostly empty grid
/// (the lab traced from its map). The hand-written worlds keep the sweep, and the lab with
/// hundreds of boxes, past the sweep's limit, keeps walking its grid. Its readings are the
/// reference's either way (the whole-scan test above, over every bundled world).
#[test]
fn fans_are_cast_together_only_where_that_does_less_work() {
    let folder = crate::common::repo().join("worlds");
    let load = |file: &str| WorldMap::new(&WorldDescription::load(folder.join(file)).unwrap());
    for file in ["lab.toml", "glass-door.toml", "lab-stage.toml"] {
        assert!(load(file).casts_fans(), "{file}");
    }
    let traced = load("lab-from-map.toml");
    assert!(traced.faces().len() > FAN_MAX_FACES && !traced.casts_fans());
    let lab = std::fs::read_to_string(folder.join("lab.toml")).unwrap();
    let boxes = sim::world::clutter::lab_with_boxes(&lab, 792);
    let boxes = WorldMap::new(&WorldDescription::parse(&boxes, "lab-792-boxes.toml").unwrap());
    assert!(boxes.faces().len() > FAN_MAX_FACES && boxes.casts_fans());
}

#[test]
fn beams_through_the_ends_of_faces_match_too() {
    // Each beam aimed exactly at a corner of the lab (up to rounding): the sweep's angular
    // bounds are tightest there.
    let lms = crate::common::robot("pioneer-3dx").laser;
    let model = LaserModel::new(&lms, Pose2::IDENTITY, 0.0, Outliers::NONE);
    let world = crate::common::world("lab");
    let map = WorldMap::new(&world);
    let mut fan = Vec::new();
    let mut aimed = 0;
    for face in map.faces() {
        for (end, k) in [
            (face.a, 17usize),
            (face.b, 180),
            (face.a, 301),
            (face.b, 360),
        ] {
            for yaw in [0.3f64, 2.0, -2.9] {
                let level = LaserFrame {
                    origin: [0.0, 0.0, 0.3],
                    yaw,
                    tilt: 0.0,
                };
                let dir = model.directions(level)[k];
                let frame = LaserFrame {
                    origin: [end[0] - 2.5 * dir[0], end[1] - 2.5 * dir[1], 0.3],
                    ..level
                };
                let dirs = model.directions(frame);
                map.cast_fan(frame.origin, &dirs, 32.0, &mut fan);
                let mut plane = FanCast::default();
                let (beams, axes) = (model.beams(), frame.axes());
                map.cast_plane_fan(frame.origin, axes, beams, 32.0, &mut plane);
                assert_eq!(plane.dirs(), &dirs[..]);
                for (j, d) in dirs.iter().enumerate() {
                    let reference = map.cast_down_tree(frame.origin, *d, 32.0);
                    for fast in [&fan[j], &plane.hit(&map, j)] {
                        assert!(
                            same(fast, &reference),
                            "{frame:?}, beam {j}: {fast:?} vs {reference:?}"
                        );
                    }
                }
                aimed += 1;
            }
        }
    }
    assert!(aimed > 100);
}

/// A single ray walked through the plan's grid (`cast`, what a reflected beam's leg or a sonar
/// ray is) meets what it meets down the tree, and so does a walk told a face (`cast_near`: what
/// the ray's neighbour met), whether the hint is the face met, another face, one the ray misses,
/// or no face at all: from random points in every world (and around it), in random directions,
/// level and not.
#[test]
fn a_hinted_cast_meets_what_the_plain_cast_meets() {
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(5);
    let mut right_hints = 0;
    for (name, world) in worlds() {
        let map = WorldMap::new(&world);
        let faces = map.faces().len();
        let mut last = None;
        for _ in 0..3000 {
            let frame = random_frame(&world, &mut rng);
            let angle = rng.random_range(-1.6f64..1.6);
            let dir = frame.direction(angle);
            let max = rng.random_range(0.5..32.0);
            let plain = map.cast_down_tree(frame.origin, dir, max);
            let walked = map.cast(frame.origin, dir, max);
            assert!(
                identical(&walked, &plain),
                "{name}: from {:?} along {dir:?} within {max} m: walked {walked:?}, down the tree {plain:?}",
                frame.origin
            );
            let met = match plain {
                Some(Hit {
                    surface: sim::world::Surface::Face(i),
                    ..
                }) => Some(i),
                _ => None,
            };
            for hint in [met, last, Some(rng.random_range(0..faces + 2)), None] {
                right_hints += usize::from(hint.is_some() && hint == met);
                let near = map.cast_near(frame.origin, dir, max, hint);
                assert!(
                    identical(&near, &plain),
                    "{name}: from {:?} along {dir:?} within {max} m, hint {hint:?}: {near:?} against {plain:?}",
                    frame.origin
                );
            }
            last = met.or(last);
        }
    }
    assert!(
        right_hints > 1000,
        "the hints were often right: {right_hints}"
    );
}

/// The walk through the plan's grid where its rounding is tightest: rays through the faces'
/// ends, rays along the axes (along walls and along the grid's lines), from the ends themselves
/// and from points beside them, level and rising — the same face at the same distance as down
/// the tree, every time.
#[test]
fn walked_rays_through_corners_and_along_walls_match_the_tree() {
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(23);
    let mut cast = 0;
    for (name, world) in worlds() {
        let map = WorldMap::new(&world);
        let ends: Vec<[f64; 2]> = map.faces().iter().flat_map(|f| [f.a, f.b]).collect();
        for _ in 0..400 {
            let from = ends[rng.random_range(0..ends.len())];
            let to = ends[rng.random_range(0..ends.len())];
            let nudge = [0.0, 1e-7, -1e-7, 0.013][rng.random_range(0..4)];
            let origin = [
                from[0] + nudge,
                from[1] - nudge,
                rng.random_range(0.05..1.5),
            ];
            let rise = [0.0, 0.0, 0.3, -0.3][rng.random_range(0..4)];
            let mut aims = vec![
                [1.0, 0.0, rise],
                [-1.0, 0.0, rise],
                [0.0, 1.0, rise],
                [0.0, -1.0, rise],
            ];
            let (dx, dy) = (to[0] - origin[0], to[1] - origin[1]);
            if dx.hypot(dy) > 1e-6 {
                aims.push([dx, dy, rise * dx.hypot(dy)]);
            }
            for aim in aims {
                let norm = (aim[0] * aim[0] + aim[1] * aim[1] + aim[2] * aim[2]).sqrt();
                let dir = aim.map(|v| v / norm);
                let max = 32.0;
                let walked = map.cast(origin, dir, max);
                let tree = map.cast_down_tree(origin, dir, max);
                assert!(
                    identical(&walked, &tree),
                    "{name}: from {origin:?} along {dir:?}: walked {walked:?}, down the tree {tree:?}"
                );
                cast += 1;
            }
        }
    }
    assert!(cast > 10_000, "{cast} rays");
}

/// A leg a mirror reflects or a pane lets through is cast among the faces listed for the cone
/// from the laser (or its image behind the mirror) through the face it leaves
/// (`WorldMap::faces_beyond`): it meets what the plain cast meets, to the last bit — also legs
/// leaving the face at its very ends, legs aimed at other faces' ends, rising and falling legs,
/// legs nudged off the face along its normal or along their way.
#[test]
fn legs_cast_among_a_cones_faces_meet_what_the_plain_cast_meets() {
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(17);
    let (mut compared, mut through_ends) = (0, 0);
    let mut listed = Vec::new();
    for (name, world) in worlds() {
        let map = WorldMap::new(&world);
        let faces = map.faces();
        for _ in 0..300 {
            let frame = random_frame(&world, &mut rng);
            let apex = [frame.origin[0], frame.origin[1]];
            let m = rng.random_range(0..faces.len());
            let (a, b) = (faces[m].a, faces[m].b);
            // The laser itself (legs through a pane) or its image behind the face (reflected).
            let apex = if rng.random_bool(0.5) {
                apex
            } else {
                let n = map.face_normal(m);
                let off = (apex[0] - a[0]) * n[0] + (apex[1] - a[1]) * n[1];
                [apex[0] - 2.0 * off * n[0], apex[1] - 2.0 * off * n[1]]
            };
            listed.clear();
            if !map.faces_beyond(apex, m, &mut listed) {
                continue;
            }
            // Where legs leave the face: its ends, just inside them, anywhere, and where the
            // rays from the apex to other faces' ends cross it.
            let mut leaves: Vec<[f64; 2]> = [0.0, 1e-12, 0.5, 1.0 - 1e-12, 1.0]
                .into_iter()
                .chain((0..3).map(|_| rng.random_range(0.0..1.0)))
                .map(|s| [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])])
                .collect();
            for other in faces {
                for end in [other.a, other.b] {
                    let e = [end[0] - apex[0], end[1] - apex[1]];
                    let ab = [b[0] - a[0], b[1] - a[1]];
                    let den = e[0] * ab[1] - e[1] * ab[0];
                    let w = [a[0] - apex[0], a[1] - apex[1]];
                    if den.abs() < 1e-12 {
                        continue;
                    }
                    let (s, u) = (
                        (w[0] * ab[1] - w[1] * ab[0]) / den,
                        (w[0] * e[1] - w[1] * e[0]) / den,
                    );
                    if s > 0.0 && (0.0..=1.0).contains(&u) {
                        leaves.push([apex[0] + s * e[0], apex[1] + s * e[1]]);
                        through_ends += 1;
                    }
                }
            }
            for h in leaves {
                let plan = [h[0] - apex[0], h[1] - apex[1]];
                let len = plan[0].hypot(plan[1]);
                if len < 1e-9 {
                    continue;
                }
                let rise: f64 = if rng.random_bool(0.5) {
                    0.0
                } else {
                    rng.random_range(-0.5..0.5)
                };
                let flat = (1.0 - rise * rise).sqrt() / len;
                let dir = [plan[0] * flat, plan[1] * flat, rise];
                // Nudged 10 µm off the face: along the normal on the leg's side, or along it.
                let n = map.face_normal(m);
                let side = if n[0] * dir[0] + n[1] * dir[1] >= 0.0 {
                    1.0
                } else {
                    -1.0
                };
                let nudge = if rng.random_bool(0.5) {
                    [side * n[0], side * n[1], 0.0]
                } else {
                    dir
                };
                let z = rng.random_range(0.05..1.5);
                let origin = [h[0] + 1e-5 * nudge[0], h[1] + 1e-5 * nudge[1], z];
                let max = rng.random_range(0.5..32.0);
                let among = map.cast_among(origin, dir, max, apex, &listed);
                let plain = map.cast_down_tree(origin, dir, max);
                assert!(
                    identical(&among, &plain),
                    "{name}: a leg off face {m} from {origin:?} along {dir:?} within {max} m, \
                     apex {apex:?}: {among:?} among the cone's faces, {plain:?} down the tree"
                );
                compared += 1;
            }
        }
    }
    assert!(compared > 10_000, "{compared} legs compared");
    assert!(
        through_ends > 1000,
        "{through_ends} legs through other faces' ends"
    );
}
