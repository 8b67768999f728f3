//! Measures of a cloth among obstacles: how deep it lies inside them and how
//! far it is stretched (what every run reports, docs/SCENES.md).

use crate::cloth::{Cloth, SpringKind};
use crate::collision::{penetration_depth, Obstacle};

/// The deepest any particle lies inside any obstacle's surface, in metres (0 when none is inside).
pub fn max_penetration(cloth: &Cloth, obstacles: &[Obstacle]) -> f32 {
    let mut deepest = 0.0f32;
    for o in obstacles {
        let aabb = o.shape.compute_aabb(&o.pose);
        for &p in cloth.positions() {
            if aabb.contains_local_point(p) {
                deepest = deepest.max(penetration_depth(&*o.shape, &o.pose, p));
            }
        }
    }
    deepest
}

/// The largest `length / rest length - 1` over the stretch springs.
pub fn max_stretch(cloth: &Cloth) -> f32 {
    cloth.max_strain(SpringKind::Stretch)
}
