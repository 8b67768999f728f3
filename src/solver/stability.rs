//! Stability limits of the explicit integrators: the largest substep each
//! takes on a cloth, from Gershgorin bounds on its stiffness and damping.

use super::grid_chains;
use super::integrator::Integrator;
use super::settings::SolverSettings;
use crate::cloth::{Cloth, SpringKind};

/// Upper bounds on the squared highest angular frequency (1/s²) and on the
/// highest damping rate (1/s) of the cloth, by Gershgorin's theorem: the
/// largest, over the free particles, of twice the stiffness (damping) of
/// the springs that meet there over the particle's mass. Per particle,
/// because a grid's border particles carry less cloth than the inner ones
/// but fewer springs too. Allocates nothing.
pub fn stiffness_bounds(cloth: &Cloth) -> (f32, f32) {
    let springs = cloth.springs();
    let inv_mass = cloth.inverse_masses();
    let sums = |degree: &[u32; 3]| spring_sums(cloth, degree);
    let (mut k, mut c) = (0.0f32, 0.0f32);
    if springs.degree.is_empty() && !springs.is_empty() {
        // A snapshot from before the degrees were kept: the most springs
        // of each kind at any particle, over the lightest free mass.
        let w = inv_mass.iter().copied().fold(0.0f32, f32::max);
        let (ks, cs) = sums(&springs.max_degree);
        (k, c) = (ks * w, cs * w);
    }
    for (degree, &w) in springs.degree.iter().zip(inv_mass) {
        let (ks, cs) = sums(degree);
        (k, c) = (k.max(ks * w), c.max(cs * w));
    }
    (2.0 * k, 2.0 * c + cloth.params.air_drag)
}

/// The stiffness bound (1/s²) the small-steps solver's substep follows: as
/// [`stiffness_bounds`], but with the mean free mass for every particle's.
/// Its sweeps are stable at any step; the substep sets how stiff the bulk
/// of the cloth is, not what a light particle at its border needs.
fn bulk_stiffness(cloth: &Cloth) -> f32 {
    let springs = cloth.springs();
    let (mut free, mut mass) = (0u32, 0.0f64);
    for (&m, &w) in cloth.masses().iter().zip(cloth.inverse_masses()) {
        if w != 0.0 {
            free += 1;
            mass += m as f64;
        }
    }
    if free == 0 {
        return 0.0;
    }
    let (k, _) = spring_sums(cloth, &springs.max_degree);
    2.0 * k * (free as f64 / mass) as f32
}

/// Stiffness and damping (N/m, N·s/m) of the springs at a particle with
/// `degree` springs of each kind, of the cloth's material.
fn spring_sums(cloth: &Cloth, degree: &[u32; 3]) -> (f32, f32) {
    let (mut k, mut c) = (0.0f32, 0.0f32);
    for (kind, &d) in SpringKind::ALL.iter().zip(degree) {
        let sp = cloth.material.params(*kind);
        k += sp.stiffness * d as f32;
        c += sp.damping * d as f32;
    }
    (k, c)
}

/// How many times the symplectic stability limit the small-steps solver's
/// automatic substep is. It is stable at any step; what the substep buys is
/// stiffness: a cloth at rest is held by sweeps that must pass each
/// substep's pull of gravity along the cloth, and with too few substeps it
/// rests stretched. Measured on a 48×48 cotton tablecloth at rest on a
/// table (2 sweeps a substep, a stretch limit of 4 passes): 5.9–6.1%
/// stretch at 1.5 times the limit, 3.4–4.2% at 1 (symplectic Euler: 3.7%).
/// Since the grid's limit makes more passes, the later ones only over
/// the springs still moving (`grid_sweep::LIMIT_PASSES`), the woven
/// presets' landings stay under 5% with fewer substeps; 1.25 keeps five
/// boxes dropped on a canvas sheet on it (`tests/user_drops.rs`; at 1.5 one
/// bounced off a free edge) and steps the drape with 55 substeps at N = 64
/// instead of 69 (BENCHMARKS.md, thirteenth session).
const XPBD_REACH: f32 = 1.25;

