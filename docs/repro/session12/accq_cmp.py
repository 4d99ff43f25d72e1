"""Compares two family_gap CSVs run for run: false alarms, and every run whose verdict, named
effects or final gap moved.  usage: python3 accq_cmp.py BEFORE.csv AFTER.csv"""
import csv,sys
a={(r['family'],r['effect'],r['draw']):r for r in csv.DictReader(open(sys.argv[1]))}
b={(r['family'],r['effect'],r['draw']):r for r in csv.DictReader(open(sys.argv[2]))}
fa=lambda d:sum(r['false_alarm']=='true' for r in d.values())
print('false alarms', fa(a), '->', fa(b), 'of', len(a), len(b))
for k in sorted(a, key=lambda k:(k[0],k[1],int(k[2]))):
    if k not in b: continue
    x,y=a[k],b[k]
    if (x['verdict'],x['named'],x['gap_after'])!=(y['verdict'],y['named'],y['gap_after']):
        print(k, x['false_alarm'],'->',y['false_alarm'], x['verdict'],x['named'],x['gap_after'],'=>',y['verdict'],y['named'],y['gap_after'])
