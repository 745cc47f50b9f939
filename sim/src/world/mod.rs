//! The world the twin's robot moves in: the 2.5D map of surfaces (walls, boxes and tables with
//! heights, the floor and the ceiling), with ray casts for the sensors and distance queries for
//! the checks and the pictures.

mod map;

pub use map::{Cap, Face, Hit, PointKind, Surface, WorldMap, point_segment_distance};
