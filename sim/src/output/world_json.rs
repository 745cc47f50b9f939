//! `world.json`: the world's surfaces as the viewer draws them — every vertical face (a segment
//! extruded between two heights) and horizontal cap (a polygon at one height) with its
//! material, the ceiling, the start pose, and the robot's body — so a run's folder is enough to
//! look around in it (`twin view`).

use crate::config::Scenario;
use crate::world::WorldMap;
use serde::Serialize;
use std::path::Path;

#[derive(Serialize)]
struct Face {
    a: [f64; 2],
    b: [f64; 2],
    z: [f64; 2],
    material: &'static str,
}

#[derive(Serialize)]
struct Cap {
    polygon: Vec<[f64; 2]>,
    z: f64,
    material: &'static str,
}

#[derive(Serialize)]
struct Body {
    radius_m: f64,
    height_m: f64,
    center_x_m: f64,
    laser_z_m: f64,
    /// The sonar ring, if the robot has one: transducer k faces k × 360°/count counter-clockwise
    /// from the front, on a circle of this radius around (center_x_m, 0).
    sonar: Option<Ring>,
}

#[derive(Serialize)]
struct Ring {
    count: u8,
    ring_radius_m: f64,
    center_x_m: f64,
    cone_deg: f64,
    height_m: f64,
}

#[derive(Serialize)]
struct World<'a> {
    name: &'a str,
    ceiling_m: f64,
    /// The start pose `[x, y, theta]`.
    start: [f64; 3],
    faces: Vec<Face>,
    caps: Vec<Cap>,
    robot: Body,
}

/// Writes `scenario`'s world (`map` is its map) and robot body as JSON.
pub fn write_world_json(path: &Path, scenario: &Scenario, map: &WorldMap) -> std::io::Result<()> {
    let body = &scenario.robot.body;
    let start = scenario.world.start;
    let world = World {
        name: &scenario.world.name,
        ceiling_m: map.ceiling(),
        start: [start.x, start.y, start.theta],
        faces: map
            .faces()
            .iter()
            .map(|f| Face {
                a: f.a,
                b: f.b,
                z: f.z,
                material: f.material.name(),
            })
            .collect(),
        caps: map
            .caps()
            .iter()
            .map(|c| Cap {
                polygon: c.polygon.clone(),
                z: c.z,
                material: c.material.name(),
            })
            .collect(),
        robot: Body {
            radius_m: body.radius_m.get(),
            height_m: body.height_m.get(),
            center_x_m: body.center_x_m.get(),
            laser_z_m: scenario.robot.laser.z_m.get(),
            sonar: scenario.robot.sonar.as_ref().map(|s| Ring {
                count: s.count,
                ring_radius_m: s.ring_radius_m.get(),
                center_x_m: s.center_x_m.get(),
                cone_deg: s.cone_deg.get(),
                height_m: s.height_m.get(),
            }),
        },
    };
    let mut text = serde_json::to_string(&world)?;
    text.push('\n');
    robot::logs::write_file(path, text)
}
