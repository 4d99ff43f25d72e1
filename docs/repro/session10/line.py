import numpy as np
d=np.load('adis.npy'); fs=100.0
S=16; n=len(d)//S
for i,nm in [(3,'ax'),(4,'ay'),(5,'az'),(0,'gx')]:
    out=[]
    for s in range(S):
        x=d[s*n:(s+1)*n,i]; x=x-x.mean(); t=np.arange(len(x))/fs
        fr=np.linspace(0.555,0.575,401)
        A=[2*abs(np.mean(x*np.exp(-2j*np.pi*f*t))) for f in fr]
        k=int(np.argmax(A)); out.append('%.4f:%.1e'%(fr[k],A[k]))
    print(nm,' '.join(out))
# line shape over whole record for ax: zero-padded
x=d[:,3]-d[:,3].mean(); t=np.arange(len(x))/fs
fr=np.linspace(0.560,0.570,201)
A=np.array([2*abs(np.mean(x*np.exp(-2j*np.pi*f*t))) for f in fr])
k=np.argmax(A); print('whole ax peak', fr[k], A[k], 'halfwidth bins >half:', fr[A>A[k]/2][[0,-1]])
# harmonics amplitude
for h in [1,2,3,4,5]:
    f0=0.5646*h; fr=np.linspace(f0-0.01,f0+0.01,201)
    A=[2*abs(np.mean(x[:n]*np.exp(-2j*np.pi*f*t[:n]))) for f in fr]
    print('harm',h, max(A))
