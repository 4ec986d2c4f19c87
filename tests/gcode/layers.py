#!/usr/bin/env python3
"""layers.py: the G-code module's layering holds (docs/gcode.md, "Source
layout"): toolpaths/gcode/machine/ is the one machine every dialect drives and
knows no dialect; each dialect's front end (every other folder) includes only
its own headers and machine/machine.h, and calls nothing of another dialect;
gcode.c, the dialect table, includes no front end's header.

Checked on the sources: quoted #include lines, and calls of functions by the
folder that defines them (a function defined in a dialect's folder and
called from machine/ or another dialect is a circle through the layers).
Run with the module folder (default: the repository's); exits 1 listing every
violation. --self-test copies the tree, plants an include and a call that
break the rules, and checks that both are found (so this test can fail)."""
import os
import re
import shutil
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT = os.path.join(HERE, '..', '..', 'toolpaths', 'gcode')
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)
DEFINE = re.compile(r'^[a-z][^\n;=]*?\b(gc_[a-z0-9_]+)\s*\([^;{]*\)\s*\{', re.M)
CALL = re.compile(r'\b(gc_[a-z0-9_]+)\s*\(')


def folder_of(root, path):
    rel = os.path.relpath(path, root)
    return rel.split(os.sep)[0] if os.sep in rel else ''


def sources(root):
    for dirpath, _, names in os.walk(root):
        for n in sorted(names):
            if n.endswith(('.c', '.h')):
                yield os.path.join(dirpath, n)


def strip_comments(text):
    text = re.sub(r'/\*.*?\*/', ' ', text, flags=re.S)
    return re.sub(r'//[^\n]*', ' ', text)


def check(root):
    bad = []
    files = list(sources(root))
    dialects = sorted({folder_of(root, f) for f in files} - {'', 'machine'})
    if 'machine' not in {folder_of(root, f) for f in files} or not dialects:
        return ['%s: expected machine/ and at least one dialect folder' % root]
    defined = {}
    for f in files:
        if f.endswith('.c'):
            for m in DEFINE.finditer(strip_comments(open(f).read())):
                defined[m.group(1)] = folder_of(root, f)
    for f in files:
        here = folder_of(root, f)
        text = open(f).read()
        rel = os.path.relpath(f, root)
        for name in INCLUDE.findall(text):
            target = name.split('/')
            if here == 'machine':
                if any(d in target for d in dialects):
                    bad.append('%s: #include "%s": the machine includes no dialect' % (rel, name))
            elif here == '':
                if any(d in target for d in dialects):
                    bad.append('%s: #include "%s": gcode.c names front ends by their '
                               'gc_front_end only' % (rel, name))
            else:
                own = os.path.exists(os.path.join(os.path.dirname(f), name))
                if not own and name != 'toolpaths/gcode/machine/machine.h':
                    bad.append('%s: #include "%s": a front end includes its own headers and '
                               'toolpaths/gcode/machine/machine.h only' % (rel, name))
        if f.endswith('.c'):
            for fn in sorted(set(CALL.findall(strip_comments(text)))):
                owner = defined.get(fn)
                if owner in dialects and owner != here:
                    bad.append('%s: calls %s() of the %s front end' % (rel, fn, owner))
    return bad


def self_test(root):
    tmp = tempfile.mkdtemp()
    try:
        copy = os.path.join(tmp, 'gcode')
        shutil.copytree(root, copy)
        if check(copy):
            return ['the tree itself does not pass: ' + '; '.join(check(copy))]
        dialects = sorted(d for d in os.listdir(copy)
                          if os.path.isdir(os.path.join(copy, d)) and d != 'machine')
        target = dialects[0]
        header = sorted(n for n in os.listdir(os.path.join(copy, target)) if n.endswith('.h'))[0]
        victim = os.path.join(copy, 'machine', 'line.c')
        with open(victim, 'a') as out:
            out.write('\n#include "../%s/%s"\n' % (target, header))
        found = check(copy)
        if not any('machine includes no dialect' in b for b in found):
            return ['a planted include of %s/%s from machine/ was not found' % (target, header)]
        shutil.rmtree(copy)
        shutil.copytree(root, copy)
        fn = None
        for f in sources(os.path.join(copy, target)):
            if f.endswith('.c'):
                m = DEFINE.search(strip_comments(open(f).read()))
                if m:
                    fn = m.group(1)
                    break
        with open(victim, 'a') as out:
            out.write('\nstatic void planted(void) { %s(0); }\n' % fn)
        found = check(copy)
        if not any(('calls %s()' % fn) in b for b in found):
            return ['a planted call of %s() from machine/ was not found' % fn]
        return []
    finally:
        shutil.rmtree(tmp)


def main(argv):
    args = [a for a in argv[1:] if not a.startswith('--')]
    root = os.path.abspath(args[0] if args else DEFAULT)
    bad = check(root)
    if '--self-test' in argv:
        bad += self_test(root)
    for b in bad:
        print('layers.py: ' + b)
    if not bad:
        print('layers.py: %s: machine/ knows no dialect; front ends include only machine.h' % root)
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
