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

/// The pieces a cloth is in: groups of particles joined through triangles
/// (1 for a whole cloth; a particle in no triangle is a piece of its own).
pub fn pieces(cloth: &Cloth) -> usize {
    let n = cloth.particle_count();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            // Path halving keeps the trees shallow.
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    for t in cloth.triangles() {
        let a = root(&mut parent, t[0]);
        for &u in &t[1..] {
            let b = root(&mut parent, u);
            parent[b as usize] = a;
        }
    }
    (0..n as u32).filter(|&i| root(&mut parent, i) == i).count()
}
