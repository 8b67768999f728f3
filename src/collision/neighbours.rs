//! Which particles of a cloth are neighbours in its rest mesh: a particle
//! and a triangle are *near* when the particle is a corner of the triangle
//! or is joined by a spring (stretch, shear or bend) to one of its corners
//! (on a grid, every particle within two cells), and *adjacent* when it is
//! a corner or shares a triangle edge with one. Self-collision leaves a
//! triangle's corners to the springs, and off a grid its adjacent
//! particles too ([`MeshNeighbours::left_to_springs`]; on a single grid,
//! the smooth sheet around each triangle as well); the self-intersection
//! count skips near ones. Also the triangles' edges, once each: those of
//! one triangle (the border) and those between two, with their two
//! triangles.

use crate::cloth::{SpringKind, Topology};
use crate::math::Vector;

/// Flat adjacency lists of a topology (compressed rows, sorted).
#[derive(Debug, Default, Clone)]
pub(crate) struct MeshNeighbours {
    /// Per particle: where its spring partners start in `joined` (one more
    /// entry than particles).
    joined_start: Vec<u32>,
    /// Spring partners, ascending per particle.
    joined: Vec<u32>,
    /// Per particle: where its partners along triangle edges start in
    /// `ring` (one more entry than particles).
    ring_start: Vec<u32>,
    /// Partners along triangle edges (the one-ring), ascending per particle.
    ring: Vec<u32>,
    /// Per particle `i`: where the far ends `j > i` of its triangle edges
    /// start in `edges` (one more entry than particles).
    edge_start: Vec<u32>,
    /// Far ends of triangle edges, ascending per particle.
    edges: Vec<u32>,
    /// The longest stretch or shear spring's rest length (m): about a
    /// triangle's longest edge.
    longest: f32,
    /// The cloth's border edges (lower index first), ascending.
    border_edges: Vec<[u32; 2]>,
    /// The edges between two triangles (lower index first), ascending.
    inner_edges: Vec<[u32; 2]>,
    /// The two triangles of each of `inner_edges`.
    inner_faces: Vec<[u32; 2]>,
    /// For a grid cloth: each particle's place in the rest shape (m, along
    /// a row and along a column), from which rest distances follow; empty
    /// off a grid.
    rest: Vec<[f32; 2]>,
    /// Per particle: of a grid (the cloth's, or a joined piece's).
    on_grid: Vec<bool>,
    /// What the lists were made from.
    made_for: Option<TopologyKey>,
}

/// What lists made from a topology of some particles are kept by: the
/// topology's address, the particle, spring and triangle counts, and a
/// checksum of the triangles' corners and the grid pieces. The address
/// and counts alone let another cloth's topology of as many particles,
/// springs and triangles, made where a dropped one was, reuse its lists
/// (a 32 × 48 grid after a 48 × 32).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct TopologyKey {
    address: usize,
    particles: usize,
    springs: usize,
    triangles: usize,
    checksum: u32,
}

impl TopologyKey {
    /// The key of `topology` on `particles` particles: a pass over its
    /// triangles.
    pub fn of(topology: &Topology, particles: usize) -> TopologyKey {
        let corners = topology
            .triangles
            .iter()
            .enumerate()
            // A sum of mixed terms, not a chain: it runs as vectors.
            .map(|(k, &[a, b, c])| {
                (a ^ b.rotate_left(11) ^ c.rotate_left(22) ^ k as u32).wrapping_mul(0x9E37_79B1)
            })
            .fold(0u32, u32::wrapping_add);
        let pieces = topology.grid_pieces().fold(0u32, |sum, piece| {
            let words = [piece.first_particle, piece.grid.cols, piece.grid.rows];
            words
                .into_iter()
                .fold(sum, |s, w| (s ^ w as u32).wrapping_mul(0x0100_0193))
        });
        TopologyKey {
            address: topology as *const Topology as usize,
            particles,
            springs: topology.springs.len(),
            triangles: topology.triangles.len(),
            checksum: corners ^ pieces.rotate_left(7),
        }
    }

