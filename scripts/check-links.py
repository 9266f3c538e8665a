#!/usr/bin/env python3
"""Checks that every relative link in the repository's markdown documents resolves: the file (or
folder) exists inside the repository, and the anchor, where one is given, names a heading of the
target as GitHub makes anchors of headings. Links to web addresses are not followed.

Usage: scripts/check-links.py [FILE.md ...]   (default: README.md, docs/*.md, PERFORMANCE.md,
ARCHITECTURE.md, FUZZING.md and the READMEs under assets/ and scripts/). Exit code 1 if a link is
broken, each broken link printed as FILE:LINE: TARGET: why.
"""

import glob
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
FENCE = re.compile(r"^\s*(```|~~~)")


def lines_outside_code(path, blank_inline_code=True):
    """(line number, text) of each line not inside a fenced code block; inline code is blanked
    unless told otherwise (headings keep theirs, which is part of their anchor)."""
    inside = False
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if FENCE.match(line):
                inside = not inside
            elif not inside:
                if blank_inline_code:
                    line = re.sub(r"`[^`]*`", lambda m: "`" * len(m.group(0)), line)
                yield number, line


def slug(heading):
    """GitHub's anchor of a heading: lower case, markup and punctuation but `-` and `_` dropped,
    spaces made `-`."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text.replace("`", ""))
    return text.replace(" ", "-")


def anchors(path):
    found, seen = set(), {}
    for _, line in lines_outside_code(path, blank_inline_code=False):
        m = re.match(r"^(#{1,6})\s+(.*?)\s*#*\s*$", line)
        if m:
            base = slug(m.group(2))
            n = seen.get(base, 0)
            seen[base] = n + 1
            found.add(base if n == 0 else f"{base}-{n}")
        for name in re.findall(r'<a\s+(?:name|id)="([^"]+)"', line):
            found.add(name)
    return found


def check(path):
    broken = []
    for number, line in lines_outside_code(path):
        for target in LINK.findall(line):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target):
                continue  # a web address or mailto:
            file_part, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
            rel = os.path.relpath(dest, ROOT)
            why = None
            if rel.startswith(".."):
                why = "outside the repository"
            elif not os.path.exists(dest):
                why = "no such file"
            elif anchor:
                if not dest.endswith(".md") or os.path.isdir(dest):
                    why = "an anchor into a file that is not markdown"
                elif anchor not in anchors(dest):
                    why = f"no heading '#{anchor}' in {rel}"
            if why:
                broken.append(f"{os.path.relpath(path, ROOT)}:{number}: {target}: {why}")
    return broken


def main(args):
    if args:
        files = [os.path.abspath(a) for a in args]
    else:
        names = ["README.md", "PERFORMANCE.md", "ARCHITECTURE.md", "FUZZING.md"]
        files = [os.path.join(ROOT, n) for n in names]
        for pattern in ["docs/*.md", "assets/**/README.md", "scripts/**/README.md"]:
            files += sorted(glob.glob(os.path.join(ROOT, pattern), recursive=True))
    broken, links = [], 0
    for path in files:
        broken += check(path)
        links += sum(len(LINK.findall(l)) for _, l in lines_outside_code(path))
    for b in broken:
        print(b)
    print(f"{len(files)} files, {links} links, {len(broken)} broken", file=sys.stderr)
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
