//! Self-collision: particles kept a layer's thickness
//! ([`crate::cloth::Cloth::self_thickness`]) away from the triangles of their
//! own cloth that the springs do not hold them to: not their corners, nor off a
//! grid their neighbours in the rest mesh
//! ([`MeshNeighbours::left_to_springs`](super::neighbours::MeshNeighbours::left_to_springs)),
//! with Coulomb friction between the layers.
//!
//! Found ahead, solved every substep (as the obstacles are): a spatial hash of
//! the particles ([`SpatialHash`](super::spatial_hash::SpatialHash)) gives each
//! triangle the particles within reach of it, `thickness + margin`. A look
//! costs a pass over the triangles, so it is taken again only when it may have
//! missed a pair: whenever two particles may have closed in by more than the
//! margin since the last look (a neighbour list with a skin, as in molecular
//! dynamics), by the smallest of three bounds: the diagonal of the box around
//! the particles' motions, twice the farthest motion from their mean, and the
//! same diagonal for the particles near each other alone, tile by tile
//! ([`MotionTiles`](super::motion_tiles::MotionTiles)); and when the cloth, its
//! thickness or the margin changed. Every substep for a cloth in violent
//! motion, seldom for one at rest or in free fall: a look carries over from
//! step to step (the `stack` at rest looked once a step before, 5 ms of its
//! frame). Where it looked is solver state ([`SelfLook`], in a snapshot); the
//! pairs are scratch, found again from those positions by a solver with fresh
//! scratch, to the same list. The triangles of quiet patches
//! ([`Patches`](super::patches::Patches): a bent sheet that cannot touch
//! itself) are skipped. Each pair keeps the side of the triangle the particle
//! was on a substep before the look (back along its velocity: a layer that
//! crossed within the substep that asked for the look is pushed back). The
//! cloth's border edges are also paired with the other edges near them, so that
//! two borders cannot slip past each other; and so are the edges of sharp folds
//! ([`SHARP_FOLD`](edge_pairs::SHARP_FOLD)), with the edges at the particles
//! paired with their two triangles: a crease's edge and another layer's can
//! pass through each other between particles that each keep the thickness from
//! the other layer's triangles.
//!
//! A look takes the triangles in runs of a few ([`RUN`](look::RUN): a grid's
//! cells along a row), the particles inside the box around a run found once and
//! tested against each triangle eight at a time where the CPU has AVX2.
//!
//! A substep's pass, in pair order (Gauss–Seidel) within each of three
//! parts ([`PassPlane`](pass_plane::PassPlane)): the pairs below a plane
//! across the cloth and those above it on two threads at once, then those
//! across it (the same bits on any number of threads). Where the CPU has AVX2 a vector test
//! of eight pairs at a time passes over those the pass would leave as
//! they are (the pairs of layers apart), with the same bits. For a
//! particle `p` whose projection falls inside
//! triangle `abc` or within a rim outside its edges (where the cloth bends,
//! a particle near a common edge may project outside both triangles;
//! barycentrics `u, v, w`, clamped to the triangle), closer than the
//! thickness `t` along the side's normal `n` (in the rim, a thickness that
//! thins to none at the rim's outer edge, [`rim_taper`](geometry::rim_taper):
//! a particle sliding into the rim is not pushed by half a thickness at
//! once), the constraint
//! `C = (x_p − x_a)·n − t ≥ 0` moves `p` by `w_p s n` and each corner `i` by
//! `−w_i b_i s n`, with `s = −C / (w_p + Σ w_i b_i²)` (the inverse masses
//! weigh who moves; at most half the thickness a pass). Velocities then
//! lose the part of the relative velocity that closes the gap, and Coulomb
//! friction (coefficient μ) takes up to μ times the normal velocity change
//! (that change and the correction over the substep) from the sliding
//! part. No velocity is added: the pass never pumps energy. Edge pairs
//! are kept apart the same way at their closest points; two folds' edges
//! by as much of the thickness as the lesser fold is sharp now
//! ([`fold_share`](edge_pairs::fold_share)), so that a fold the looks
//! pair at one look and not at the next comes and goes gradually. Both
//! thinnings keep the pass continuous in the positions: a layer at rest
//! stays still instead of being kicked back and forth (the `stack` at
//! rest shook by up to 11 mm a frame with steps of half a thickness).

mod contacts;
mod edge_pairs;
mod geometry;
mod lists;
mod look;
mod pair_lanes;
mod pairs;
mod params;
mod pass;
mod pass_plane;
mod points;

pub use self::contacts::SelfContacts;
pub(crate) use self::geometry::{barycentric, is_positive};
pub(crate) use self::pairs::SelfLook;
pub(crate) use self::params::{LookBasis, SelfContactParams};

#[cfg(test)]
mod tests;
