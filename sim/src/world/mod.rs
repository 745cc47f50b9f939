//! The world the twin's robot moves in: the 2.5D map of surfaces (walls, boxes and tables with
//! heights, the floor and the ceiling), with ray casts for the sensors, distance queries for the
//! checks and the pictures, and the scores of a 3D model against the true surfaces ([`score`]).

pub mod clutter;
mod cone;
mod fan;
mod index;
mod map;
pub mod raster;
pub mod score;
mod walk;

pub use cone::Beyond;
pub use fan::{FAN_MAX_FACES, FanCast, FanColumns, PlaneFan};
pub use index::SurfaceId;
pub use map::{Cap, Face, Hit, PointKind, PointKinds, Surface, WorldMap, point_segment_distance};

/// Per-cell lists packed into one: cell `k`'s items are `items[starts[k]..starts[k + 1]]`.
fn packed<T>(lists: Vec<Vec<T>>) -> (Vec<u32>, Vec<T>) {
    let mut starts = Vec::with_capacity(lists.len() + 1);
    let mut items = Vec::new();
    starts.push(0);
    for list in lists {
        items.extend(list);
        starts.push(items.len() as u32);
    }
    (starts, items)
}
