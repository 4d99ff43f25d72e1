#!/usr/bin/env python3
"""The real ADIS16405 gyro z band, piece by piece (docs/gap.md, "Real recording (session 12)").

usage: xz -dc ../shared/reference/imu/adis16405_imu1_static_100hz.csv.xz > adis.csv
       python3 adis_gz_spectrum.py adis.csv
Welch spectra (numpy, scipy) of gyro z against gyro x (same part, same filter, no band; gyro z's
white level is 0.9 of gyro x's below 17 Hz): the excess over 17-30 Hz of the whole record, then
per 250-s piece its peak, centroid, rms width and rms.
"""
import sys
import numpy as np
from scipy.signal import welch

FS = 100.0
d = np.loadtxt(sys.argv[1], delimiter=",", skiprows=2, usecols=(0, 2))
gx, gz = d[:, 0], d[:, 1]


def excess(x, z, nper):
    f, px = welch(x - x.mean(), FS, nperseg=nper)
    _, pz = welch(z - z.mean(), FS, nperseg=nper)
    m = (f > 17) & (f < 30)
    e = np.clip(pz - 0.9 * px, 0, None) * m
    c = (f * e).sum() / e.sum()
    w = np.sqrt(((f - c) ** 2 * e).sum() / e.sum())
    return f, pz / px, e, c, w, np.sqrt(e.sum() * (f[1] - f[0]))


f, ratio, e, c, w, rms = excess(gx, gz, 4096)
half = f[e > e.max() / 2]
print(f"whole record: peak {f[e.argmax()]:.2f} Hz, half power {half.min():.2f}-{half.max():.2f} Hz, "
      f"centroid {c:.2f} Hz, rms width {w:.2f} Hz, excess rms {rms:.3f} deg/s")
for lo, hi in [(17, 19), (19, 21), (21, 23), (23, 26), (26, 29), (40, 42)]:
    s = (f >= lo) & (f < hi)
    print(f"  gyro z / gyro x spectrum {lo}-{hi} Hz: {ratio[s].mean():.2f}")
n = 25000
for k in range(len(gz) // n):
    _, _, e, c, w, rms = excess(gx[k * n:(k + 1) * n], gz[k * n:(k + 1) * n], 2048)
    fk = np.fft.rfftfreq(2048, 1 / FS)
    print(f"{k * n / FS:6.0f} s  peak {fk[e.argmax()]:.2f}  centroid {c:.2f}  rms width {w:.2f}  rms {rms:.3f}")
