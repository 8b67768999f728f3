//! The edge pass: stretch and shear springs kept out of obstacles, so that
//! cloth cannot cut through a cube's edges and corners between its particles.

use parry3d::bounding_volume::Aabb;

use super::contact_set::NONE;
use super::obstacle::Obstacle;
use super::stage::CollisionStage;
use crate::cloth::Particles;
use crate::math::Vector;

/// Where along a spring the edge test samples (as fractions of it from
/// its first end; the solver's lanes sample there too).
pub(crate) const EDGE_SAMPLES: [f32; 3] = [0.25, 0.5, 0.75];

impl CollisionStage {
    /// Keeps the samples of the spring `a`–`b` at least `margin` outside every obstacle.
    pub(super) fn resolve_spring(
        &mut self,
        p: &mut Particles,
        a: usize,
        b: usize,
        obstacles: &[Obstacle],
        margin: f32,
    ) {
        let (wa, wb) = (p.inv_mass[a], p.inv_mass[b]);
        if wa == 0.0 && wb == 0.0 {
            return;
        }
        // Candidates near the whole spring, once.
        let (xa, xb) = (p.x[a], p.x[b]);
        self.tracks.gather_box(Aabb::new(xa.min(xb), xa.max(xb)));
        for c in 0..self.tracks.candidates.len() {
            let o = self.tracks.candidates[c] as usize;
            if self.surely_clear((a, b), o, &p.x, margin) {
                continue;
            }
            let obstacle = &obstacles[o];
            let pose = self.tracks.poses[o];
            // A ball: the one point of the spring nearest its centre.
            // Other shapes: the samples at 1/4, 1/2 and 3/4.
            let nearest_to_centre;
            let samples: &[f32] = match obstacle.shape.as_ball() {
                Some(_) => {
                    let (ab, ac) = (p.x[b] - p.x[a], pose.translation - p.x[a]);
                    let len2 = ab.length_squared();
                    nearest_to_centre = [if len2 > 0.0 {
                        (ac.dot(ab) / len2).clamp(0.0, 1.0)
                    } else {
                        0.5
                    }];
                    &nearest_to_centre
                }
                None => &EDGE_SAMPLES,
            };
            // A pinned end held inside the obstacle cannot be moved out: the
            // spring cannot be resolved, and pushing its free end would only
            // shove it about.
            let pinned_inside = [(a, wa), (b, wb)].iter().any(|&(i, w)| {
                w == 0.0
                    && self
                        .tracks
                        .contact(obstacles, o, p.x[i])
                        .is_some_and(|c| c.signed_distance < 0.0)
            });
            if pinned_inside {
                continue;
            }
            for &t in samples {
                let sample = p.x[a] * (1.0 - t) + p.x[b] * t;
                // Most samples near a box are clear of it: told without the
                // contact's root and divisions (the same samples pass).
                if self.tracks.contact_beyond(o, sample, margin) {
                    continue;
                }
                let Some(contact) = self.tracks.contact(obstacles, o, sample) else {
                    continue;
                };
                if contact.signed_distance >= margin {
                    continue;
                }
                let (ca, cb) = ((1.0 - t) * wa, t * wb);
                let denom = (1.0 - t) * ca + t * cb;
                if denom <= 0.0 {
                    continue;
                }
                let n = contact.normal;
                let push = n * ((margin - contact.signed_distance) / denom);
                for (i, w) in [(a, ca), (b, cb)] {
                    if w == 0.0 {
                        continue;
                    }
                    p.x[i] += push * w;
                    if !std::mem::replace(&mut self.edge_moved[i], true) {
                        self.moved.push(i as u32);
                    }
                    let surface_v = self.tracks.surface_velocity_of(obstacles, o, p.x[i]);
                    let vn = (p.v[i] - surface_v).dot(n);
                    if vn < 0.0 {
                        let dv = -n * vn;
                        p.v[i] += dv;
                        let j = -dv * p.mass[i];
                        let imp = &mut self.tracks.impulses[o];
                        imp.linear += j;
                        imp.angular_about_origin += p.x[i].cross(j);
                    }
                }
            }
        }
    }

