//! The world the twin's robot moves in: the 2.5D map of surfaces (walls, boxes and tables with
//! heights, the floor and the ceiling), with ray casts for the sensors, distance queries for the
//! checks and the pictures, and the scores of a 3D model against the true surfaces ([`score`]).

pub mod clutter;
mod fan;
mod index;
mod map;
pub mod raster;
pub mod score;
mod walk;

pub use fan::{FAN_MAX_FACES, FanCast, PlaneFan};
pub use index::SurfaceId;
pub use map::{Cap, Face, Hit, PointKind, Surface, WorldMap, point_segment_distance};
