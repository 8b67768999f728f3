//! The cloth model, as data: particles, topology (springs, triangles, grid),
//! material, pins and the physical parameters of its world. Nothing here
//! steps a cloth; the solver does (`crate::solver`).

mod builder;
// The module of the `Cloth` type itself, beside the parts it is made of.
#[allow(clippy::module_inception)]
mod cloth;
mod energy;
mod join;
mod material;
mod mesh;
mod particles;
mod physics;
mod pins;
mod split;
mod springs;
mod topology;

pub use builder::{ClothBuilder, MassSpec};
pub use cloth::Cloth;
pub use energy::Energy;
pub use material::{Material, SpringParams, WOVEN_STRETCH_LIMIT};
pub use mesh::ClothMesh;
pub use particles::Particles;
pub use physics::{PhysicsParams, Wind};
pub use pins::PinPreset;
pub use split::ParticleSplit;
pub(crate) use split::TopologyEdit;
pub use springs::{Spring, SpringKind, Springs};
pub use topology::{Grid, GridPiece, LaneGrid, Topology};
