//! Contact planes: each particle that rests on or comes near a still
//! obstacle gets, for one substep, the obstacle's tangent plane at the
//! point nearest to it, moved out by the thickness. A solver that projects
//! its particles onto these half-spaces between its sweeps meets the
//! contacts inside the substep (Macklin et al. 2019, "Small steps"), where
//! springs and contacts converge together, instead of having the collision
//! stage push the particles out after it. The plane is taken where the
//! particle starts the substep, outside the obstacle: a particle the
//! springs pull over a box's edge is held by the face it was on, never
//! pushed out through the other.

use super::obstacle::Obstacle;
use super::stage::CollisionStage;
use crate::math::Vector;

/// One substep's contact planes, as a flat list.
#[derive(Debug, Default)]
pub(crate) struct ContactPlanes {
    /// The particle of each plane.
    pub(crate) particle: Vec<u32>,
    /// Its unit outward normal.
    pub(crate) normal: Vec<Vector>,
    /// Its offset (m): the particle must keep `normal · x ≥ offset`.
    pub(crate) offset: Vec<f32>,
    /// How far (m) the projections pushed it along the normal, summed
    /// over the substep (the normal "impulse" friction is bounded by).
    pub(crate) depth: Vec<f32>,
    /// The obstacle's friction coefficient.
    pub(crate) friction: Vec<f32>,
    /// Per obstacle: whether its contacts are held as planes.
    held: Vec<bool>,
}

impl ContactPlanes {
    /// Removes every plane.
    pub(crate) fn clear(&mut self) {
        self.particle.clear();
        self.normal.clear();
        self.offset.clear();
        self.depth.clear();
        self.friction.clear();
    }

    /// Whether there are none.
    pub(crate) fn is_empty(&self) -> bool {
        self.particle.is_empty()
    }
}

/// How far (m) a particle may lie inside the plane the particle pass found
/// before the plane is looked up afresh where the particle is.
const PLANE_SLACK: f32 = 1.0e-5;

impl CollisionStage {
    /// The contact planes of a substep of `h` seconds for particles at `x`
    /// moving at `v` (their start), into `planes`: one for each free
    /// particle whose nearest obstacle is still and has edges
    /// ([`Obstacle::is_still`], [`Obstacle::has_edges`]), and may be
    /// reached within the substep (its gap over the thickness under twice
    /// the particle's motion at `v` plus the thickness). The nearest
    /// obstacle and its plane are those the particle pass found at the last
    /// resolution, unless the particle has moved inside the plane since:
    /// then the plane is looked up afresh where the particle is. At a
    /// step's `first` substep both are found afresh among the particle's
    /// candidates of the step's cache: the obstacles handed to this step
    /// need not be the last step's, and what the last step's pass found is
    /// scratch, which a solver restored from a snapshot does not have (it
    /// had no planes at that substep, and went on to other bits).
    pub(crate) fn contact_planes(
        &self,
        (x, v, inv_mass): (&[Vector], &[Vector], &[f32]),
        obstacles: &[Obstacle],
        (h, thickness, first): (f32, f32, bool),
        planes: &mut ContactPlanes,
    ) {
        planes.clear();
        planes.held.clear();
        planes
            .held
            .extend(obstacles.iter().map(|o| o.has_edges() && o.is_still()));
        if !planes.held.iter().any(|&held| held) {
            return;
        }
        if first {
            self.first_contact_planes((x, v, inv_mass), obstacles, (h, thickness), planes);
            return;
        }
        if self.nearest.len() != v.len() {
            return;
        }
        for i in 0..v.len() {
            let o = self.nearest[i] as usize;
            // `NONE` and obstacles of another step are out of range.
            if !planes.held.get(o).copied().unwrap_or(false) || inv_mass[i] == 0.0 {
                continue;
            }
            let reach = thickness + 2.0 * v[i].length() * h;
            if self.distance[i] - thickness > reach {
                continue;
            }
            let (mut normal, mut offset) = (self.normal[i], self.surface[i] + thickness);
            // Moved inside the plane since the particle pass (by the edge
            // pass or the stretch hold, perhaps round an edge onto another
            // face): its plane where the particle is now.
            if normal.dot(x[i]) < offset - PLANE_SLACK {
                let Some(hit) = self.tracks.contact(obstacles, o, x[i]) else {
                    continue;
                };
                if hit.signed_distance - thickness > reach {
                    continue;
                }
                (normal, offset) = (hit.normal, hit.normal.dot(hit.point) + thickness);
            }
            planes.push(i, (normal, offset), obstacles[o].friction);
        }
    }

    /// [`Self::contact_planes`] at a step's first substep: each free
    /// particle's nearest obstacle among its cached candidates, where it
    /// is, from the step's state alone.
    fn first_contact_planes(
        &self,
        (x, v, inv_mass): (&[Vector], &[Vector], &[f32]),
        obstacles: &[Obstacle],
        (h, thickness): (f32, f32),
        planes: &mut ContactPlanes,
    ) {
        for i in 0..v.len() {
            if inv_mass[i] == 0.0 {
                continue;
            }
            let reach = thickness + 2.0 * v[i].length() * h;
            let mut nearest = None;
            for &o in self.tracks.cached_of(i) {
                let o = o as usize;
                // Further than a plane would be taken at: not its nearest,
                // or no plane either way.
                if self.tracks.surely_beyond(o, x[i], thickness + reach) {
                    continue;
                }
                let Some(hit) = self.tracks.contact(obstacles, o, x[i]) else {
                    continue;
                };
                if nearest.is_none_or(|(_, d, _)| hit.signed_distance < d) {
                    nearest = Some((o, hit.signed_distance, hit));
                }
            }
            let Some((o, distance, hit)) = nearest else {
                continue;
            };
            // Within the thickness already (a cloth laid on the obstacle
            // by hand; the last step's pass leaves none there): a plane
            // would push it out over one substep, at the speed of the push
            // over the substep (a sheet laid on a ramp took off). The
            // collision stage's pass takes it out without.
            let inside = distance < thickness - PLANE_SLACK;
            if !planes.held.get(o).copied().unwrap_or(false)
                || distance - thickness > reach
                || inside
            {
                continue;
            }
            let plane = (hit.normal, hit.normal.dot(hit.point) + thickness);
            planes.push(i, plane, obstacles[o].friction);
        }
    }
}

impl ContactPlanes {
    /// Adds particle `i`'s plane `(normal, offset)` with the obstacle's
    /// `friction`.
    #[inline]
    fn push(&mut self, i: usize, (normal, offset): (Vector, f32), friction: f32) {
        self.particle.push(i as u32);
        self.normal.push(normal);
        self.offset.push(offset);
        self.depth.push(0.0);
        self.friction.push(friction);
    }
}
