"""A whole-mission state-space fit of the clock offset, set beside `trajdrift eval` on the second
simulator's vehicles: does a model of the slow errors over the whole mission beat the pose fit's
windows?

The pose fit holds one heading, scale and translation per ~20 s window. The second simulator's
vehicles lose part of their accuracy to two slow errors a window holds still (the estimate's
heading random walk, the reference's wandering bias; see the evidence, "What limits a vehicle's
Δt"). This script fits the other model, one state over the whole mission, and is an independent
check, not a part of the product: an extended Kalman filter whose state is the reference point's
position, the estimate's heading error (a random walk), the reference's bias (first order, its
simulated 1 cm and 100-sample correlation), the lever between the two sensors (body frame,
constant) and the inverse of the estimate's scale (constant). Between two reference samples the
point moves by the estimate's increment over the same interval, shifted by the candidate Δt,
rotated by the heading error, scaled, less the lever's turn with the estimate's orientation. Δt
is the minimum of the filter's −2 log-likelihood (a profile over Δt: 5 ms steps ±60 ms around
trajdrift's answer, then 1 ms steps and a parabola), σ from the parabola's curvature. It is given
what the product is not: the reference's white noise and the bias's size and correlation (the
simulator's own); the heading walk's rate is chosen per mission from four by the likelihood.
The estimate is averaged over 0.2 s (an odd number of its samples) first: its 2 mm per sample
would otherwise make the profile as rough as its samples are apart.

    cargo build --release
    python3 tests/python/state_space_check.py --trajdrift target/release/trajdrift --seed 49 50 51 52

prints one JSON row per vehicle (`trajdrift eval`'s error and σ, the state-space fit's) and the
two side by side. Receipt-stamped missions are left out (their stamps' latency jitter is not in
the filter's model). Needs NumPy; about 10 s a mission at 5–20 Hz references.
"""

import argparse
import json
import math
import os
import statistics
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import independent_missions as im  # noqa: E402

EPOCH = 1.7e9
BIAS_M = 0.01
EST_AVERAGE_S = 0.2
KINDS = ["ground", "straight", "outages"]


def rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def drz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]])


