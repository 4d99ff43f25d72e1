# held2 s10: band_on.csv / band_off.csv (seed 10102): white rate + narrow-band noise at 20.7 Hz, rounded to 0.05 deg/s.
import numpy as np
rng=np.random.default_rng(10102)
fs=100.; n=360000
w=0.35*rng.standard_normal(n)
f0=20.7; bw=3.0; r=np.exp(-np.pi*bw/fs); a1=2*r*np.cos(2*np.pi*f0/fs); a2=-r*r
e=rng.standard_normal(n); y=np.zeros(n)
for i in range(2,n): y[i]=a1*y[i-1]+a2*y[i-2]+e[i]
y*=0.28/y.std()
for name,x in [('band_on',w+y),('band_off',w)]:
    np.savetxt(name+'.csv', np.round(x/0.05)*0.05, header='gz_dps', comments='', fmt='%.2f')
