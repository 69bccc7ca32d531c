#!/usr/bin/env python3
"""The structure targets of issue 32, measured (for engineers; not run by CI):

  python3 benches/structure.py cycles DIR        # module import cycles of a crate's src dir
  python3 benches/structure.py functions N DIR.. # functions longer than N lines (fn line to its brace)
  python3 benches/structure.py codelines DIR..   # code lines: not blank, not comments, not #[cfg(test)] modules
  python3 benches/structure.py kinds DIR..       # those code lines split: use/mod items, attributes, the rest

`cycles`: nodes are the crate's modules (files); an edge a -> b when a's non-test code names a
path under b (`crate::`, `super::`, `self::` resolved; `use` groups expanded); edges between a
module and its own ancestors or descendants are not counted. Prints each strongly connected
component of more than one module. Text-based: a macro that builds paths is not seen.
"""
import os, re, sys

def strip_tests(s):
    """The source without #[cfg(test)] modules and // comments."""
    out = []; i = 0
    while True:
        m = re.search(r'#\[cfg\(test\)\]\s*(#\[[^\]]*\]\s*|//[^\n]*\n\s*)*(pub(\([^)]*\))?\s+)?mod\s+\w+\s*\{', s[i:])
        if not m:
            out.append(s[i:]); break
        out.append(s[i:i + m.start()]); j = i + m.end(); depth = 1
        while depth and j < len(s):
            if s[j] == '{': depth += 1
            elif s[j] == '}': depth -= 1
            j += 1
        i = j
    return ''.join(out)

def rust_files(root):
    for d, _, fs in os.walk(root):
        for f in sorted(fs):
            if f.endswith('.rs'):
                yield os.path.join(d, f)

def cycles(root):
    mods = {}
    for p in rust_files(root):
        parts = os.path.relpath(p, root)[:-3].split(os.sep)
        if parts[-1] in ('mod', 'lib', 'main'): parts = parts[:-1]
        mods['::'.join(parts)] = p
    def resolve(path, cur):
        segs = path.split('::')
        if segs[0] == 'crate': base = []; segs = segs[1:]
        else:
            base = cur.split('::') if cur else []
            while segs and segs[0] in ('super', 'self'):
                if segs[0] == 'super': base = base[:-1]
                segs = segs[1:]
        full = base + segs
        for k in range(len(full), 0, -1):
            if '::'.join(full[:k]) in mods: return '::'.join(full[:k])
        return None
    edges = {m: set() for m in mods}
    for m, p in mods.items():
        s = re.sub(r'//[^\n]*', '', strip_tests(open(p).read()))
        toks = re.findall(r'\b(?:crate|super|self)(?:::\w+)+', s)
        for base, group in re.findall(r'\buse\s+((?:crate|super|self)(?:::\w+)*)::\{([^}]*)\}', s):
            toks += [base + '::' + it.strip().split(' as ')[0].split('::')[0] for it in group.split(',') if it.strip()]
        for tok in toks:
            t = resolve(tok, m)
            if t and t != m and not t.startswith(m + '::') and not m.startswith(t + '::'):
                edges[m].add(t)
    sys.setrecursionlimit(10000)
    idx, low, st, on, sccs, c = {}, {}, [], set(), [], [0]
    def dfs(v):
        idx[v] = low[v] = c[0]; c[0] += 1; st.append(v); on.add(v)
        for w in edges[v]:
            if w not in idx: dfs(w); low[v] = min(low[v], low[w])
            elif w in on: low[v] = min(low[v], idx[w])
        if low[v] == idx[v]:
            comp = []
            while True:
                w = st.pop(); on.discard(w); comp.append(w)
                if w == v: break
            if len(comp) > 1: sccs.append(comp)
    for v in mods:
        if v not in idx: dfs(v)
    for comp in sccs:
        print('cycle:', ' '.join(sorted(comp)))
        for a in sorted(comp):
            print('   ', a, '->', ', '.join(sorted(b for b in edges[a] if b in comp)))
    print(f'{root}: {len(mods)} modules, {len(sccs)} cycles')
    return len(sccs)

def functions(limit, roots):
    n = 0
    for root in roots:
        for p in rust_files(root):
            lines = strip_tests(open(p).read()).split('\n')
            depth, stack = 0, []
            for k, l in enumerate(lines):
                code = re.sub(r'"(\\.|[^"\\])*"', '""', re.sub(r'//.*', '', l))
                m = re.match(r'\s*(pub(\([^)]*\))?\s+)?(const\s+)?(unsafe\s+)?(extern\s+"C"\s+)?fn\s+(\w+)', code)
                if m and not code.rstrip().endswith(';'):
                    stack.append((m.group(6), k + 1, depth))
                for ch in code:
                    if ch == '{': depth += 1
                    elif ch == '}':
                        depth -= 1
                        if stack and stack[-1][2] == depth:
                            name, start, _ = stack.pop()
                            if k + 2 - start > limit:
                                print(f'{k + 2 - start:4d} {p}:{start} {name}'); n += 1
    print(f'{n} functions over {limit} lines (test modules left out)')

def code_lines(path):
    """The lines `codelines` counts, stripped: not blank, not comments, not test modules."""
    return [t for t in (l.strip() for l in strip_tests(open(path).read()).split('\n')) if t and not t.startswith('//')]

def codelines(roots):
    print(sum(len(code_lines(p)) for root in roots for p in rust_files(root)))

def kinds(roots):
    c = {'files': 0, 'use/mod': 0, 'attributes': 0, 'other': 0}
    for root in roots:
        for p in rust_files(root):
            c['files'] += 1
            cont = None  # the kind of a statement or attribute that goes on to the next line
            depth = 0
            for t in code_lines(p):
                if cont == 'use/mod':
                    c[cont] += 1
                    cont = None if t.endswith(';') else cont
                elif cont == 'attributes':
                    c[cont] += 1
                    depth += t.count('[') + t.count('(') - t.count(']') - t.count(')')
                    cont = cont if depth > 0 else None
                elif re.match(r'(pub(\([^)]*\))? )?(use|mod) ', t) and (t.endswith(';') or (' use ' in ' ' + t and t.endswith('{'))):
                    c['use/mod'] += 1
                    cont = None if t.endswith(';') else 'use/mod'
                elif t.startswith('#'):
                    c['attributes'] += 1
                    depth = t.count('[') + t.count('(') - t.count(']') - t.count(')')
                    cont = 'attributes' if depth > 0 else None
                else:
                    c['other'] += 1
    print(' '.join(f'{k} {v}' for k, v in c.items()))

if __name__ == '__main__':
    cmd, args = sys.argv[1], sys.argv[2:]
    if cmd == 'cycles': sys.exit(1 if sum(cycles(a) for a in args) else 0)
    elif cmd == 'functions': functions(int(args[0]), args[1:])
    elif cmd == 'codelines': codelines(args)
    elif cmd == 'kinds': kinds(args)
    else: sys.exit(__doc__)