def quat_to_rot(q):
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    r = np.empty((len(q), 3, 3))
    r[:, 0, 0] = 1 - 2 * (y * y + z * z)
    r[:, 0, 1] = 2 * (x * y - z * w)
    r[:, 0, 2] = 2 * (x * z + y * w)
    r[:, 1, 0] = 2 * (x * y + z * w)
    r[:, 1, 1] = 1 - 2 * (x * x + z * z)
    r[:, 1, 2] = 2 * (y * z - x * w)
    r[:, 2, 0] = 2 * (x * z - y * w)
    r[:, 2, 1] = 2 * (y * z + x * w)
    r[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return r


def interp_rows(t, ts, xs):
    return np.stack([np.interp(t, ts, xs[:, k]) for k in range(xs.shape[1])], -1)


def averaged(te, pe, width_s=EST_AVERAGE_S):
    """The estimate's positions averaged over an odd number of its samples spanning `width_s`
    (centred: an even count would shift them by half a sample)."""
    n = max(1, int(round(width_s / np.median(np.diff(te))))) // 2 * 2 + 1
    if n <= 1:
        return pe
    out = pe.copy()
    for j in range(3):
        c = np.convolve(pe[:, j], np.ones(n) / n, mode="same")
        out[n:-n, j] = c[n:-n]
    return out


def neg2_log_likelihood(dt, tr, r, te, pe, re9, noise_m, ref_hz, q, psi0, u0):
    """The filter's −2 log-likelihood of the reference's samples, Δt = `dt`. State: point (3),
    heading error, bias (3), lever (3), inverse scale."""
    tau = tr - dt
    d = interp_rows(tau, te, pe)
    rot = interp_rows(tau, te, re9).reshape(-1, 3, 3)
    phi = math.exp(-1.0 / (100.0 * ref_hz))
    x = np.zeros(11)
    x[0:3], x[3], x[10] = r[0], psi0, u0
    p = np.diag([1.0] * 3 + [0.02**2] + [BIAS_M**2] * 3 + [0.3**2] * 3 + [0.03**2])
    h = np.zeros((3, 11))
    h[:, 0:3] = np.eye(3)
    h[:, 4:7] = np.eye(3)
    rn = np.eye(3) * noise_m**2
    total = 0.0
    for k in range(len(tr)):
        nu = r[k] - (x[0:3] + x[4:7])
        s = h @ p @ h.T + rn
        si = np.linalg.inv(s)
        gain = p @ h.T @ si
        x = x + gain @ nu
        p = p - gain @ h @ p
        total += math.log(np.linalg.det(s)) + nu @ si @ nu
        if k == len(tr) - 1:
            break
        dk, dr = d[k + 1] - d[k], rot[k + 1] - rot[k]
        psi, lever, u = x[3], x[7:10], x[10]
        w = u * dk - dr @ lever
        turn = rz(-psi)
        f = np.eye(11)
        f[0:3, 3] = -drz(-psi) @ w
        f[0:3, 7:10] = -turn @ dr
        f[0:3, 10] = turn @ dk
        f[4:7, 4:7] = np.eye(3) * phi
        x[0:3] = x[0:3] + turn @ w
        x[4:7] = phi * x[4:7]
        qn = np.zeros((11, 11))
        qn[0:3, 0:3] = np.eye(3) * 1e-8
        qn[3, 3] = q * q * (tr[k + 1] - tr[k])
        qn[4:7, 4:7] = np.eye(3) * (1 - phi * phi) * BIAS_M**2
        p = f @ p @ f.T + qn
    return total


def fit(ref, est, info, centre):
    """Δt and σ of the state-space fit, the profile centred on `centre`."""
    tr, r = ref[0] - EPOCH, ref[1]
    te, qe = est[0] - EPOCH, est[2]
    pe = averaged(te, est[1])
    re9 = quat_to_rot(qe).reshape(-1, 9)
    # The heading and scale to start from: the first 60 s's 2-D Procrustes fit.
    sel = tr < tr[0] + 60
    a = r[sel] - r[sel].mean(0)
    b = interp_rows(tr[sel] - centre, te, pe)
    b = b - b.mean(0)
    ang = math.atan2((b[:, 0] * a[:, 1] - b[:, 1] * a[:, 0]).sum(), (b[:, 0] * a[:, 0] + b[:, 1] * a[:, 1]).sum())
    u0 = np.linalg.norm(a[:, :2], axis=1).sum() / max(1e-9, np.linalg.norm(b[:, :2], axis=1).sum())
    base = (tr, r, te, pe, re9, info["noise_mm"] / 1e3, info["ref_hz"])
    rates = [0.0005, 0.001, 0.002, 0.004]
    q = rates[int(np.argmin([neg2_log_likelihood(centre, *base, qq, -ang, u0) for qq in rates]))]

    def profile(g):
        return neg2_log_likelihood(g, *base, q, -ang, u0)

    grid = centre + np.arange(-0.06, 0.0601, 0.005)
    i = min(max(int(np.argmin([profile(g) for g in grid])), 1), len(grid) - 2)
    fine = grid[i] + np.arange(-0.004, 0.00401, 0.001)
    c2, c1, _ = np.polyfit(fine - grid[i], [profile(g) for g in fine], 2)
    if c2 <= 0:
        return None, None
    return grid[i] - c1 / (2 * c2), math.sqrt(1.0 / c2)


def summary(name, errors_ms, sigmas_ms):
    e = sorted(abs(x) for x in errors_ms)
    z = [abs(x) / s for x, s in zip(errors_ms, sigmas_ms)]
    return (
        f"{name}: |error| median {statistics.median(e):.2f} ms, p90 {e[int(0.9 * (len(e) - 1))]:.1f}, "
        f"worst {e[-1]:.1f}, above 10 ms {sum(x > 10 for x in e)}, 2σ covers {100 * sum(x <= 2 for x in z) / len(z):.0f} %"
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trajdrift", default="target/release/trajdrift")
    ap.add_argument("--missions", type=int, default=8, help="missions of each kind")
    ap.add_argument("--seed", type=int, nargs="+", default=[49], help="one or more seed sets")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as workdir:
        for kind, seed in im.mission_seeds(args.seed, args.missions, KINDS):
            ref, est, info = im.mission(kind, seed)
            if info["legged"]:
                continue
            o, _ = im.evaluate(args.trajdrift, ref, est, workdir)
            if o is None or not o.get("sigma_s"):
                continue
            best, sigma = fit(ref, est, info, o["offset_s"])
            if best is None:
                continue
            row = dict(
                kind=kind,
                seed=seed,
                ref_hz=info["ref_hz"],
                noise_mm=round(info["noise_mm"], 1),
                trajdrift_error_ms=round(1e3 * (o["offset_s"] - info["truth_s"]), 2),
                trajdrift_sigma_ms=round(1e3 * o["sigma_s"], 2),
                state_space_error_ms=round(1e3 * (best - info["truth_s"]), 2),
                state_space_sigma_ms=round(1e3 * sigma, 2),
            )
            rows.append(row)
            print(json.dumps(row), flush=True)
    print()
    print(summary(f"trajdrift eval, {len(rows)} vehicles", [r["trajdrift_error_ms"] for r in rows], [r["trajdrift_sigma_ms"] for r in rows]))
    print(summary("whole-mission state space", [r["state_space_error_ms"] for r in rows], [r["state_space_sigma_ms"] for r in rows]))


if __name__ == "__main__":
    sys.exit(main())
