"""core/'s folders form layers: no two folders include each other, directly or through others
(core/nurbs, the patch types and their evaluation, is the ground floor every folder may use).
Usage: check_layers.py SOURCE_DIR. Exit 0 when the folder include graph has no cycle, else 1 and
the folder pairs on a cycle with the includes that close it."""

import itertools
import os
import re
import sys


def folder_edges(source):
    edges = {}
    core = os.path.join(source, "core")
    for folder, _, files in os.walk(core):
        for f in files:
            if not f.endswith((".h", ".cpp")):
                continue
            path = os.path.join(folder, f)
            a = os.path.relpath(path, core).split(os.sep)[0]
            with open(path, encoding="utf-8") as fh:
                for m in re.finditer(r'#include "core/([a-z_]+)/([^"]+)"', fh.read()):
                    if m.group(1) != a:
                        edges.setdefault((a, m.group(1)), []).append(
                            "%s includes core/%s/%s" % (os.path.relpath(path, source), m.group(1), m.group(2)))
    return edges


def main():
    edges = folder_edges(sys.argv[1])
    folders = sorted({x for e in edges for x in e})
    reach = {f: {b for (a, b) in edges if a == f} for f in folders}
    changed = True
    while changed:
        changed = False
        for f in folders:
            grown = set(reach[f])
            for g in reach[f]:
                grown |= reach[g]
            if grown != reach[f]:
                reach[f], changed = grown, True
    pairs = [(a, b) for a, b in itertools.combinations(folders, 2) if b in reach[a] and a in reach[b]]
    if pairs:
        print("core folders that include each other: %s" % pairs)
        for (a, b), why in sorted(edges.items()):
            if (a, b) in pairs or (b, a) in pairs:
                print("  " + "\n  ".join(why))
        return 1
    print("core's %d folders form layers (no include cycle)" % len(folders))
    return 0


if __name__ == "__main__":
    sys.exit(main())
