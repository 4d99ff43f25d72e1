import numpy as np, sys
rng=np.random.default_rng(1)
tau0=0.0005; N=3.252e-3; lsb=0.1305
n=2_000_000
sdx=N/np.sqrt(tau0)
x=rng.normal(0,sdx,n)+0.0123
def ma(v,t,st):
    for _ in range(st):
        c=np.cumsum(np.concatenate([[0],v])); v=(c[t:]-c[:-t])/t
    return v
def avar(r,m):
    # overlapping avar of rate samples r at cluster m
    c=np.concatenate([[0],np.cumsum(r)])
    ybar=(c[m:]-c[:-m])/m
    d=ybar[m:]-ybar[:-m]
    return 0.5*np.mean(d*d)
for taps,st in [(8,1),(8,2),(25,1),(2,1)]:
  s=ma(x,taps,st)
  for k in [0.5,1,2,4]:
    L=k*s.std()
    q=L*np.round(s/L); e=q-s
    print(f"taps {taps} st {st} step/sd_f {k}: e sd/(L/sqrt12) {e.std()/(L/np.sqrt(12)):.3f} corr(e,s) {np.corrcoef(e,s)[0,1]:.3f} lag1 {np.corrcoef(e[1:],e[:-1])[0,1]:.3f}")
    for m in [1,2,4,8,16,32,64,256,1024]:
      a_s=avar(s,m); a_q=avar(q,m); a_e=avar(e,m); wf=L*L/12/m
      print(f"   m {m:5d} avar_s {a_s:.3e} avar_q/avar_s {a_q/a_s:.3f}  (avar_s+white floor)/avar_s {(a_s+wf)/a_s:.3f}  avar_e/wf {a_e/wf:.3f}")
