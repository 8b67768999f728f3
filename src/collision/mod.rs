//! Collision with parry3d shapes: obstacles, point contacts, the particles'
//! contact set, and the collision stage of a step that resolves them.
//!
//! A particle closer to an obstacle than the cloth's thickness is moved to the
//! surface projection plus the thickness along the outward normal; its velocity
//! relative to the surface loses the part going into the surface and its
//! tangential part gets Coulomb friction (unless the solver decided friction
//! itself: [`FrictionPolicy`]). Stretch and shear springs are then sampled so
//! the cloth cannot cut through edges and corners.
//!
//! Self-collision keeps the cloth's own layers a thickness apart
//! ([`SelfContacts`]); [`self_intersections()`] counts where they are not.

mod backing;
pub(crate) mod contact;
mod contact_planes;
mod contact_set;
mod edges;
mod motion_tiles;
mod neighbours;
mod obstacle;
mod one_obstacle;
mod one_obstacle_lanes;
mod particle_pass;
mod patches;
mod response;
mod self_contacts;
mod self_intersections;
mod spatial_hash;
mod stage;
mod stretch_hold;
mod stretch_incidence;
mod tracks;

pub use contact::{contact, penetration_depth, Contact};
pub(crate) use contact_planes::ContactPlanes;
pub use contact_set::{ContactSet, ParticleContact};
pub(crate) use edges::{chords_clear_ball, EDGE_SAMPLES};
pub use obstacle::{DynamicBody, Obstacle, ObstacleImpulse};
pub use response::{respond, FrictionPolicy, Response};
pub use self_contacts::SelfContacts;
pub(crate) use self_contacts::{LookBasis, SelfContactParams, SelfLook};
pub use self_intersections::self_intersections;
pub use stage::CollisionStage;
pub(crate) use stage::ResolveOptions;
pub(crate) use stretch_hold::{any_stretch_over_limit, stop_separating, LIMIT_SLACK};
pub(crate) use stretch_incidence::StretchIncidence;