    /// True when no stretch or shear spring can come within half the
    /// `thickness` of the obstacles between its ends, whatever its ends'
    /// neighbours: the one obstacle is a ball, every particle is at least
    /// the thickness out of it (the particle pass saw to the free ones; the
    /// caller checks the pinned ones), and no spring is longer than
    /// `longest_edge` plus twice the farthest a particle has `drift`ed
    /// since (m). A chord of length `l` with both ends `R + t` from a
    /// ball's centre passes no nearer than `√((R + t)² − l²/4)`: on the
    /// drape's ball no spring was ever sampled, and looking for them was
    /// an eighth of its frame (measured).
    pub(super) fn springs_clear_one_ball(&self, drift: f32, thickness: f32) -> bool {
        let Some(radius) = self.tracks.one_ball() else {
            return false;
        };
        chords_clear_ball(radius, thickness, self.longest_edge + 2.0 * drift)
    }

    /// True when the spring `a`–`b` surely stays `margin` metres outside
    /// obstacle `o`: both ends are nearest to it, it is convex, and the
    /// larger of its signed distance's tangent lines at the two ends (what
    /// the particle pass found there: distance and normal) stays beyond
    /// the margin. A convex shape's signed distance is convex along the
    /// spring, so it never dips below those lines; at a box's edge the two
    /// lines are its two faces, which is where the samples would have
    /// found it.
    fn surely_clear(&self, (a, b): (usize, usize), o: usize, x: &[Vector], margin: f32) -> bool {
        let o32 = o as u32;
        if o32 == NONE
            || self.nearest[a] != o32
            || self.nearest[b] != o32
            || !self.tracks.is_convex(o)
        {
            return false;
        }
        let ab = x[b] - x[a];
        let (da, db) = (self.distance[a], self.distance[b]);
        let (sa, sb) = (self.normal[a].dot(ab), self.normal[b].dot(ab));
        tangent_bound([da, sa], [db, sb]).is_some_and(|least| least >= margin)
    }
}

/// Whether no segment of length at most `longest` (m) with both ends at
/// least `thickness` (m) out of a ball of `radius` (m) comes within half
/// the thickness of it: it passes no nearer the centre than
/// `√((r + t)² − l²/4)`, which must be at least `r + t/2`. False for a
/// length that is not finite.
pub(crate) fn chords_clear_ball(radius: f32, thickness: f32, longest: f32) -> bool {
    let (out, margin) = (radius + thickness, radius + 0.5 * thickness);
    longest.is_finite() && longest * longest <= 4.0 * (out * out - margin * margin)
}

/// The least over `t` in `[0, 1]` of `max(da + t sa, db − (1 − t) sb)`:
/// the larger of two tangent lines of a convex function with values `da`,
/// `db` and slopes `sa`, `sb` at the ends of `[0, 1]`, a lower bound of
/// the function there. `None` when an input is not finite.
fn tangent_bound([da, sa]: [f32; 2], [db, sb]: [f32; 2]) -> Option<f32> {
    if !(da.is_finite() && sa.is_finite() && db.is_finite() && sb.is_finite()) {
        return None;
    }
    let larger = |t: f32| (da + t * sa).max(db - (1.0 - t) * sb);
    let mut least = larger(0.0).min(larger(1.0));
    if sa != sb {
        // Where the two lines cross.
        let t = (db - sb - da) / (sa - sb);
        if t > 0.0 && t < 1.0 {
            least = least.min(larger(t));
        }
    }
    Some(least)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound is the least of the larger line, checked on a fine grid;
    /// at a box's edge (a flat top, a vertical side) it is the wedge.
    #[test]
    fn the_tangent_bound_is_the_least_of_the_larger_line() {
        let cases = [
            ([0.02, -0.03], [0.02, 0.03]),
            ([0.01, 0.5], [0.3, 0.1]),
            ([0.05, -0.2], [-0.1, -0.4]),
            ([0.02, 0.0], [0.02, 0.0]),
        ];
        for (a, b) in cases {
            let bound = tangent_bound(a, b).unwrap();
            let least = (0..=10_000)
                .map(|k| {
                    let t = k as f32 / 10_000.0;
                    (a[0] + t * a[1]).max(b[0] - (1.0 - t) * b[1])
                })
                .fold(f32::INFINITY, f32::min);
            assert!(
                (bound - least).abs() < 1e-5,
                "{a:?} {b:?}: {bound} vs {least}"
            );
        }
        assert_eq!(tangent_bound([f32::NAN, 0.0], [0.0, 0.0]), None);
    }
}