/// [`XPBD_REACH`] when the direct solves along rows and columns run before
/// the sweeps (`grid_chains.rs`): they carry a correction across the cloth
/// in one substep, so the substep no longer limits how far one travels.
/// The drape's peak stretch over every frame at the substeps this gives
/// (BENCHMARKS.md, sixteenth session): 4.56% with 12 at N = 64 (8 gave
/// 5.95%), 4.90% with 24 at N = 128 (20 gave 5.28%).
const XPBD_CHAIN_REACH: f32 = 5.7;

/// [`XPBD_CHAIN_REACH`] for a material with a stretch limit, which the
/// lanes hold with more calls of its passes while a spring is still far
/// over it (`xpbd::hold_limit`): two thirds of the substeps. Peak stretch
/// over every frame of the drape (BENCHMARKS.md, twentieth session): at
/// N = 128 cotton 4.81% at 16 substeps (24 before), silk 4.85% at 16 (the
/// floor of [`unpinned_substeps`]); N = 256 4.77% at 64 (96 before). A
/// material without a limit keeps
/// [`XPBD_CHAIN_REACH`]: rubber's drape at N = 128 rests 35% stretched
/// with 12 substeps against 9% with 24. A cloth without pins on still
/// round obstacles takes [`limited_chain_substeps`] instead.
const XPBD_LIMITED_CHAIN_REACH: f32 = 1.5 * XPBD_CHAIN_REACH;

/// Automatic substeps a second with the chain solves for a cloth without
/// pins on still balls and half-spaces, of a material with a stretch limit,
/// on a grid whose longer side has up to [`XPBD_LIMITED_CHAIN_SIDE`]
/// particles; past it they grow with the side ([`limited_chain_substeps`]),
/// whatever the stiffness. Nothing hangs such a cloth: its stretch is a
/// landing's, which the limit's passes hold after the chains and one
/// sweep, and how far they carry a correction is counted in particles (a
/// stiffer spring the chains meet just as exactly). Measured, peak stretch
/// over every frame of the drape (BENCHMARKS.md, twenty-fourth session),
/// silk, cotton, denim, leather and canvas: at most 4.85% with 12 substeps
/// at N = 80 to 128. With the limit over-relaxed by 1.9
/// (`grid_sweep::LIMIT_OVER_RELAXATION`; thirtieth session, 60 frames):
/// 4.51–4.55% at N = 96 and 128 with 12, 4.51–4.52% at N = 160 with 14,
/// 4.53–4.56% at 192 with 16, 4.56–4.62% at 224 with 18, 4.59–4.70% at
/// 256 with 20 (cotton 8.3% with 16). With 1.5 the limit stayed unsettled
/// through a landing and the rule grew with the square of the side: at
/// N = 256 4.79–5.71% with 32, 4.63–4.75% with 48. The limit has since
/// learnt to carry a correction farther a call (its pairs and long spans,
/// its calls again after an unsettled one), and the rule grows half as
/// fast (sixty-first session, 90 frames, the five materials): 4.51% at
/// N = 192 with 13 and 14, at 224 with 14 and 15, at 256 with 15 and 16,
/// never into the ball; at N = 256 16 substeps were the fastest (bench,
/// one thread, medians of five alternated runs: 15 38.3 ms, 16 37.0, 18
/// 40.1, 20 45.1).
/// [`XPBD_LIMITED_CHAIN_REACH`] gave 16 substeps at N = 128 and 64 at 256
/// to cotton, 49 and 193 to canvas. A hanging cloth is another matter: the
/// `pins` sheet at N = 128 hung by its centre peaks at 10% with 16
/// substeps against 4.6% with canvas's 49.
const XPBD_LIMITED_CHAIN_SUBSTEPS_PER_SECOND: f32 = 720.0;

// The side rule's floor is the unpinned floor (`unpinned_substeps`).
const _: () = assert!(XPBD_LIMITED_CHAIN_SUBSTEPS_PER_SECOND >= XPBD_UNPINNED_SUBSTEPS_PER_SECOND);

