"""Session 11 (docs/gap.md, "Rounding after a filter (session 11)"): the AVAR of a first-order
filtered white rate rounded to a step, against session 10's model (the rounding error's
autocovariance averaged over where the mean falls between two steps), with the mean at a given
fraction of a step.

usage: python3 rr_mu.py T_SAMPLES SIGMA_PER_STEP MEAN_IN_STEPS [N_SAMPLES]
e.g.   python3 rr_mu.py 10 0.45 0.0 1e7     (the mean on a step)
       python3 rr_mu.py 10 0.45 0.25 1e7    (the mean at a quarter step)
Needs numpy only. Prints, per cluster size m, simulated / model and the simulation's own
relative spread (20 chunks)."""
import math
import sys

import numpy as np


def autocov_first_order(t_samples):
    """Autocovariance of unit white noise through y_k = a y_{k-1} + (1 - a) x_k."""
    a = math.exp(-1.0 / t_samples)
    n = math.ceil(math.log(1e-15) / math.log(a)) + 2
    return (1 - a) / (1 + a) * a ** np.arange(n)


def theta_sum(x):
    """sum_{n>=1} exp(-n^2 x) / n^2 (Poisson form below 0.5)."""
    x = max(x, 0.0)
    if x < 0.5:
        return math.pi ** 2 / 6 - math.sqrt(math.pi * x) + 0.5 * x
    return sum(math.exp(-n * n * x) / (n * n) for n in range(1, 64))


def avar_from_autocov(c, ms):
    c = np.asarray(c)
    p0 = np.concatenate([[0.0], np.cumsum(c[1:])])
    p1 = np.concatenate([[0.0], np.cumsum(np.arange(1, len(c)) * c[1:])])

    def s(n):
        k = min(n - 1, len(c) - 1)
        return n * c[0] + 2 * (n * p0[k] - p1[k])

    return np.array([(4 * s(m) - s(2 * m)) / (2 * m * m) for m in ms])


def rounding_autocov(rho, step):
    """Session 10's model (src/gap/rounding.rs): averaged over the mean's position."""
    x = 4 * math.pi ** 2 * rho[0] / step ** 2
    c = step ** 2 / (2 * math.pi ** 2)
    tail = theta_sum(x)
    return [c * (theta_sum(x * max(1 - v / rho[0], 0.0)) - tail) for v in rho]


def avar(v, m):
    c = np.concatenate([[0.0], np.cumsum(v)])
    b = (c[m:] - c[:-m]) / m
    d = b[m:] - b[:-m]
    return 0.5 * np.mean(d * d)


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
    model = avar_from_autocov(rho, ms) + avar_from_autocov(rounding_autocov(rho, step), ms)
    sim = np.array([avar(y, m) for m in ms])
    chunks = np.array([[avar(c, m) for m in ms] for c in np.array_split(y, 20)])
    spread = chunks.std(0) / math.sqrt(20) / sim
    print(f"T {t_samples} samples, sigma/step {per_step}, mean {mean_steps} step")
    for m, r, sd in zip(ms, sim / model, spread):
        print(f"m {m:4d}  simulated/model {r:.4f}  spread {sd:.4f}")


if __name__ == "__main__":
    main()
