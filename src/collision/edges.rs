//! The edge pass: stretch and shear springs kept out of obstacles, so that
//! cloth cannot cut through a cube's edges and corners between its particles.

use parry3d::bounding_volume::Aabb;

use super::obstacle::Obstacle;
use super::stage::CollisionStage;
use crate::cloth::Particles;

/// Where along a spring the edge test samples.
const EDGE_SAMPLES: [f32; 3] = [0.25, 0.5, 0.75];

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
}
