//! Collision with parry3d shapes: obstacles, point contacts, and their resolution.
//!
//! A particle closer to an obstacle than the cloth's thickness is moved to the
//! surface projection plus the thickness along the outward normal; its velocity
//! relative to the surface loses the part going into the surface and its
//! tangential part gets Coulomb friction. Stretch and shear springs are then
//! sampled at 1/4, 1/2 and 3/4 of their length so the cloth cannot cut through
//! edges and corners.

mod contact;
mod obstacle;
mod resolve;
mod response;

pub use contact::{contact, penetration_depth, Contact};
pub use obstacle::{DynamicBody, Obstacle, ObstacleImpulse};
pub(crate) use resolve::Collider;
pub(crate) use response::Response;
