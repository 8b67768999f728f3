# Spike for issue 16 (see row_column_solve.py): `python3
# docs/spikes/row_column_swing.py N S1 S2 ...`.
# The same cloth starting horizontal, pinned along one edge: it falls and
# swings (the drape's skirt, roughly). Peak stretch of any spring over every
# frame's end, and the stretch after 2 s (no damping).
import numpy as np, sys, time
from row_column_solve import gs_pass, direct_pass

def run(N, S, mode, T=2.0, k=1500.0, damp=0.0):
    L = 1.0 / (N - 1); m = 1.0 / (N * N)
    ys, xs = np.meshgrid(np.arange(N), np.arange(N), indexing="ij")
    p = np.zeros((N, N, 3)); p[..., 0] = xs * L; p[..., 2] = ys * L
    v = np.zeros_like(p)
    w = np.full((N, N), 1.0 / m); w[0, :] = 0.0
    dt = 1.0 / 60.0; h = dt / S; a = 1.0 / (k * h * h)
    g = np.array([0.0, -9.81, 0.0]); peak = 0.0
    for f in range(int(T / dt)):
        for s in range(S):
            v += (w[..., None] > 0) * g * h
            x0 = p.copy(); p = p + v * h
            lh = np.zeros((N, N - 1)); lv = np.zeros((N - 1, N))
            (gs_pass if mode == "gs" else direct_pass)(p, w, L, a, lh, lv)
            v = (p - x0) / h
        d = np.linalg.norm(p[1:] - p[:-1], axis=2) / L - 1
        e = np.linalg.norm(p[:, 1:] - p[:, :-1], axis=2) / L - 1
        peak = max(peak, d.max(), e.max())
        if not np.isfinite(p).all():
            return float("nan"), float("nan")
    return peak, max(d.max(), e.max())

if __name__ == "__main__":
    N = int(sys.argv[1])
    for S in [int(s) for s in sys.argv[2:]]:
        for mode in ("gs", "direct"):
            t = time.time(); pk, last = run(N, S, mode)
            print(f"N={N} S={S:3d} {mode:6s} peak {pk*100:6.2f}%  last {last*100:6.2f}%  ({time.time()-t:.1f}s)", flush=True)
