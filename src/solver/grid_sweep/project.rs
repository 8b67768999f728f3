//! The projection of one spring, shared by the grid's sweep and the springs
//! swept after it (`grid_leftover`): a kind's compliance terms for a
//! substep, how a kind takes part in a sweep, and the projection itself.

/// Compliance terms of one spring kind for a substep: `α = 1/(k h²)`, `γ = c/(k h)`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Compliance {
    pub alpha: f32,
    pub gamma: f32,
}

/// How one sweep takes one kind of spring ([`sweep`](super::sweep::sweep); by
/// [`SpringKind::index`](crate::cloth::SpringKind::index)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct KindInSweep {
    /// The kind's springs are projected.
    pub on: bool,
    /// Nothing projected them yet this substep: their multipliers are
    /// taken as zero, not read (the arrays are not filled with zeros).
    pub from_zero: bool,
    /// A later sweep of this substep reads their multipliers, so they are
    /// stored (else nothing reads them, and the stores are left out).
    pub kept: bool,
}

impl KindInSweep {
    /// Projected, with multipliers read and stored.
    #[cfg(test)]
    pub const READ_AND_KEPT: KindInSweep = KindInSweep {
        on: true,
        from_zero: false,
        kept: true,
    };

    /// Not projected.
    pub const OFF: KindInSweep = KindInSweep {
        on: false,
        from_zero: false,
        kept: false,
    };
}

/// One spring's projection: new positions of its ends `a` and `b` (m),
/// given the motion of `b` relative to `a` since the substep's start, the
/// inverse masses `w` of the ends, the rest length (0: no spring here) and
/// the multiplier `lambda` so far this substep, which it updates.
///
/// With `d = b − a`, `l = |d|` and `D = (1 + γ)(w_a + w_b) + α`:
/// `Δλ = −(l − L + αλ + γ d·m / l) / D`, and the ends move by `w Δλ d / l`.
/// Both are written over `l² D`, which needs no root:
/// `s = −(l (l − L + αλ) + γ d·m) / (l² D)`, `Δλ = s l`, moves `w s d`.
/// The one division then runs beside the root instead of after it (a
/// root, then two divisions one after the other, was the sweep's longest
/// chain).
#[inline(always)]
pub(crate) fn project(
    a: [f32; 3],
    b: [f32; 3],
    motion: [f32; 3],
    w: [f32; 2],
    (rest, lambda): (f32, &mut f32),
    k: Compliance,
) -> ([f32; 3], [f32; 3]) {
    let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let wsum = w[0] + w[1];
    // A missing spring, two pinned ends or coincident ends: no change.
    let active = rest > 0.0 && wsum > 0.0 && len2 > f32::MIN_POSITIVE;
    let denom = (1.0 + k.gamma) * wsum + k.alpha;
    let inv_l2d = 1.0 / (len2 * denom);
    let len = len2.sqrt();
    let rate = d[0] * motion[0] + d[1] * motion[1] + d[2] * motion[2];
    let num = len * (len - rest + k.alpha * *lambda) + k.gamma * rate;
    let s = if active { -num * inv_l2d } else { 0.0 };
    *lambda += s * len;
    let (sa, sb) = (w[0] * s, w[1] * s);
    (
        [a[0] - d[0] * sa, a[1] - d[1] * sa, a[2] - d[2] * sa],
        [b[0] + d[0] * sb, b[1] + d[1] * sb, b[2] + d[2] * sb],
    )
}