    /// The particles the key is of.
    pub fn particles(self) -> usize {
        self.particles
    }
}

impl MeshNeighbours {
    /// Makes the lists for `topology` of `n` particles, unless they were
    /// made for it already.
    pub fn update(&mut self, topology: &Topology, n: usize) {
        self.update_for(topology, TopologyKey::of(topology, n));
    }

    /// [`Self::update`] with the topology's key, `key` (of `topology`).
    pub fn update_for(&mut self, topology: &Topology, key: TopologyKey) {
        if self.made_for == Some(key) {
            return;
        }
        let n = key.particles;
        let springs = &topology.springs;
        let pairs = springs
            .a
            .iter()
            .zip(&springs.b)
            .flat_map(|(&a, &b)| [(a, b), (b, a)]);
        (self.joined_start, self.joined) = compressed(n, pairs);
        let edges = topology.triangles.iter().flat_map(|t| {
            [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])].map(|(a, b)| (a.min(b), a.max(b)))
        });
        (self.edge_start, self.edges) = compressed(n, edges.clone());
        (self.ring_start, self.ring) = compressed(n, edges.flat_map(|(a, b)| [(a, b), (b, a)]));
        // Each triangle edge with its triangle, by edge: an edge met once
        // is a border edge, twice an inner one (more often, neither).
        let mut all: Vec<([u32; 2], u32)> = topology
            .triangles
            .iter()
            .enumerate()
            .flat_map(|(t, c)| {
                [(c[1], c[2]), (c[2], c[0]), (c[0], c[1])]
                    .map(|(a, b)| ([a.min(b), a.max(b)], t as u32))
            })
            .collect();
        all.sort_unstable();
        self.border_edges.clear();
        self.inner_edges.clear();
        self.inner_faces.clear();
        for run in all.chunk_by(|a, b| a.0 == b.0) {
            match run {
                [(edge, _)] => self.border_edges.push(*edge),
                [(edge, t0), (_, t1)] => {
                    self.inner_edges.push(*edge);
                    self.inner_faces.push([*t0, *t1]);
                }
                _ => {}
            }
        }
        let spacing = topology.grid.and_then(|g| {
            let rest = |a: usize, b: usize| {
                (0..springs.len())
                    .find(|&s| (springs.a[s], springs.b[s]) == (a as u32, b as u32))
                    .map(|s| springs.rest[s])
            };
            Some((g.cols, rest(0, 1)?, rest(0, g.cols)?))
        });
        self.rest = match spacing {
            Some((cols, dx, dy)) => (0..n)
                .map(|p| [(p % cols) as f32 * dx, (p / cols) as f32 * dy])
                .collect(),
            None => Vec::new(),
        };
        self.longest = springs
            .range(SpringKind::Stretch)
            .chain(springs.range(SpringKind::Shear))
            .map(|s| springs.rest[s])
            .fold(0.0f32, f32::max);
        self.on_grid.clear();
        self.on_grid.resize(n, false);
        for piece in topology.grid_pieces() {
            let particles = piece.particles();
            let end = particles.end.min(n);
            if let Some(on) = self.on_grid.get_mut(particles.start.min(end)..end) {
                on.fill(true);
            }
        }
        self.made_for = Some(key);
    }

    /// True when particle `p` and the triangle `tri` are neighbours.
    pub fn near(&self, p: u32, tri: [u32; 3]) -> bool {
        if tri.contains(&p) {
            return true;
        }
        let joined = self.joined_to(p);
        tri.iter().any(|c| joined.binary_search(c).is_ok())
    }

    /// True when particle `p` is a corner of triangle `tri` or shares a
    /// triangle edge with one of its corners: the pairs self-collision
    /// leaves to the springs. Closer than [`MeshNeighbours::near`], which
    /// spares bend partners too (two cells on a grid): a crumple that
    /// folds within two cells is then still kept from crossing itself.
    pub fn adjacent(&self, p: u32, tri: [u32; 3]) -> bool {
        if tri.contains(&p) {
            return true;
        }
        let ring = row(&self.ring_start, &self.ring, p);
        tri.iter().any(|c| ring.binary_search(c).is_ok())
    }

    /// True when self-collision leaves particle `p` and triangle `tri` to
    /// the springs: `p` is a corner of `tri`, or `tri` lies off a grid and
    /// `p` is [`Self::adjacent`] to it. On a grid, a particle of a
    /// corner's one-ring lies a whole cell beyond the triangle's nearer
    /// edge in the rest shape (the altitude onto a cell's diagonal is at
    /// least its shorter side over √2), never within the rim the pass
    /// acts in (at most a quarter of the shortest edge): its pair acts
    /// only where the cloth folds over at that corner, as a border's pleat
    /// two cells wide did, crossing the `stack` at 20 substeps with no
    /// pair to stop it. Off a grid, a one-ring particle of a sliver
    /// triangle may lie within the rim of a flat cloth: left to the
    /// springs.
    pub fn left_to_springs(&self, p: u32, tri: [u32; 3]) -> bool {
        if tri.contains(&p) {
            return true;
        }
        let on_grid = |c: u32| self.on_grid.get(c as usize).copied().unwrap_or(false);
        !tri.iter().all(|&c| on_grid(c)) && self.adjacent(p, tri)
    }

    /// The longest stretch or shear spring's rest length, in metres.
    pub fn longest(&self) -> f32 {
        self.longest
    }

    /// The cloth's border edges: those of one triangle only.
    pub fn border_edges(&self) -> &[[u32; 2]] {
        &self.border_edges
    }

    /// The edges between two triangles (lower index first, ascending), and
    /// the two triangles of each.
    pub fn inner_edges(&self) -> (&[[u32; 2]], &[[u32; 2]]) {
        (&self.inner_edges, &self.inner_faces)
    }

    /// The particles of the same smooth sheet as triangle `tri`: on a
    /// grid cloth, those closer than `radius` metres to one of its corners
    /// in the rest shape (none off a grid). Such a particle can only come
    /// within the thickness of the triangle through a fold tighter than
    /// about `radius / π`, which the bending springs resist.
    pub fn sheet(&self, tri: [u32; 3], radius: f32) -> Sheet<'_> {
        let at = |c: u32| self.rest.get(c as usize).copied().unwrap_or([f32::NAN; 2]);
        Sheet {
            rest: &self.rest,
            corners: tri.map(at),
            // Off a grid `rest` is empty and nothing is held.
            radius2: radius * radius,
        }
    }

    /// The longest triangle edge at positions `x` (m; 0 with none, not a
    /// number when a position is not, and infinite when `x` holds fewer
    /// particles than the edges' ends).
    pub fn longest_at(&self, x: &[Vector]) -> f32 {
        let mut longest = 0.0f32;
        for p in 0..self.edge_start.len().saturating_sub(1) {
            for &q in self.edges_from(p as u32) {
                let (Some(&a), Some(&b)) = (x.get(p), x.get(q as usize)) else {
                    return f32::INFINITY;
                };
                let length = (b - a).length_squared();
                if length.is_nan() {
                    return f32::NAN;
                }
                longest = longest.max(length);
            }
        }
        longest.sqrt()
    }

    /// The particles joined to `p` by a spring, ascending.
    pub fn joined_to(&self, p: u32) -> &[u32] {
        row(&self.joined_start, &self.joined, p)
    }

    /// The partners of `p` along triangle edges (its one-ring), ascending.
    pub fn ring(&self, p: u32) -> &[u32] {
        row(&self.ring_start, &self.ring, p)
    }

    /// The far ends `j > p` of the triangle edges at `p`, ascending.
    pub fn edges_from(&self, p: u32) -> &[u32] {
        row(&self.edge_start, &self.edges, p)
    }

    /// The triangle edges, once each: how many.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Where the triangle edge `[p, q]` (`p < q`) is among the edges (below
    /// [`Self::edge_count`]), if it is one.
    pub fn edge_index(&self, [p, q]: [u32; 2]) -> Option<usize> {
        let start = *self.edge_start.get(p as usize)? as usize;
        Some(start + self.edges_from(p).binary_search(&q).ok()?)
    }
}