/// The longest grid side (particles) at which
/// [`XPBD_LIMITED_CHAIN_SUBSTEPS_PER_SECOND`] holds unscaled.
const XPBD_LIMITED_CHAIN_SIDE: f32 = 128.0;

/// Past [`XPBD_LIMITED_CHAIN_SIDE`], the side rule adds a substep a frame
/// at 60 Hz for every this many particles along the side: 12 substeps at
/// N = 128, 16 at 256.
const XPBD_LIMITED_CHAIN_PARTICLES_PER_SUBSTEP: f32 = 32.0;

/// The automatic substeps of a frame step of `dt` seconds with the chain
/// solves for a cloth of a material with a stretch limit, without pins, on
/// still balls and half-spaces, on a grid whose longer side has `side`
/// particles: [`XPBD_LIMITED_CHAIN_SUBSTEPS_PER_SECOND`] up to
/// [`XPBD_LIMITED_CHAIN_SIDE`], and past it one substep a frame at 60 Hz
/// more for every [`XPBD_LIMITED_CHAIN_PARTICLES_PER_SUBSTEP`] particles.
fn limited_chain_substeps(side: f32, dt: f32) -> f32 {
    let past = (side - XPBD_LIMITED_CHAIN_SIDE).max(0.0);
    let more = 60.0 * past / XPBD_LIMITED_CHAIN_PARTICLES_PER_SUBSTEP;
    substeps_at_rate(dt, XPBD_LIMITED_CHAIN_SUBSTEPS_PER_SECOND + more)
}

/// The whole substeps of a frame step of `dt` seconds at `per_second`
/// substeps a second, rounded up from a thousandth below: 1/60 s at 960 a
/// second is 16, not 17.
fn substeps_at_rate(dt: f32, per_second: f32) -> f32 {
    (dt * per_second - 1.0e-3).ceil()
}

/// Particles along a grid's longer side up to which [`XPBD_CHAIN_REACH`]
/// holds; past it the reach falls in proportion to the side. The drape at
/// N = 256 peaked at 5.44% with the 48 substeps of the full reach, 5.13%
/// with 56, 4.98% with 64, 5.05% with 68, 4.82% with 72 and 80, 4.99%
/// with 76 and 4.75% with 96 (a limit of 24 passes instead of 8 did not
/// help: 5.59% at 48): the peak of a landing wanders by a few tenths of a
/// percent from one count to the next, and this keeps a margin (96 there).
const XPBD_CHAIN_FULL_REACH_SIDE: f32 = 128.0;

/// Automatic substeps a second at least with the chain solves: 16 a frame
/// at 60 Hz (self-collision's [`super::MAX_SELF_SUBSTEP`] too). Where the
/// stretch comes from contacts rather than from the cloth's weight, the
/// chains do not carry it away, and the substep sets it. Measured, peak
/// stretch over every frame: the drape at N = 48 in a cotton with half the
/// stretch stiffness (`tests/stretch_limit.rs`) 5.09% at 12 substeps, 4.89%
/// at 16 (4.76% at the sweeps' own 31); the curtain pushed by its
/// kinematic ball 6.7% at 8, 5.8% at 12, 5.5% at 16 (5.0% at the sweeps'
/// 34); the `pins` sheet 5.6% at 7, 4.9% at 12.
const XPBD_CHAIN_SUBSTEPS_PER_SECOND: f32 = 960.0;

