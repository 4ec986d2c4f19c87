#!/usr/bin/env python3
"""check_links.py: every relative link in the repository's Markdown files
resolves to a file or folder of the tree, and every #anchor to a heading of
the file it names. Usage: tests/docs/check_links.py [ROOT]; prints each broken
link as FILE:LINE: TARGET and exits 1 when there is any."""
import os
import re
import subprocess
import sys

LINK = re.compile(r'!?\[[^\]]*\]\(([^)\s]+)(?:\s+"[^"]*")?\)')
FENCE = re.compile(r'^\s*(```|~~~)')


def anchors(path):
    """GitHub's anchors of a Markdown file's headings."""
    out = set()
    with open(path, encoding='utf-8') as f:
        fenced = False
        for line in f:
            if FENCE.match(line):
                fenced = not fenced
                continue
            if fenced or not line.startswith('#'):
                continue
            text = line.lstrip('#').strip().lower()
            text = re.sub(r'[^\w\- ]', '', text)
            out.add(text.replace(' ', '-'))
    return out


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else '.')
    files = subprocess.check_output(['git', 'ls-files', '*.md'], cwd=root, text=True).split()
    files = [f for f in files if os.path.exists(os.path.join(root, f))]
    bad = checked = 0
    for rel in files:
        path = os.path.join(root, rel)
        with open(path, encoding='utf-8') as f:
            fenced = False
            for n, line in enumerate(f, 1):
                if FENCE.match(line):
                    fenced = not fenced
                    continue
                if fenced:
                    continue
                for target in LINK.findall(re.sub(r'`[^`]*`', '', line)):
                    if re.match(r'^[a-z][a-z0-9+.-]*:', target):
                        continue  # http:, https:, mailto:
                    checked += 1
                    file_part, _, anchor = target.partition('#')
                    dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
                    if not dest.startswith(root) or not os.path.exists(dest):
                        print(f'{rel}:{n}: {target}')
                        bad += 1
                    elif anchor and dest.endswith('.md') and anchor not in anchors(dest):
                        print(f'{rel}:{n}: {target} (no heading #{anchor})')
                        bad += 1
    print(f'{checked} relative links in {len(files)} Markdown files, {bad} broken')
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main())
