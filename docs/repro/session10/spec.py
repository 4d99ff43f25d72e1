import numpy as np
d=np.loadtxt('adis.csv',delimiter=',',skiprows=2)
np.save('adis.npy',d)
names=['gx','gy','gz','ax','ay','az']
fs=100.0
for i,n in enumerate(names):
    x=d[:,i]; x=x-x.mean()
    # Welch PSD with 2^16 segments
    L=2**16; seg=len(x)//L
    P=np.zeros(L//2+1)
    w=np.hanning(L)
    for s in range(seg):
        y=x[s*L:(s+1)*L]*w
        P+=np.abs(np.fft.rfft(y))**2
    P/= seg*(w**2).sum()*fs/2
    f=np.fft.rfftfreq(L,1/fs)
    # find lines: ratio to running median
    from numpy.lib.stride_tricks import sliding_window_view
    k=401
    pad=np.pad(P,(k//2,k//2),mode='edge')
    med=np.median(sliding_window_view(pad,k),axis=1)
    r=P/med
    idx=np.argsort(r)[::-1][:8]
    print(n, 'std', x.std(), 'unique steps', np.unique(np.round(np.diff(np.unique(d[:,i])),6))[:3])
    for j in sorted(idx): print('   f %.4f Hz  P/median %.1f  P %.3e' % (f[j], r[j], P[j]))
    # PSD shape at high freq: ratio of PSD near 45-50 Hz vs 1-5 Hz
    def band(a,b): m=(f>=a)&(f<b); return P[m].mean()
    print('   PSD 1-5 Hz %.3e, 10-20 %.3e, 20-30 %.3e, 30-40 %.3e, 40-50 %.3e' % (band(1,5),band(10,20),band(20,30),band(30,40),band(40,50)))
