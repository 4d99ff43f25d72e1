import numpy as np
d=np.load('adis.npy'); fs=100.0
names=['gx','gy','gz','ax','ay','az']
S=8; n=len(d)//S
def psd(x,L=2**13):
    x=x-x.mean(); seg=len(x)//L; w=np.hanning(L); P=0
    for s in range(seg):
        P=P+np.abs(np.fft.rfft(x[s*L:(s+1)*L]*w))**2
    return np.fft.rfftfreq(L,1/fs), P/(seg*(w**2).sum()*fs/2)
for i,nm in enumerate(names):
    row=[]
    for s in range(S):
        x=d[s*n:(s+1)*n,i]
        f,P=psd(x)
        b=lambda a,c: P[(f>=a)&(f<c)].mean()
        if nm=='gz': row.append('%.2f' % (b(17,24)/b(2,8)))
        elif nm[0]=='a':
            # line power: amplitude of 0.5646 line via direct DFT
            t=np.arange(len(x))/fs; z=(x-x.mean())*np.exp(-2j*np.pi*0.5646*t); A=2*abs(z.mean())
            row.append('%.2e/%.2e' % (A, x.std()))
        else: row.append('%.2e' % b(2,8))
        row.append('m=%.4f'%x.mean())
    print(nm, ' '.join(row))
