"""Source files of the library crates over 900 lines of code (the lines before a file's
`#[cfg(test)]`; test files `tests.rs` and `tests/` aside), largest first (issue 30).
Exit status 1 when there is one. `--top N` lists the N largest files instead."""
import os, sys

LIMIT = 900
res = []
for root, _, files in os.walk('crates'):
    if '/tests' in root or 'target' in root:
        continue
    for f in files:
        if not f.endswith('.rs') or f == 'tests.rs':
            continue
        p = os.path.join(root, f)
        lines = open(p).read().split('\n')
        n = len(lines)
        for i, l in enumerate(lines):
            if l.strip().startswith('#[cfg(test)]'):
                n = i
                break
        res.append((n, len(lines), p))
res.sort(reverse=True)
if '--top' in sys.argv:
    for n, t, p in res[: int(sys.argv[sys.argv.index('--top') + 1])]:
        print(n, t, p)
    sys.exit(0)
over = [r for r in res if r[0] > LIMIT]
for n, t, p in over:
    print(f'{p}: {n} lines of code (limit {LIMIT})')
print(f'{len(over)} files over {LIMIT} lines of code')
sys.exit(1 if over else 0)
