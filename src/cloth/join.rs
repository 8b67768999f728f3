//! Several cloths as one: the pieces of a scene stepped together, so that
//! they meet through self-collision, which keeps any two parts of one cloth
//! apart, and share the solver, its contacts and its rapier coupling.

use std::sync::Arc;

use super::cloth::{next_mass_revision, Cloth};
use super::particles::Particles;
use super::springs::{Spring, Springs};
use super::topology::{GridPiece, Topology};
use crate::error::ClothError;

impl Cloth {
    /// One cloth made of `pieces`, in order: the first piece's particles
    /// keep their indices, each next piece's follow those before it (its
    /// particle `i` becomes `i` plus the particles of the pieces before).
    /// Springs, triangles, texture coordinates, masses and pins come with
    /// their piece; the material, physical parameters and time are the
    /// first piece's. The pieces share no spring, so they move apart freely
    /// and, with self-collision on, never pass through each other.
    ///
    /// Every piece must have the first piece's material (one cloth has one
    /// material); a joined cloth is no grid ([`Cloth::grid`] is `None`),
    /// though its pieces may be ([`Topology::grid_pieces`]), and pieces of
    /// one grid shape are swept as one grid of their rows stacked
    /// ([`Topology::lane_grid`]).
    pub fn join(pieces: Vec<Cloth>) -> Result<Cloth, ClothError> {
        let mut pieces = pieces.into_iter();
        let Some(first) = pieces.next() else {
            return Err(ClothError::InvalidTopology {
                what: "cloth",
                index: 0,
                reason: "nothing to join: no cloth given".into(),
            });
        };
        let rest: Vec<Cloth> = pieces.collect();
        if rest.is_empty() {
            return Ok(first);
        }
        let total: usize =
            first.particle_count() + rest.iter().map(Cloth::particle_count).sum::<usize>();
        if total > u32::MAX as usize {
            return Err(ClothError::GridTooLarge {
                cols: total,
                rows: 1,
                max: u32::MAX as usize,
            });
        }
        for (k, piece) in rest.iter().enumerate() {
            if piece.material != first.material {
                return Err(ClothError::InvalidTopology {
                    what: "cloth",
                    index: k + 1,
                    reason: format!(
                        "its material ({}) differs from the first cloth's ({}): the cloths \
                         joined into one share a material",
                        piece.material.name, first.material.name
                    ),
                });
            }
        }
        let mut particles = Particles::default();
        let (mut springs, mut triangles, mut uvs) = (Vec::new(), Vec::new(), Vec::new());
        let mut grids = Vec::new();
        for piece in std::iter::once(&first).chain(&rest) {
            let offset = particles.len() as u32;
            // Its grids, where they now lie: self-collision skips the
            // quiet parts of grids (`collision/patches.rs`).
            grids.extend(piece.topology.grid_pieces().map(|g| GridPiece {
                first_particle: g.first_particle + offset as usize,
                first_triangle: g.first_triangle + triangles.len(),
                grid: g.grid,
            }));
            let p = &piece.particles;
            particles.x.extend_from_slice(&p.x);
            particles.v.extend_from_slice(&p.v);
            particles.x_prev.extend_from_slice(&p.x_prev);
            particles.mass.extend_from_slice(&p.mass);
            particles.inv_mass.extend_from_slice(&p.inv_mass);
            springs.extend(piece.springs().iter().map(|s| Spring {
                a: s.a + offset,
                b: s.b + offset,
                ..s
            }));
            triangles.extend(piece.triangles().iter().map(|t| t.map(|i| i + offset)));
            uvs.extend_from_slice(piece.uvs());
        }
        Ok(Cloth {
            particles,
            topology: Arc::new(Topology {
                springs: Springs::from_list(springs),
                triangles,
                uvs,
                grid: None,
                split_from: None,
                splits: Vec::new(),
                pieces: grids,
            }),
            material: first.material.clone(),
            params: first.params.clone(),
            time: first.time,
            mass_revision: next_mass_revision(),
        })
    }
}