/// Automatic substeps a second at least with the chain solves for a cloth
/// without pins whose every obstacle is a still ball or half-space (whose
/// contacts the lanes hold, `lane_contacts`): 12 a frame at 60 Hz.
/// Nothing there pulls the cloth against a pin or a moving surface: the
/// contacts push it out where they stand, and the chains carry the rest.
/// Measured, peak stretch over every frame of the drape (120 frames),
/// 16 → 12 substeps: cotton 4.51 → 4.51% at N = 32, 4.63 → 4.63% at 48,
/// 4.53 → 4.67% at 64; cotton with half the stretch stiffness 4.82 →
/// 4.90%, 4.77 → 4.80%, 4.69 → 4.69%; silk, denim, leather and canvas at
/// N = 32 and 64 at most 4.67%. With pins the floor stays
/// [`XPBD_CHAIN_SUBSTEPS_PER_SECOND`]: the `pins` sheet hung by its
/// corners peaks at 10.6% at 12 against 8.5% at 16, by all four at 5.8%
/// against 5.3%.
const XPBD_UNPINNED_SUBSTEPS_PER_SECOND: f32 = 720.0;

/// Automatic substeps a second at least with the chain solves while a still
/// obstacle with edges or corners is within reach of the cloth (and no
/// moving one): 20 a frame at 60 Hz. Its contacts are then held inside the
/// substep as planes (`collision/contact_planes.rs`, and the lanes' own);
/// what still sets the substep is a corner, over which the cloth must
/// stretch or fold and the stretch limit and the contacts pull against
/// each other. It was 32 (1920 a second) when the limit took turns with
/// the contacts over a cuboid's edges (the 48 × 48 cotton tablecloth of
/// `tests/user_drops.rs` peaked at 5.03% at 16 substeps, 4.92% at 20,
/// 4.56% at 32); since the limit holds the lanes on the cuboid's planes
/// itself (`xpbd::hold_limit`), the substeps no longer set the peak.
/// Measured (forty-seventh session, peak stretch over every frame, deepest
/// penetration): tablecloths of 32², 48² and 64², 1.0–2.0 m, in silk,
/// cotton and denim dropped on a table with a leg, 4.51% and none at 32,
/// 24, 20 and 16 substeps; the `box` 4.51% and none at each, 1.673 →
/// 1.432 → 1.297 G instructions (callgrind, `bench --scene box`, one
/// thread) at 32, 24 and 20. What breaks first below is a dynamic body
/// resting on a cloth over a table: at 16 a 1 kg ball on a laid table
/// still bounced at 0.15 m/s after 150 frames and the limit's rounds
/// after the contacts ran to 26 a step (`tests/user_drops.rs`); at 20 and
/// more it rests, with one round at most.
const XPBD_EDGE_SUBSTEPS_PER_SECOND: f32 = 1200.0;

/// The automatic substeps of a frame step of `dt` seconds near still
/// obstacles with edges: at least [`XPBD_EDGE_SUBSTEPS_PER_SECOND`].
pub(crate) fn edge_substeps(dt: f32) -> u32 {
    whole_substeps(substeps_at_rate(dt, XPBD_EDGE_SUBSTEPS_PER_SECOND))
}

/// Whether the chain solves lengthen the automatic substeps of `settings`
/// on `cloth`: the small-steps solver with them on, on a whole grid.
pub(crate) fn chains_lengthen(cloth: &Cloth, settings: &SolverSettings) -> bool {
    settings.integrator == Integrator::Xpbd && settings.xpbd_chains && grid_chains::apply_to(cloth)
}

