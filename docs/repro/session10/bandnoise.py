# held2 s10: synthetic channels for the real-recording findings (seed 10102/10103).
import numpy as np, sys
fs=100.; n=360000
def resonance(rng, f0, bw, rms):
    r=np.exp(-np.pi*bw/fs); a1=2*r*np.cos(2*np.pi*f0/fs); a2=-r*r
    e=rng.standard_normal(n); y=np.zeros(n)
    for i in range(2,n): y[i]=a1*y[i-1]+a2*y[i-2]+e[i]
    return y*rms/y.std()
rng=np.random.default_rng(10103)
t=np.arange(n)/fs
w=0.0040*rng.standard_normal(n)
# pure coherent line
pure=8.7e-4*np.sin(2*np.pi*0.5646*t)
# wandering line: frequency a slow random walk (std ~0.0015 Hz over the run) + 19% third harmonic
df=np.cumsum(rng.standard_normal(n)); df=0.0015*df/np.abs(df).max()
ph=2*np.pi*np.cumsum(0.5646+df)/fs
wand=8.7e-4*(np.sin(ph)+0.19*np.sin(3*ph+0.4))
hump=resonance(rng,10.5,2.0,0.0012)
for name,x in [('acc_pure',w+pure),('acc_wander',w+wand),('acc_wander_hump',w+wand+hump)]:
    np.savetxt(name+'.csv', np.round(x/0.00333)*0.00333, header='ax_g', comments='', fmt='%.5f')
