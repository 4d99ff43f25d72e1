# The counter sawtooth AVAR (docs/gap.md, "The counter's sawtooth in the base model (session 23)")
# against a direct simulation of a counter with carry: python3 saw_check.py [seed] (needs numpy).
# Unit: family_gap rlg seed 221 draw 33 (dither 0.171 LSB, N 0.0995, LSB 1.084, 10.12 Hz), one hour.
import numpy as np, sys
rng=np.random.default_rng(int(sys.argv[1]) if len(sys.argv)>1 else 1)
tau0=0.0020491803278688526; lsb=1.0839646876279558; N=0.09953413285209203; sig=0.18549591662393322
w=10.1158*lsb; T=3600; n=int(T/tau0)
th = w*tau0*np.arange(1,n+1) + np.cumsum(N*np.sqrt(tau0)*rng.standard_normal(n))
x = rng.standard_normal(n)*sig
cnt = np.round((th+x)/lsb)   # carry: cumulative count = round(theta+x)
out = cnt*lsb                # output angle
def oavar(ph, m):
    d = ph[2*m:] - 2*ph[m:-m] + ph[:-2*m]
    return np.mean(d*d)/(2*(m*tau0)**2)
def avar_model(m, with_saw=True, nh=30):
    tau=m*tau0
    # white phase of total: R0 ~ sig^2 + lsb^2/12 - coherent
    A=[lsb**2/(2*k*k*np.pi**2)*np.exp(-4*np.pi**2*k*k*sig**2/lsb**2) for k in range(1,nh+1)]
    coh=sum(A)
    R0w = sig**2+lsb**2/12-coh
    v = 3*R0w/tau**2 + N**2/tau
    if with_saw:
        f=w/lsb
        def R(t): return sum(A[k-1]*np.cos(2*np.pi*k*f*t)*np.exp(-2*np.pi**2*k*k*N**2*t/lsb**2) for k in range(1,nh+1))
        v += (6*coh - 8*R(tau) + 2*R(2*tau))/(2*tau**2)
    return v
for m in [1,2,4,8,16,32,64,128,256,512,1024,2048,4096,8192,16384,32768,65536]:
    a=oavar(out,m); print(m, round(m*tau0,4), '%.4e'%a, 'ratio saw %.3f'%(a/avar_model(m)), 'nosaw %.3f'%(a/avar_model(m,False)))
