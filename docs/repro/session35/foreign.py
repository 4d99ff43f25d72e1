#!/usr/bin/env python3
"""Clean IMU channels made by methods other than allanscope's simulator, for diagnosing blind.

usage: foreign.py FAMILY SEED OUT.csv   (prints the truth as one JSON line)

allanscope's simulator makes flicker from a bank of Gauss-Markov terms over a stated band. A
user's data, or another tool's simulation, has flicker from other mechanisms; this script makes
it the ways other tools do, so the diagnosis is tried on noise it was not tuned on:
  - spectral: the whole record's Fourier coefficients drawn with a 1/f power spectral density
    from 1/(2T) to the Nyquist frequency (one-sided S(f) = B^2 / (pi f), so that the Allan
    variance's flicker floor is (2 ln 2 / pi) B^2, THEORY.md section 2), then cut to length T;
  - kasdin: Kasdin and Walter's fractional integration of white noise (alpha = 1), the filter
    h_0 = 1, h_k = h_{k-1} (k - 1 + alpha/2) / k applied by FFT convolution (allantools' pink
    noise), scaled by the discrete PSD's value at low frequency;
  - white: no flicker or random walk at all.
Random walk of rate is the running sum of white rate steps; the rate ramp a straight line. The
output is rounded the way the family's part does: the running angle counted at its LSB and
differenced (a FOG's or pendulous accelerometer's counter), or each rate sample rounded (a MEMS
part's register).
"""
import json
import math
import sys

import numpy as np

# Each family: rate f_s (Hz), hours, unit, terms in the unit's THEORY.md units (N u/sqrt(s),
# B u/s, K u/s/sqrt(s), R u/s^2), flicker method, rounding ("angle" or "rate", LSB as a share of
# the per-sample white noise's sd), and how the file is written ("increments" with --tau0, or
# "rates" with a time column).
FAMILIES = {
    # a tactical FOG at 400 Hz, flicker-dominated from 1 s to 100 s, angle counted finely
    "fftfog": dict(fs=400, hours=(1, 3), unit="deg", N=(1e-4, 3e-4), B=(3e-6, 2e-5),
                   K=(1e-8, 1e-7), R=0, flicker="spectral", rounding="angle",
                   lsb=(0.05, 0.5), write="increments"),
    # a MEMS gyro at 200 Hz, each rate sample rounded in its register, written as rates
    "fftmems": dict(fs=200, hours=(1, 2), unit="rad", N=(5e-5, 3e-4), B=(2e-5, 1e-4),
                    K=(1e-6, 1e-5), R=0, flicker="spectral", rounding="rate",
                    lsb=(0.2, 1.0), write="rates"),
    # a navigation-grade accelerometer at 1 kHz with Kasdin-Walter flicker and a ramp
    "kwacc": dict(fs=1000, hours=(1, 2), unit="m/s", N=(2e-4, 1e-3), B=(5e-6, 3e-5),
                  K=(1e-7, 1e-6), R=(1e-9, 5e-9), flicker="kasdin", rounding="angle",
                  lsb=(0.1, 1.0), write="increments"),
    # a long run of a flicker-dominated FOG at 100 Hz: the record's lowest frequencies matter
    "longfog": dict(fs=100, hours=(8, 16), unit="deg", N=(5e-5, 2e-4), B=(5e-6, 3e-5),
                    K=(1e-8, 5e-8), R=0, flicker="spectral", rounding="angle",
                    lsb=(0.1, 1.0), write="increments"),
    # a MEMS gyro with white noise and random walk only, rates rounded, at 400 Hz
    "rrwmems": dict(fs=400, hours=(1, 3), unit="rad", N=(1e-4, 5e-4), B=0, K=(5e-6, 5e-5),
                    R=0, flicker="none", rounding="rate", lsb=(0.1, 1.0), write="rates"),
    # white rate noise only, rates rounded
    "white": dict(fs=100, hours=(1, 2), unit="rad", N=(1e-4, 1e-3), B=0, K=0, R=0,
                  flicker="none", rounding="rate", lsb=(0.1, 0.5), write="rates"),
}


