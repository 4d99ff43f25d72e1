import numpy as np
d=np.load('adis.npy'); fs=100.0
L=30000  # 5-min pieces
for i,nm in [(3,'ax'),(4,'ay'),(5,'az')]:
    x=d[:,i].copy(); y=x.copy()
    for s in range(0,len(x),L):
        seg=x[s:s+L]; t=np.arange(len(seg))/fs; z=seg-seg.mean()
        fr=np.linspace(0.555,0.575,201)
        A=[abs(np.mean(z*np.exp(-2j*np.pi*f*t))) for f in fr]; f0=fr[int(np.argmax(A))]
        cols=[np.ones_like(t)]
        for h in range(1,6): cols+= [np.cos(2*np.pi*h*f0*t), np.sin(2*np.pi*h*f0*t)]
        X=np.array(cols).T; c,*_=np.linalg.lstsq(X,seg,rcond=None)
        y[s:s+L]=seg-X[:,1:]@c[1:]
    np.savetxt(nm+'_noline.csv', y, header=nm+'_g', comments='', fmt='%.7f')
    np.savetxt(nm+'_raw.csv', x, header=nm+'_g', comments='', fmt='%.5f')
np.savetxt('gz_raw.csv', d[:,2], header='gz_dps', comments='', fmt='%.2f')
