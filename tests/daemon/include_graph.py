#!/usr/bin/env python3
"""include_graph.py: the include graph of daemon/ between its modules, and
its circles (issue 33: "the include graph of daemon/ has no circle").

A module is a file stem in a folder: daemon/server/queue.c and
daemon/server/queue.h are one module, server/queue. A module depends on
every module whose header one of its files includes ("runner/job.h", or
"jobs.h" beside it). A header that declares functions defined in other
modules' .c files (a shared internal header such as the old
jobs_internal.h, declaring what five files define) adds an edge from each
file that includes it and uses one of those functions to the module that
defines it: a circle hidden behind one shared header is still a circle.

    include_graph.py [--root DIR] [--dot] [--allow A,B,...] [--self-test]

prints the edges and every circle (the strongly connected components with
more than one module), and exits 1 when there is one. Each run first checks
itself on small made-up trees (a circle through a shared header, one
through direct includes, and layers without one) and fails unless it
finds exactly their circles; --self-test does only that. --allow names the
modules of one known circle that is reported but does not fail the run
(a circle that is about to go in another branch); any other circle, or a
larger one, fails."""

import argparse
import os
import re
import sys
import tempfile

INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)
# A prototype or a definition's first line: a name followed by "(" at the
# outer level of a declaration (not a call inside a body: bodies are indented).
DECLARED = re.compile(r'^[A-Za-z_][\w \t\*]*?\b([a-z_][a-z0-9_]*)\s*\([^;{]*?\)\s*;', re.M | re.S)
DEFINED = re.compile(r'^[A-Za-z_][\w \t\*]*?\b([a-z_][a-z0-9_]*)\s*\([^;{]*?\)\s*\{', re.M | re.S)


def strip_comments(text):
    text = re.sub(r'/\*.*?\*/', lambda m: '\n' * m.group(0).count('\n'), text, flags=re.S)
    return re.sub(r'//[^\n]*', '', text)


def module_of(root, path):
    rel = os.path.relpath(path, root)
    return os.path.splitext(rel)[0].replace(os.sep, '/')


def build(root):
    files = []
    for folder, _, names in os.walk(root):
        for n in sorted(names):
            if n.endswith(('.c', '.h')):
                files.append(os.path.join(folder, n))
    texts = {f: strip_comments(open(f, encoding='utf-8', errors='replace').read()) for f in files}
    by_path = {os.path.normpath(f): f for f in files}
    defined_in = {}
    for f, t in texts.items():
        if f.endswith('.c'):
            for name in DEFINED.findall(t):
                if not re.search(r'\bstatic\b[^\n]*\b' + name + r'\s*\(', t):
                    defined_in.setdefault(name, set()).add(module_of(root, f))
    declared = {}
    for f, t in texts.items():
        if f.endswith('.h'):
            declared[f] = set(DECLARED.findall(t))
    edges = {}
    for f, t in texts.items():
        m = module_of(root, f)
        edges.setdefault(m, set())
        words = set(re.findall(r'[A-Za-z_]\w*', t))
        for inc in INCLUDE.findall(t):
            for cand in (os.path.join(os.path.dirname(f), inc), os.path.join(root, inc)):
                cand = os.path.normpath(cand)
                if cand in by_path:
                    header = by_path[cand]
                    target = module_of(root, header)
                    if target != m:
                        edges[m].add(target)
                    # what the header declares and another module defines:
                    # using it is depending on that module
                    for name in declared.get(header, ()) & words:
                        for owner in defined_in.get(name, ()):
                            if owner != m:
                                edges[m].add(owner)
                    break
    return edges


def circles(edges):
    """Tarjan's strongly connected components with more than one module."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def report(edges, dot):
    if dot:
        print('digraph daemon {')
        for a in sorted(edges):
            for b in sorted(edges[a]):
                print(f'  "{a}" -> "{b}";')
        print('}')
    else:
        for a in sorted(edges):
            print(f'{a} -> {", ".join(sorted(edges[a])) or "-"}')
    found = circles(edges)
    for c in found:
        print('circle: ' + ' <-> '.join(c))
    if not found:
        print(f'no circle among {len(edges)} modules')
    return found


def self_test(verbose=True):
    def tree(files):
        d = tempfile.mkdtemp()
        for name, text in files.items():
            p = os.path.join(d, name)
            os.makedirs(os.path.dirname(p), exist_ok=True)
            with open(p, 'w') as f:
                f.write(text)
        return d

    # a.c and b.c both include one shared header that declares what each
    # defines: a and b call each other through it.
    shared = tree({
        's/shared.h': 'int fm_a(int x);\nint fm_b(int x);\n',
        's/a.c': '#include "shared.h"\nint fm_a(int x)\n{\n    return fm_b(x);\n}\n',
        's/b.c': '#include "shared.h"\nint fm_b(int x)\n{\n    return fm_a(x);\n}\n',
    })
    direct = tree({
        's/a.h': 'int fm_a(void);\n', 's/a.c': '#include "b.h"\nint fm_a(void)\n{\n    return 0;\n}\n',
        's/b.h': 'int fm_b(void);\n', 's/b.c': '#include "s/a.h"\nint fm_b(void)\n{\n    return 0;\n}\n',
    })
    layered = tree({
        's/a.h': 'int fm_a(void);\n', 's/a.c': '#include "a.h"\n#include "b.h"\nint fm_a(void)\n{\n    return fm_b();\n}\n',
        's/b.h': 'int fm_b(void);\n', 's/b.c': '#include "b.h"\nstatic int fm_a(void)\n{\n    return 1;\n}\nint fm_b(void)\n{\n    return fm_a();\n}\n',
    })
    ok = True
    for name, root, want in (('shared header', shared, [['s/a', 's/b']]),
                             ('direct includes', direct, [['s/a', 's/b']]),
                             ('layers', layered, [])):
        got = circles(build(root))
        if verbose or got != want:
            print(f'self-test {name}: {got}, expected {want}')
        ok = ok and got == want
    return ok


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--root', default=os.path.join(os.path.dirname(__file__), '..', '..', 'daemon'))
    ap.add_argument('--dot', action='store_true')
    ap.add_argument('--allow', action='append', default=[])
    ap.add_argument('--self-test', action='store_true')
    a = ap.parse_args()
    if a.self_test:
        return 0 if self_test() else 1
    if not self_test(verbose=False):
        print('the circle finder failed its self-test', file=sys.stderr)
        return 2
    root = os.path.normpath(a.root)
    if not os.path.isdir(root):
        print(f'{root}: no such folder', file=sys.stderr)
        return 2
    allowed = [sorted(x.split(',')) for x in a.allow]
    failing = [c for c in report(build(root), a.dot) if c not in allowed]
    for c in failing:
        print('not allowed: ' + ' <-> '.join(c))
    return 1 if failing else 0


if __name__ == '__main__':
    sys.exit(main())
