//! What a step's looks and a substep's pass go by.

use crate::cloth::Topology;

/// What a self-collision pass works with.
pub(crate) struct SelfContactParams {
    /// Distance layers keep, in metres.
    pub thickness: f32,
    /// Coulomb friction between layers.
    pub friction: f32,
    /// The substep, in seconds.
    pub h: f32,
}

/// What a step's looks go by: the cloth's `topology` of `particles`, its
/// `revision` (`Cloth::mass_revision`, which changes with its topology),
/// the layers' `thickness` and the `margin` (m).
pub(crate) struct LookBasis<'a> {
    pub topology: &'a Topology,
    pub particles: usize,
    pub revision: u64,
    pub thickness: f32,
    pub margin: f32,
}
