import re,sys,os
# Lists functions longer than a limit (default 100 lines), from the `fn` line to its closing
# brace: python3 scripts/checks/fn_lengths.py src 150
pat=re.compile(r'^(\s*)(pub(\([^)]*\))?\s+)?(const\s+)?(unsafe\s+)?fn\s+(\w+)')
res=[]
for root,_,files in os.walk(sys.argv[1] if len(sys.argv)>1 else 'src'):
    for f in files:
        if not f.endswith('.rs'): continue
        p=os.path.join(root,f); L=open(p).read().split('\n')
        for i,l in enumerate(L):
            m=pat.match(l)
            if not m: continue
            ind=m.group(1)
            # find end: line == ind + '}'
            for j in range(i,len(L)):
                if L[j]==ind+'}' or (j==i and l.rstrip().endswith('}')) or (L[j].startswith(ind) and L[j].rstrip().endswith(';') and j==i):
                    break
            res.append((j-i+1,p,i+1,m.group(6)))
res.sort(reverse=True)
lim=int(sys.argv[2]) if len(sys.argv)>2 else 100
for r in res:
    if r[0]>lim: print(*r)
