//! 3D reconstruction from the pan-tilt laser (thesis ch. 4, §5.3, App. D): scenes, meshes and
//! merged models. Pure computation: it runs on the real robot's recordings as on the twin's.
//!
//! 1. A **scene** ([`Scene`]) is one scan per tilt position over the tilt range at one pan, kept
//!    as a grid of world points (rows: scans, columns: beams), each reading put in 3D through
//!    the chain of Eq. 4.1 ([`crate::mount`]) with the head's angles its scan carries and the
//!    base's pose at its stamp.
//! 2. A **mesh** ([`Model::add`]) joins four grid neighbours into a quadrilateral or two
//!    triangles when they plausibly lie on one surface ([`MeshRule`]: the thesis's fixed
//!    distance, or the proposed incidence rule), wound to face the laser.
//! 3. A **model** ([`Model`]) merges the scenes of one or more stations, each placed by the
//!    base's pose: from the 2D localisation of the level scans ([`EstimatePlacement`]), from the
//!    odometry, or — on the twin — from the truth.
//!
//! Inside, everything is SI and REP-103 (x forward, y left, z up); the thesis's OpenGL axes (y up,
//! floor in xz, units of 10 cm) appear only where a file is written for its viewer.
//!
//! ```
//! use robot::control::SceneTag;
//! use robot::hardware::{HeadAngles, LaserScan};
//! use robot::mount::{HeadGeometry, LaserMount};
//! use robot::reconstruction::{MeshOptions, Model, Scene, SceneScan};
//! use robot::{Pose2, Stamp};
//! // Three scans of a cylinder 2 m around the laser, tilted 0°, 1° and 2°.
//! let scans: Vec<LaserScan> = (0..3)
//!     .map(|j| {
//!         let mut s = LaserScan::sick_lms_half_degree(Stamp::from_millis(j), vec![2000; 361]);
//!         s.head = Some(HeadAngles { pan: 0.0, tilt: (j as f64).to_radians() });
//!         s
//!     })
//!     .collect();
//! let mount = LaserMount::Head(HeadGeometry::THESIS);
//! let rows: Vec<SceneScan> = scans
//!     .iter()
//!     .map(|scan| SceneScan::mounted(scan, Pose2::IDENTITY, &mount))
//!     .collect();
//! let scene = Scene::build(SceneTag { scene: 0, station: 0 }, &rows).unwrap();
//! let model = Model::build(&[scene], &MeshOptions::default());
//! let ((quads, of), _) = model.counts();
//! assert_eq!(of, 2 * 360);
//! // Near ±90° the beams lie along the tilt axis: the scans' readings there are closer than
//! // App. D's 5 mm minimum, and only those polygons fail.
//! assert!(quads > 9 * of / 10 && quads < of);
//! ```

mod mesh;
mod model;
mod placement;
mod scene;

pub use mesh::{MeshOptions, MeshRule, normal, triangle_area};
pub use model::{Model, SceneStats};
pub use placement::EstimatePlacement;
pub use scene::{Scene, SceneError, SceneScan};
