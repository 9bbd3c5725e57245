"""Module dependency cycles per crate (issue 30): nodes are the file modules, edges the
`crate::a::b` / `super::` paths (and `use` groups) of their non-test code. A module using its
parent (or an ancestor) is not counted; a parent using its child is. Exit status 1 when a crate
has a cycle."""
import os,re,sys,subprocess
from collections import defaultdict
def modpath(src,f):
    rel=os.path.relpath(f,src)[:-3].split('/')
    if rel[-1] in('lib','main','mod'): rel=rel[:-1]
    return rel
def strip_tests(t):
    i=t.find('#[cfg(test)]')
    return t if i<0 else t[:i]
out=[]
found=0
for crate in sorted(os.listdir('crates')):
    src=f'crates/{crate}/src'
    if not os.path.isdir(src): continue
    mods={}
    for root,_,fs in os.walk(src):
        for fn in fs:
            if fn.endswith('.rs'):
                p=os.path.join(root,fn); mods[tuple(modpath(src,p))]=p
    g=defaultdict(set)
    for m,p in mods.items():
        if m and m[-1]=='tests': continue
        t=strip_tests(open(p).read())
        t=re.sub(r'//.*','',t)
        # expand use groups crudely: take first segments after crate::
        for mm in re.finditer(r'\b(crate|super)((?:::\w+)+)',t):
            base=list(m) if not p.endswith(('mod.rs','lib.rs','main.rs')) else list(m)
            segs=mm.group(2).split('::')[1:]
            if mm.group(1)=='crate': cur=[]
            else:
                # super from file module m: parent of m
                cur=list(m[:-1])
                while segs and segs[0]=='super': cur=cur[:-1]; segs=segs[1:]
            # longest module prefix
            tgt=None
            for k in range(len(segs),-1,-1):
                cand=tuple(cur+segs[:k])
                if cand in mods: tgt=cand;break
            if tgt is None: continue
            # also handle `use crate::a::{b, c}` groups
            if tgt!=m and not (len(tgt)<len(m) and m[:len(tgt)]==tgt):
                g[m].add(tgt)
        # `use crate::{a::X, b::{c, d}}` groups: expand into crate::a::X, crate::b::c ...
        def expand(prefix,body):
            items=[];depth=0;cur=''
            for ch in body:
                if ch=='{': depth+=1
                if ch=='}': depth-=1
                if ch==',' and depth==0: items.append(cur);cur=''
                else: cur+=ch
            items.append(cur)
            res=[]
            for it in items:
                it=it.strip()
                if not it: continue
                if '{' in it:
                    head=it[:it.index('{')].rstrip(':').strip()
                    res+=expand(prefix+'::'+head if head else prefix,it[it.index('{')+1:it.rindex('}')])
                else: res.append(prefix+'::'+it.split(' as ')[0].strip())
            return res
        for mm in re.finditer(r'\b((?:crate|super)(?:::\w+)*)::\{',t):
            i=mm.end();depth=1;j=i
            while depth: 
                if t[j]=='{': depth+=1
                elif t[j]=='}': depth-=1
                j+=1
            for path in expand(mm.group(1),t[i:j-1]):
                segs0=path.split('::')
                if segs0[0]=='crate': cur=[];segs=segs0[1:]
                else:
                    cur=list(m[:-1]);segs=segs0
                    while segs and segs[0]=='super': cur=cur[:-1];segs=segs[1:]
                tgt=None
                for k in range(len(segs),-1,-1):
                    cand=tuple(cur+segs[:k])
                    if cand in mods: tgt=cand;break
                if tgt is None or tgt==m or (len(tgt)<len(m) and m[:len(tgt)]==tgt): continue
                g[m].add(tgt)
    # Tarjan
    idx={};low={};st=[];on=set();sccs=[];c=[0]
    sys.setrecursionlimit(10000)
    def sc(v):
        idx[v]=low[v]=c[0];c[0]+=1;st.append(v);on.add(v)
        for w in g[v]:
            if w not in idx: sc(w);low[v]=min(low[v],low[w])
            elif w in on: low[v]=min(low[v],idx[w])
        if low[v]==idx[v]:
            comp=[]
            while True:
                w=st.pop();on.discard(w);comp.append(w)
                if w==v:break
            if len(comp)>1: sccs.append(comp)
    for v in list(mods):
        if v not in idx: sc(v)
    for comp in sccs:
        names=sorted('::'.join(x) or '(root)' for x in comp)
        found+=1
        print(crate,': cycle among',', '.join(names))
        cs=set(comp)
        for a in comp:
            for b in g[a]:
                if b in cs: print('    ','::'.join(a),'->','::'.join(b))
print(f'{found} module cycles')
sys.exit(1 if found else 0)