/// Row `p` of compressed rows (`start` has one more entry than rows);
/// empty for a row out of range.
fn row<'a>(start: &[u32], list: &'a [u32], p: u32) -> &'a [u32] {
    let p = p as usize;
    match (start.get(p), start.get(p + 1)) {
        (Some(&s), Some(&e)) => &list[s as usize..e as usize],
        _ => &[],
    }
}

/// Compressed rows of the pairs `(row, column)` over `n` rows: sorted and
/// without repeats; pairs out of range are dropped.
fn compressed(n: usize, pairs: impl Iterator<Item = (u32, u32)>) -> (Vec<u32>, Vec<u32>) {
    let mut list: Vec<(u32, u32)> = pairs
        .filter(|&(a, b)| (a as usize) < n && (b as usize) < n && a != b)
        .collect();
    list.sort_unstable();
    list.dedup();
    let mut start = vec![0u32; n + 1];
    for &(a, _) in &list {
        start[a as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    (start, list.into_iter().map(|(_, b)| b).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;

    /// Another cloth of as many particles, springs and triangles whose
    /// topology lies where the last one's did (a 6 × 8 grid after an 8 ×
    /// 6) gets lists of its own: the key's checksum tells them apart.
    #[test]
    fn a_topology_of_the_same_counts_at_the_same_address_is_listed_again() {
        let (wide, tall) = (
            ClothBuilder::new(8, 6).build().unwrap(),
            ClothBuilder::new(6, 8).build().unwrap(),
        );
        let n = wide.particle_count();
        let first = TopologyKey::of(wide.topology(), n);
        // The second as if made where the first was.
        let second = TopologyKey {
            address: first.address,
            ..TopologyKey::of(tall.topology(), n)
        };
        assert_eq!(
            (first.particles, first.springs, first.triangles),
            (second.particles, second.springs, second.triangles)
        );
        assert_ne!(first, second);
        let mut nb = MeshNeighbours::default();
        nb.update_for(wide.topology(), first);
        // Particle 1's partner below it: 9 in rows of eight, 7 in rows of
        // six.
        assert!(nb.joined_to(1).contains(&9) && !nb.joined_to(1).contains(&7));
        nb.update_for(tall.topology(), second);
        let mut fresh = MeshNeighbours::default();
        fresh.update(tall.topology(), n);
        for p in 0..n as u32 {
            assert_eq!(nb.joined_to(p), fresh.joined_to(p), "particle {p}");
        }
    }

    /// A triangle's corners are left to the springs everywhere; its
    /// one-ring only off a grid: a joined grid's piece leaves it to the
    /// pairs, a mesh of the same quads to the springs.
    #[test]
    fn the_springs_keep_a_triangles_one_ring_off_a_grid_only() {
        use crate::cloth::{Cloth, ClothMesh, MassSpec, Material};
        let sheet = ClothBuilder::new(5, 5).build().unwrap();
        let joined = Cloth::join(vec![sheet.clone(); 2]).unwrap();
        let faces = (0..4u32)
            .flat_map(|r| (0..4u32).map(move |c| r * 5 + c))
            .map(|i| vec![i, i + 5, i + 6, i + 1])
            .collect();
        let mesh = ClothMesh {
            positions: sheet.positions().to_vec(),
            faces,
            uvs: Vec::new(),
        };
        let mesh = Cloth::from_mesh(&mesh, Material::cotton(), MassSpec::FromDensity).unwrap();
        for (cloth, on_grid) in [(&joined, true), (&mesh, false)] {
            let mut nb = MeshNeighbours::default();
            nb.update(cloth.topology(), cloth.particle_count());
            // A triangle at particle 6 without particle 7, its partner
            // along the row.
            let &tri = cloth
                .topology()
                .triangles
                .iter()
                .find(|t| t.contains(&6) && !t.contains(&7))
                .expect("a triangle at 6");
            assert!(nb.adjacent(7, tri));
            assert!(nb.left_to_springs(tri[0], tri));
            assert_eq!(nb.left_to_springs(7, tri), !on_grid, "on a grid: {on_grid}");
            // Particles beyond the one-ring: the pairs' either way.
            assert!(!nb.left_to_springs(24, tri));
        }
    }

    /// On a grid: the corner's partners are its stretch, shear and bend
    /// springs' far ends; a particle three cells away is no neighbour of a
    /// corner triangle, a bend partner's triangle near but not adjacent;
    /// the triangle edges are each listed once.
    #[test]
    fn grid_neighbours_and_edges() {
        let cloth = ClothBuilder::new(5, 5).build().unwrap();
        let mut nb = MeshNeighbours::default();
        nb.update(cloth.topology(), cloth.particle_count());
        // Corner (0, 0): right (1), down (5), diagonal (6), two right (2), two down (10).
        assert_eq!(nb.joined_to(0), &[1, 2, 5, 6, 10]);
        let tri = cloth.triangles()[0];
        assert!(nb.near(tri[0], tri));
        assert!(nb.near(12, [0, 1, 6]), "(2, 2) is (1, 1)'s shear partner");
        assert!(
            !nb.near(18, [0, 1, 6]),
            "(3, 3) is two cells from the triangle's nearest corner"
        );
        // Adjacent is closer: sharing a triangle edge with a corner. (4, 0)
        // is a bend partner of (4, 2) but shares no edge with the triangle
        // (3, 3), (4, 2), (4, 3): near, not adjacent.
        assert!(cloth.triangles().contains(&[18, 22, 23]));
        assert!(nb.near(20, [18, 22, 23]) && !nb.adjacent(20, [18, 22, 23]));
        assert!(
            nb.adjacent(12, [0, 1, 6]),
            "(2, 2) shares an edge with (1, 1)"
        );
        assert!(nb.adjacent(0, [0, 1, 6]) && !nb.adjacent(18, [0, 1, 6]));
        let edges: usize = (0..25).map(|p| nb.edges_from(p).len()).sum();
        // The 4 × 4 cells' outline.
        assert_eq!(nb.border_edges().len(), 16);
        assert!(nb.border_edges().contains(&[0, 1]) && nb.border_edges().contains(&[19, 24]));
        // 4×4 cells of two triangles: 2·5·4 grid edges and 16 diagonals.
        assert_eq!(edges, 2 * 5 * 4 + 16);
        // The rest lie between two triangles, each of which has the edge.
        let (inner, faces) = nb.inner_edges();
        assert_eq!(inner.len() + nb.border_edges().len(), edges);
        assert!(inner.windows(2).all(|w| w[0] < w[1]));
        for (&[a, b], &[t0, t1]) in inner.iter().zip(faces) {
            let tris = cloth.triangles();
            assert!(t0 != t1);
            for t in [t0, t1] {
                assert!(tris[t as usize].contains(&a) && tris[t as usize].contains(&b));
            }
        }
    }
}

/// The particles near a triangle in the rest shape of a grid cloth
/// ([`MeshNeighbours::sheet`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sheet<'a> {
    /// Every particle's place in the rest shape.
    rest: &'a [[f32; 2]],
    /// The triangle's corners' places in the rest shape.
    corners: [[f32; 2]; 3],
    /// The radius squared, in m².
    radius2: f32,
}

impl Sheet<'_> {
    /// True when particle `p` lies within the radius of a corner.
    #[inline]
    pub fn holds(&self, p: u32) -> bool {
        let Some(&[u, v]) = self.rest.get(p as usize) else {
            return false;
        };
        self.corners.iter().any(|&[cu, cv]| {
            let (du, dv) = (u - cu, v - cv);
            du * du + dv * dv < self.radius2
        })
    }
}