/// The largest substep (seconds) at which the integrator of `settings` is
/// estimated to be stable on this cloth (for the small-steps solver, which
/// is stable at any step: the substep at which its springs keep their
/// stiffness; longer when its direct solves along rows and columns apply).
pub fn stable_substep(cloth: &Cloth, settings: &SolverSettings) -> f32 {
    let integrator = settings.integrator;
    let (omega2, gamma) = stiffness_bounds(cloth);
    if omega2 <= 0.0 {
        return f32::INFINITY;
    }
    // Symplectic Euler on x'' = -ω² x - γ x' is stable while h² ω² + 2 h γ < 4.
    let symplectic = (-gamma + (gamma * gamma + 4.0 * omega2).sqrt()) / omega2;
    let safety = 0.9;
    let h = match integrator {
        Integrator::SymplecticEuler | Integrator::Verlet => symplectic,
        // RK4's stability region reaches 2.8 on the imaginary axis.
        Integrator::Rk4 => 1.4 * symplectic,
        // Forward Euler only damps a mode while h < γ/ω², that is c/k per spring.
        Integrator::ImplicitEuler | Integrator::FastMassSpring => return f32::INFINITY,
        // Stable at any step; the stiffness converges with the substeps.
        // Damping takes no substeps here: the sweep treats it implicitly,
        // with the springs (a heavily damped cloth steps as fast as a light one).
        Integrator::Xpbd => {
            let reach = match cloth.topology().lane_grid() {
                Some(lanes) if chains_lengthen(cloth, settings) => {
                    // A piece's side: the chains stop at a stacked piece's edge.
                    let side = lanes.piece_side() as f32;
                    let reach = if cloth.material.stretch_limit.is_some() {
                        XPBD_LIMITED_CHAIN_REACH
                    } else {
                        XPBD_CHAIN_REACH
                    };
                    reach * (XPBD_CHAIN_FULL_REACH_SIDE / side).min(1.0)
                }
                _ => XPBD_REACH,
            };
            reach * 2.0 / bulk_stiffness(cloth).sqrt()
        }
        Integrator::ExplicitEuler => {
            let ratio = SpringKind::ALL
                .iter()
                .map(|&k| {
                    let sp = cloth.material.params(k);
                    sp.damping / sp.stiffness
                })
                .fold(f32::INFINITY, f32::min);
            // A spring kind without damping is never damped by it: then only
            // air drag helps, and a step far below the symplectic one.
            if ratio > 0.0 {
                symplectic.min(ratio)
            } else {
                symplectic / 8.0
            }
        }
    };
    safety * h
}

/// The longest grid side (particles) at which
/// [`XPBD_CHAIN_SUBSTEPS_PER_SECOND`] holds unscaled for a cloth of a
/// material with a stretch limit that hangs from pins or meets moving
/// obstacles ([`stable_substeps`]).
const XPBD_CHAIN_SIDE: f32 = 80.0;

/// Past [`XPBD_CHAIN_SIDE`], [`stable_substeps`] adds a substep a frame at
/// 60 Hz for every this many particles along the side: 16 substeps at
/// N = 80, 20 at 96, 28 at 128, 36 at 160. A cloth hung from pins hangs on
/// runs of springs at the stretch limit as long as its side, and a
/// substep's limit holds a longer run in more calls (up to
/// `xpbd::PINNED_LIMIT_ROUNDS`) or not at all. Measured, peak stretch over
/// every frame and ms a frame at 16 substeps → this rule (BENCHMARKS.md,
/// thirty-seventh session): the `pins` sheet hung by two corners at N =
/// 96 4.75% → 4.77% (7.8 → 7.4 ms), at 128 13.0% → 4.89% (27.8 → 21.4),
/// at 160 28.8% → 5.58% (68 → 47; 4.92% with 64 substeps); by four
/// corners at 128 7.53% → 4.66% (23.2 → 12.1); the `curtain` at N = 96
/// 5.62% → 4.95%, at 128 5.97% → 4.59%, at 160 6.08% → 4.72%. The sheet
/// hung by its centre held 4.51% at 16 substeps up to N = 128 and pays
/// for the others (7.4 → 10.4 ms at 128). Up to N = 80 every case above
/// held under 5% at 16.
const XPBD_CHAIN_PARTICLES_PER_SUBSTEP: f32 = 4.0;

/// The substeps a second at least of the small-steps solver with its chain
/// solves on `cloth` hung from pins or among moving obstacles:
/// [`XPBD_CHAIN_SUBSTEPS_PER_SECOND`], and for a material with a stretch
/// limit on a grid whose longer side (a piece's, for stacked pieces) is
/// past [`XPBD_CHAIN_SIDE`], one a frame at 60 Hz more for every
/// [`XPBD_CHAIN_PARTICLES_PER_SUBSTEP`] particles.
fn chain_substeps_per_second(cloth: &Cloth) -> f32 {
    let side = match cloth.topology().lane_grid() {
        Some(lanes) if cloth.material.stretch_limit.is_some() => lanes.piece_side() as f32,
        _ => 0.0,
    };
    let past = (side - XPBD_CHAIN_SIDE).max(0.0);
    XPBD_CHAIN_SUBSTEPS_PER_SECOND + 60.0 * past / XPBD_CHAIN_PARTICLES_PER_SUBSTEP
}