def draw(rng, v):
    """A value log-uniform in (lo, hi), or the constant v."""
    if isinstance(v, tuple):
        return math.exp(rng.uniform(math.log(v[0]), math.log(v[1])))
    return v


def spectral_flicker(rng, n, fs, b):
    """Flicker rate samples (u/s) with one-sided PSD b^2 / (pi f) over the whole record."""
    m = 2 * n
    f = np.fft.rfftfreq(m, 1.0 / fs)
    psd = np.zeros_like(f)
    psd[1:] = b * b / (math.pi * f[1:])
    # E|X_k|^2 = S(f_k) f_s m / 2 gives a one-sided PSD S with numpy's DFT convention
    amp = np.sqrt(psd * fs * m / 2.0)
    x = amp * (rng.standard_normal(len(f)) + 1j * rng.standard_normal(len(f))) / math.sqrt(2.0)
    x[-1] = x[-1].real * math.sqrt(2.0)
    return np.fft.irfft(x, m)[:n]


def kasdin_flicker(rng, n, fs, b):
    """Flicker rate samples (u/s) by Kasdin-Walter fractional integration (alpha = 1)."""
    k = np.arange(1, n)
    h = np.concatenate(([1.0], np.cumprod((k - 1 + 0.5) / k)))
    w = rng.standard_normal(n)
    m = 1 << (2 * n - 1).bit_length()
    y = np.fft.irfft(np.fft.rfft(w, m) * np.fft.rfft(h, m), m)[:n]
    # the filter's two-sided PSD at frequency f is sigma_w^2 / (f_s |2 sin(pi f / f_s)|^alpha)
    # -> sigma_w^2 / (2 pi f) at low f: one-sided sigma_w^2 / (pi f); set equal to b^2 / (pi f)
    return b * y


def main():
    family, seed, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    p = FAMILIES[family]
    rng = np.random.default_rng(seed)
    fs = p["fs"]
    tau0 = 1.0 / fs
    hours = rng.uniform(*p["hours"])
    n = int(hours * 3600 * fs)
    nn, bb, kk, rr = (draw(rng, p[t]) for t in ("N", "B", "K", "R"))
    rate = nn / math.sqrt(tau0) * rng.standard_normal(n)
    if bb > 0:
        rate += (spectral_flicker if p["flicker"] == "spectral" else kasdin_flicker)(rng, n, fs, bb)
    if kk > 0:
        rate += np.cumsum(kk * math.sqrt(tau0) * rng.standard_normal(n))
    if rr > 0:
        rate += rr * tau0 * np.arange(n)
    lsb_share = draw(rng, p["lsb"])
    if p["rounding"] == "angle":
        lsb = lsb_share * nn * math.sqrt(tau0)  # of the per-step angle noise, u
        angle = np.cumsum(rate * tau0) + rng.uniform(0, lsb)
        counts = np.floor(angle / lsb)
        inc = np.diff(np.concatenate(([math.floor((angle[0] - rate[0] * tau0) / lsb)], counts))) * lsb
        values = inc
    else:
        lsb = lsb_share * nn / math.sqrt(tau0)  # of the per-sample rate noise, u/s
        values = np.round(rate / lsb) * lsb
        inc = values * tau0
    truth = dict(family=family, seed=seed, tau0=tau0, hours=round(hours, 4), n=n,
                 N=nn, B=bb, K=kk, R=rr, lsb=lsb, rounding=p["rounding"], unit=p["unit"],
                 write=p["write"])
    with open(out, "w") as fh:
        if p["write"] == "rates":
            fh.write("time_s,rate\n")
            t = np.arange(n) * tau0
            np.savetxt(fh, np.column_stack((t, values)), fmt=["%.6f", "%.9e"], delimiter=",")
        else:
            fh.write("increment\n")
            np.savetxt(fh, inc, fmt="%.9e")
    print(json.dumps(truth))


if __name__ == "__main__":
    main()
