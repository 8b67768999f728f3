//! The math types of parry3d and rapier3d (glam-based, `f32`), so a rapier
//! user passes their own values straight in.

pub use parry3d::math::{Pose, Real, Rotation, Vector};