/// The substeps that keep the integrator of `settings` within its
/// stability limit for a frame step `dt` (with the small-steps solver's
/// chain solves, at least 960 a second, more on a fine grid:
/// `chain_substeps_per_second`).
pub fn stable_substeps(cloth: &Cloth, settings: &SolverSettings, dt: f32) -> u32 {
    substeps_at_least(cloth, settings, dt, chain_substeps_per_second(cloth))
}

/// [`stable_substeps`] for a cloth without pins whose every obstacle is a
/// still ball or half-space: with the chain solves, at least
/// [`XPBD_UNPINNED_SUBSTEPS_PER_SECOND`] on a grid whose longer side has
/// at most [`XPBD_UNPINNED_FLOOR_SIDE`] particles, where it was measured;
/// for a material with a stretch limit, [`limited_chain_substeps`] at any
/// size.
pub(crate) fn unpinned_substeps(cloth: &Cloth, settings: &SolverSettings, dt: f32) -> u32 {
    let limited = cloth.material.stretch_limit.is_some();
    match cloth.topology().lane_grid() {
        Some(lanes) if limited && chains_lengthen(cloth, settings) => {
            // At least XPBD_UNPINNED_SUBSTEPS_PER_SECOND: the side rule's
            // own rate at N = 128 and below.
            let side = lanes.piece_side() as f32;
            whole_substeps(limited_chain_substeps(side, dt))
        }
        Some(lanes) if lanes.piece_side() <= XPBD_UNPINNED_FLOOR_SIDE => {
            substeps_at_least(cloth, settings, dt, XPBD_UNPINNED_SUBSTEPS_PER_SECOND)
        }
        _ => substeps_at_least(cloth, settings, dt, XPBD_CHAIN_SUBSTEPS_PER_SECOND),
    }
}

/// The longest grid side (particles) that [`XPBD_UNPINNED_SUBSTEPS_PER_SECOND`]
/// applies to for a material without a stretch limit: it was measured on
/// the drape at N = 32 to 64 (rubber's drape at N = 128 peaks at 97% with
/// 12 substeps and 82% with 16). The presets with a limit peak at most at
/// 4.85% with 12 up to N = 128 (BENCHMARKS.md, twenty-fourth session).
const XPBD_UNPINNED_FLOOR_SIDE: usize = 64;

/// [`stable_substeps`] with `per_second` substeps a second at least when
/// the chain solves lengthen them.
fn substeps_at_least(cloth: &Cloth, settings: &SolverSettings, dt: f32, per_second: f32) -> u32 {
    let h = stable_substep(cloth, settings);
    let mut k = (dt / h).ceil();
    if chains_lengthen(cloth, settings) {
        k = k.max(substeps_at_rate(dt, per_second));
    }
    whole_substeps(k)
}

/// How fast (m/s) two layers of a cloth with self-collision may close in
/// on each other for the automatic substeps of the small-steps solver with
/// its chain solves: a substep moves such a layer by at most the layers'
/// thickness ([`Cloth::self_thickness`]), so that the next substep's pass
/// still finds it on its side. Measured on `fold` (240 frames, final and
/// largest self-intersection counts), the five presets: at N = 48 (layers
/// 5.3 mm) none at 20 substeps in any frame, denim 137 at 18; at N = 64
/// (4.0 mm) none at the end with 24, silk 14 in some frame (as many as
/// with the sweeps' 34); at N = 96 (2.6 mm) none at the end with 38 for
/// cotton, silk and denim (silk 26 in some frame), 380 with 24. The
/// sweeps' own count, taken before, rose with the stiffness (leather 106
/// and canvas 124 at N = 48), which keeps no layer apart.
const SELF_CLOSING_SPEED: f32 = 6.4;

