import numpy as np
d=np.load('adis.npy'); fs=100.0
x=d[:,2]-d[:,2].mean(); L=2**12; seg=len(x)//L; w=np.hanning(L); P=0
for s in range(seg): P=P+np.abs(np.fft.rfft(x[s*L:(s+1)*L]*w))**2
P/=seg*(w**2).sum()*fs/2; f=np.fft.rfftfreq(L,1/fs)
x2=d[:,0]-d[:,0].mean(); P2=0
for s in range(seg): P2=P2+np.abs(np.fft.rfft(x2[s*L:(s+1)*L]*w))**2
P2/=seg*(w**2).sum()*fs/2
for a in range(0,50,2):
    m=(f>=a)&(f<a+2); print('%2d-%2d Hz gz %.2e gx %.2e ratio %.2f'%(a,a+2,P[m].mean(),P2[m].mean(),P[m].mean()/P2[m].mean()))
# excess over gx-shaped floor scaled at 2-8 Hz
m=(f>=2)&(f<8); s=P[m].mean()/P2[m].mean()
ex=np.clip(P-s*P2,0,None); df=f[1]-f[0]
band=(f>12)&(f<32)
print('excess variance (deg/s)^2 %.3e -> rms %.3f deg/s; centroid %.2f Hz; rms width %.2f Hz'%(ex[band].sum()*df, np.sqrt(ex[band].sum()*df), (f*ex)[band].sum()/ex[band].sum(), np.sqrt((((f-(f*ex)[band].sum()/ex[band].sum())**2)*ex)[band].sum()/ex[band].sum())))
