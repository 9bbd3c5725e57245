"""Library functions over 150 lines (signature to closing brace, by a brace scan that skips
strings and comments; code after a file's `#[cfg(test)]`, `tests.rs` and `tests/` aside),
largest first (issue 30). Exit status 1 when there is one."""
import re,sys,subprocess
files=subprocess.check_output("git ls-files 'crates/*/src/*.rs' 'crates/*/src/**/*.rs'",shell=True,text=True).split()
res=[]
for f in files:
    if f.endswith('tests.rs') or '/tests/' in f: continue
    L=open(f).read().split('\n')
    i=0
    in_test=False
    while i<len(L):
        l=L[i]
        if re.match(r'\s*#\[cfg\(test\)\]',l): break
        m=re.match(r'\s*(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?fn\s+(\w+)',l)
        if m:
            # find opening brace
            depth=0;started=False;j=i
            while j<len(L):
                s=re.sub(r'"(\\.|[^"\\])*"','""',L[j]); s=re.sub(r"//.*","",s)
                s=re.sub(r"'(\\.|[^'\\])'","''",s)
                for c in s:
                    if c=='{': depth+=1;started=True
                    elif c=='}': depth-=1
                if started and depth==0: break
                if not started and s.rstrip().endswith(';'): break
                j+=1
            n=j-i+1
            if started and n>150: res.append((n,f,i+1,m.group(6)))
            i=j+1 if started else i+1
            continue
        i+=1
for r in sorted(res,reverse=True): print(*r)
print(f'{len(res)} functions over 150 lines')
sys.exit(1 if res else 0)
