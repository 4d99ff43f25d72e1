"""Session 12 (docs/gap.md, "Rounding after a filter (session 12)"): the AVAR of a first-order
filtered white rate rounded to a step, against the rounding model that knows where the mean
falls on the grid (src/gap/rounding.rs), and against session 10's model (averaged over the
mean's position).

usage: python3 rr_grid.py T_SAMPLES SIGMA_PER_STEP MEAN_IN_STEPS [N_SAMPLES]
Needs numpy only. Prints, per cluster size m, simulated / model for both models and the
simulation's own relative spread (20 chunks)."""
import math
import sys

import numpy as np

sys.path.insert(0, __file__.rsplit("/", 1)[0] + "/../session11")
from rr_mu import autocov_first_order, avar, avar_from_autocov, rounding_autocov  # noqa: E402


def pair_sum(p, x, r, nmax=2000):
    """sum over n + m = p (n, m != 0) of [exp(-x/2 (n^2 + m^2 + 2 n m r)) - exp(-x/2 (n^2 + m^2))]
    / (n m): the harmonic p of the mean-dependent part of the error's covariance."""
    one_minus = max(1.0 - r, 0.0)
    if one_minus > 0:
        nn = min(nmax, int(math.ceil(math.sqrt(45.0 / (x * one_minus)))) + p + 2)
    else:
        nn = nmax
    n = np.arange(-nn, nn + p + 1, dtype=float)
    n = n[(n != 0) & (n != p)]
    m = p - n
    e1 = np.exp(-0.5 * x * (n * n + m * m + 2 * n * m * r))
    e2 = np.exp(-0.5 * x * (n * n + m * m))
    if one_minus == 0:
        # lag 0: sum of 1/(n m) over n + m = p is -2/p^2 exactly
        return math.exp(-0.5 * x * p * p) * (-2.0 / p**2) - np.sum(e2 / (n * m))
    return np.sum((e1 - e2) / (n * m))


def grid_autocov(rho, step, a):
    """Mean-dependent part of the rounded output's autocovariance, beyond the signal and session
    10's averaged error: cross terms with the signal and the error's harmonics, for the grid
    averages a[p-1] = mean cos(2 pi p mu / L)."""
    s2 = rho[0]
    x = 4 * math.pi**2 * s2 / step**2
    cross = 4 * sum((-1) ** p * a[p - 1] * math.exp(-0.5 * x * p * p) for p in range(1, len(a) + 1))
    out = []
    for v in rho:
        r = v / s2
        c = cross * v
        for p in range(1, len(a) + 1):
            if a[p - 1] == 0:
                continue
            # c_n c_m = -L^2 (-1)^p / (4 pi^2 n m), twice for +-p
            c += 2 * a[p - 1] * (-(step**2) * (-1) ** p / (4 * math.pi**2)) * pair_sum(p, x, r)
        out.append(c)
    return np.array(out)


def main():
    t_samples, per_step, mean_steps = (float(a) for a in sys.argv[1:4])
    n = int(float(sys.argv[4])) if len(sys.argv) > 4 else int(1e7)
    rng = np.random.default_rng(1)
    a = math.exp(-1.0 / t_samples)
    w = np.fft.rfft(rng.standard_normal(n))
    om = 2 * np.pi * np.arange(len(w)) / n
    s = np.fft.irfft(w * (1 - a) / (1 - a * np.exp(-1j * om)), n)  # circular AR(1)
    rho = autocov_first_order(t_samples)
    step = math.sqrt(rho[0]) / per_step
    mu = mean_steps * step
    y = np.round((s + mu) / step) * step - mu
    ms = [1, 2, 4, 8, 16, 32, 64, 128]
    avg = avar_from_autocov(rho, ms) + avar_from_autocov(rounding_autocov(rho, step), ms)
    grid = [math.cos(2 * math.pi * p * mean_steps) for p in range(1, 9)]
    full = avg + avar_from_autocov(grid_autocov(rho, step, grid), ms)
    sim = np.array([avar(y, m) for m in ms])
    chunks = np.array([[avar(c, m) for m in ms] for c in np.array_split(y, 20)])
    spread = chunks.std(0) / math.sqrt(20) / sim
    print(f"T {t_samples} samples, sigma/step {per_step}, mean {mean_steps} step")
    for m, r0, r1, sd in zip(ms, sim / avg, sim / full, spread):
        print(f"m {m:4d}  sim/averaged {r0:.4f}  sim/grid {r1:.4f}  spread {sd:.4f}")


if __name__ == "__main__":
    main()