/// Substeps a second (at least) for cloths joined into one with
/// self-collision where the chain solves lengthen the substeps: they land
/// on each other, faster than one cloth's layers close. Measured on the
/// `stack` over 42 starts (N = 26–38 in steps of 2, cotton, silk and
/// denim, 60 and 50 Hz; crossed in some frame / still at the end). With a
/// triangle's one-ring paired on a grid
/// (`MeshNeighbours`) and every material at one
/// count: at 1440 (24 substeps at 60 Hz, 29 at 50) 1 / 0, as at the
/// sweeps' own (cotton 28 and 33, denim 46 and 55, silk 17 and 21) 2 / 0;
/// at 1320 (22 and 27) 6 / 2; at 1200 (20 and 24) 5 / 1, the crossings at
/// the borders (two cloths' border edges in an X by a corner, creases of
/// two cloths in an X near a border). With the pairs' sides taken a
/// substep before the look too: at 1200, all at one count, 4 / 0; as this
/// rule gives them (silk at its sweeps' 17 and 21) 5 / 0, six
/// self-intersections in all, each in a frame or two (the sweeps' counts
/// before either change: 1 / 0, two).
const JOINED_SELF_SUBSTEPS_PER_SECOND: f32 = 1200.0;

/// The substeps of a frame of `dt` seconds for cloths joined into one
/// with self-collision where the chains apply
/// ([`JOINED_SELF_SUBSTEPS_PER_SECOND`]).
pub(crate) fn joined_self_substeps(dt: f32) -> u32 {
    whole_substeps(substeps_at_rate(dt, JOINED_SELF_SUBSTEPS_PER_SECOND))
}

/// The substeps of a frame of `dt` seconds in which a layer closing at
/// [`SELF_CLOSING_SPEED`] moves at most `thickness` metres each.
pub(crate) fn self_closing_substeps(thickness: f32, dt: f32) -> u32 {
    whole_substeps(substeps_at_rate(dt, SELF_CLOSING_SPEED / thickness))
}

/// A substep count from a whole number `k` of them: 1 to a million, and 1
/// for one that is not finite.
fn whole_substeps(k: f32) -> u32 {
    if k.is_finite() {
        k.clamp(1.0, 1.0e6) as u32
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::{ClothBuilder, Material};

    #[test]
    fn a_limited_cloths_chain_substeps_grow_with_its_side_past_80() {
        let dt = 1.0 / 60.0;
        let substeps = |n: usize, material: Material| {
            let cloth = ClothBuilder::new(n, n).material(material).build().unwrap();
            substeps_at_rate(dt, chain_substeps_per_second(&cloth))
        };
        assert_eq!(substeps(40, Material::cotton()), 16.0);
        assert_eq!(substeps(80, Material::cotton()), 16.0);
        assert_eq!(substeps(96, Material::cotton()), 20.0);
        assert_eq!(substeps(128, Material::cotton()), 28.0);
        // The longer side counts.
        let cloth = ClothBuilder::new(128, 20)
            .material(Material::cotton())
            .build()
            .unwrap();
        assert_eq!(
            substeps_at_rate(dt, chain_substeps_per_second(&cloth)),
            28.0
        );
        // Without a stretch limit, the floor alone.
        let unlimited = Material {
            stretch_limit: None,
            ..Material::cotton()
        };
        assert_eq!(substeps(128, unlimited), 16.0);
    }

    #[test]
    fn a_limited_cloths_substeps_grow_with_its_side_past_128() {
        let dt = 1.0 / 60.0;
        assert_eq!(limited_chain_substeps(64.0, dt), 12.0);
        assert_eq!(limited_chain_substeps(128.0, dt), 12.0);
        assert_eq!(limited_chain_substeps(160.0, dt), 13.0);
        assert_eq!(limited_chain_substeps(256.0, dt), 16.0);
        assert_eq!(limited_chain_substeps(256.0, 2.0 * dt), 32.0);
    }
}
