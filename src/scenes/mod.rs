//! Scenes: the catalogue of canonical scenes (docs/SCENES.md), the
//! description every scene is built from and that scene files hold, the
//! options a user overrides, a scene at run time (a cloth with obstacles, or
//! with a rapier world), and runs measured frame by frame.

mod catalogue;
pub mod desc;
mod error;
#[cfg(feature = "scene-files")]
pub mod file;
#[cfg(feature = "scene-files")]
pub mod mesh_file;
mod options;
mod run;
mod world;

pub use catalogue::{curtain_ball_z, SceneKind};
pub use desc::{
    AttachmentDesc, BodyDesc, BodyKind, ClothDesc, CutDesc, MaterialDesc, ObstacleDesc, PinsDesc,
    Placement, SceneDesc, ShapeDesc, Waypoint, CLOTH_MASS, FRAME_DT, THICKNESS,
};
pub use error::SceneError;
pub use options::{SceneOptions, SolverTuning};
pub use run::{run, run_with, RunMetrics, Series};
pub use world::{RapierSide, Scene};
