import csv,sys
# usage: fa.py CSV [CSV2]: lists false alarms / differences. Runs are keyed by family, effect
# and draw (until session 18 by family and draw only, which mixed the effects of a detection set).
def load(f): return {(r['family'],r['effect'],r['draw']):r for r in csv.DictReader(open(f))}
a=load(sys.argv[1])
b=load(sys.argv[2]) if len(sys.argv)>2 else None
keys=['verdict','gap_after','named','named_params','qlim']
for k,r in sorted(a.items(), key=lambda kv:(kv[0][0],kv[0][1],int(kv[0][2]))):
    if b is None:
        if r['false_alarm'] in ('true','1'):
            print(k, r['verdict'], r['gap_before'], r['gap_after'], r['named_params'], 'qlim=',r['qlim'], 'intr=',r['intrinsic'])
    else:
        s=b.get(k)
        if s is None: continue
        if any(r[x]!=s[x] for x in ['verdict','named','gap_after']):
            print(k, 'FA' if r['false_alarm'] in ('true','1') else 'ok', '->', 'FA' if s['false_alarm'] in ('true','1') else 'ok', '|', r['verdict'], r['gap_after'], r['named_params'], '=>', s['verdict'], s['gap_after'], s['named_params'], s['qlim'])
if b:
    fa=lambda d:sum(1 for k in d if k in a and k in b and d[k]['false_alarm'] in ('true','1'))
    print('false alarms', fa(a), '->', fa(b), 'of', len([k for k in a if k in b]))
