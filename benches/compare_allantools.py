"""allantools on the arrays examples/stand_run.rs wrote: oadev, ohdev and mdev at octave taus
on each of the 8 channels (rate samples, tau0 = 4 ms), timed together (wall and CPU time)."""
import sys
import time

import allantools
import numpy as np

N = 2_700_000
TAU0 = 0.004
data = np.fromfile(sys.argv[1], dtype="<f8").reshape(8, N)
t = time.perf_counter()
c = time.process_time()
for y in data:
    for f in (allantools.oadev, allantools.ohdev, allantools.mdev):
        f(y, rate=1 / TAU0, data_type="freq", taus="octave")
dt = time.perf_counter() - t
cpu = time.process_time() - c
# The last field is CPU time (as examples/stand_run.rs reports its own), robust to other load.
print(
    f"allantools {allantools.__version__}: 8 channels x {N} samples, oadev+ohdev+mdev: "
    f"wall {dt:.3f} s, cpu: {cpu:.3f} s"
)
