# Spike for issue 16 (fifteenth session; results in BENCHMARKS.md, "A
# spike: direct solves along rows and columns"). Not part of the crate:
# numpy, run as `python3 docs/spikes/row_column_solve.py N S1 S2 ...`.
#
# A 1 kg, 1 x 1 m cloth of N x N particles pinned along its top row,
# stretch springs only (k = 1500 N/m, cotton's), hanging under gravity.
# XPBD with S substeps a 1/60 s frame and one pass a substep, either a
# colour-ordered Gauss-Seidel sweep (what cloth3d does) or a direct solve of
# each row's and each column's chain of springs (linearised, tridiagonal,
# Thomas algorithm across all rows at once). Reports the largest vertical
# spring stretch after T seconds (the cloth has settled: velocities damped).
import numpy as np, sys, time

def run(N, S, mode, T=2.0, k=1500.0, damp=0.02):
    L = 1.0 / (N - 1)
    m = 1.0 / (N * N)
    ys, xs = np.meshgrid(np.arange(N), np.arange(N), indexing="ij")
    p = np.zeros((N, N, 3)); p[..., 0] = xs * L; p[..., 1] = -ys * L
    v = np.zeros_like(p)
    w = np.full((N, N), 1.0 / m); w[0, :] = 0.0
    dt = 1.0 / 60.0; h = dt / S; a = 1.0 / (k * h * h)
    g = np.array([0.0, -9.81, 0.0])
    frames = int(T / dt)
    for f in range(frames):
        for s in range(S):
            v += (w[..., None] > 0) * g * h
            v *= (1.0 - damp)  # crude damping so the cloth settles
            x0 = p.copy()
            p = p + v * h
            lam_h = np.zeros((N, N - 1)); lam_v = np.zeros((N - 1, N))
            if mode == "gs":
                gs_pass(p, w, L, a, lam_h, lam_v)
            else:
                direct_pass(p, w, L, a, lam_h, lam_v)
            v = (p - x0) / h
    d = p[1:, :, :] - p[:-1, :, :]
    st = np.linalg.norm(d, axis=2) / L - 1.0
    dh = p[:, 1:, :] - p[:, :-1, :]
    sth = np.linalg.norm(dh, axis=2) / L - 1.0
    return st.max(), sth.max()

def project(pa, pb, wa, wb, L, a, lam):
    d = pb - pa; l = np.linalg.norm(d, axis=-1); n = d / l[..., None]
    C = l - L; denom = wa + wb + a
    dl = -(C + a * lam) / denom
    return pa - (wa * dl)[..., None] * n, pb + (wb * dl)[..., None] * n, lam + dl

def gs_pass(p, w, L, a, lam_h, lam_v):
    N = p.shape[0]
    # Rows: springs (r, c)-(r, c+1), colours by c parity.
    for par in (0, 1):
        c = np.arange(par, N - 1, 2)
        pa, pb, lam = project(p[:, c], p[:, c + 1], w[:, c], w[:, c + 1], L, a, lam_h[:, c])
        p[:, c] = pa; p[:, c + 1] = pb; lam_h[:, c] = lam
    for par in (0, 1):
        r = np.arange(par, N - 1, 2)
        pa, pb, lam = project(p[r], p[r + 1], w[r], w[r + 1], L, a, lam_v[r])
        p[r] = pa; p[r + 1] = pb; lam_v[r] = lam

def chains(P, W, L, a, lam):
    # P: (B, n, 3) chains, W: (B, n); constraints between consecutive points.
    d = P[:, 1:] - P[:, :-1]; l = np.linalg.norm(d, axis=-1); nrm = d / l[..., None]
    C = l - L
    diag = W[:, :-1] + W[:, 1:] + a
    off = -W[:, 1:-1] * np.einsum("bij,bij->bi", nrm[:, :-1], nrm[:, 1:])
    rhs = -(C + a * lam)
    # Thomas algorithm, vectorised over the batch.
    B, m = diag.shape
    cp = np.zeros((B, m)); dp = np.zeros((B, m))
    cp[:, 0] = off[:, 0] / diag[:, 0] if m > 1 else 0
    dp[:, 0] = rhs[:, 0] / diag[:, 0]
    for i in range(1, m):
        den = diag[:, i] - off[:, i - 1] * cp[:, i - 1]
        if i < m - 1:
            cp[:, i] = off[:, i] / den
        dp[:, i] = (rhs[:, i] - off[:, i - 1] * dp[:, i - 1]) / den
    x = np.zeros((B, m)); x[:, -1] = dp[:, -1]
    for i in range(m - 2, -1, -1):
        x[:, i] = dp[:, i] - cp[:, i] * x[:, i + 1]
    dP = np.zeros_like(P)
    dP[:, :-1] -= (W[:, :-1] * x)[..., None] * nrm
    dP[:, 1:] += (W[:, 1:] * x)[..., None] * nrm
    return P + dP, lam + x

def direct_pass(p, w, L, a, lam_h, lam_v):
    P, lh = chains(p, w, L, a, lam_h)
    p[:] = P; lam_h[:] = lh
    Pt, lv = chains(p.transpose(1, 0, 2), w.T, L, a, lam_v.T)
    p[:] = Pt.transpose(1, 0, 2); lam_v[:] = lv.T

if __name__ == "__main__":
    N = int(sys.argv[1]) if len(sys.argv) > 1 else 32
    for S in [int(s) for s in sys.argv[2:]] or [5, 10, 20, 40]:
        for mode in ("gs", "direct"):
            t = time.time()
            sv, sh = run(N, S, mode)
            print(f"N={N} S={S:3d} {mode:6s} vertical {sv*100:6.2f}%  horizontal {sh*100:6.2f}%  ({time.time()-t:.1f}s)", flush=True)
