import numpy as np
rng=np.random.default_rng(2)
def ma(v,t,st):
    for _ in range(st):
        c=np.cumsum(np.concatenate([[0],v])); v=(c[t:]-c[:-t])/t
    return v
def avar(r,m):
    c=np.concatenate([[0],np.cumsum(r)]); yb=(c[m:]-c[:-m])/m; d=yb[m:]-yb[:-m]; return 0.5*np.mean(d*d)
def avar_from_R(R,m):
    # R[k] k=0..K
    K=len(R)-1
    Rf=lambda k: R[abs(k)] if abs(k)<=K else 0.0
    v=sum((m-abs(k))*Rf(k) for k in range(-m+1,m))/m**2
    c=sum((m-abs(k))*Rf(m+k) for k in range(-m+1,m))/m**2
    return v-c
n=2_000_000
for taps,st,kind in [(8,1,'ma'),(8,2,'ma'),(25,1,'ma'),(10,1,'fo')]:
    x=rng.normal(0,1,n)
    if kind=='ma': s=ma(x,taps,st)
    else:
        a=np.exp(-1/taps); from scipy.signal import lfilter; s=lfilter([1-a],[1,-a],x)
    sd=s.std(); sc=s-s.mean()
    K=200
    rho=np.array([np.mean(sc[k:]*sc[:len(sc)-k]) for k in range(K+1)])/sd**2
    for k in [1,2,2.5,3]:
        L=k*sd; q=L*np.round((s+0.37*L)/L)-0.37*L; e=q-s
        sig=sd/L
        nn=np.arange(1,60)[:,None]
        R=(L**2/(2*np.pi**2))*np.sum((1/nn**2)*(np.exp(-4*np.pi**2*nn**2*sig**2*(1-rho[None,:]))-np.exp(-4*np.pi**2*nn**2*sig**2)),axis=0)
        out=[]
        for m in [1,2,4,8,32,256]:
            ae=avar(e,m); at=avar(q,m); pr=avar_from_R(R,m); ps=avar(s,m)
            out.append(f"m{m}: e {ae/pr:.3f} out {at/(ps+pr):.3f}")
        print(kind,taps,st,'step/sd',k,' | '.join(out))
