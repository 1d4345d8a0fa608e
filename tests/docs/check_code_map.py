"""docs/architecture.md's code map names every source file of the product: each file of core/,
io/, converter/, python/ and freecad_plugin/ appears in it by its path (`core/mesh/poly_mesh.*`
for a header and its source, or the exact name). Usage: check_code_map.py SOURCE_DIR. Exit 0 when
every file is named, else 1 and the list of files missing."""

import os
import re
import sys

ROOTS = ("core", "io", "converter", "python/src", "python/subd2nurbs", "freecad_plugin/s2n_freecad")
EXTENSIONS = (".h", ".cpp", ".py")


def named_paths(text):
    """Every `path` in backquotes in the map: exact names and `stem.*` patterns (a `{a,b}` group
    of names is expanded)."""
    names = set()
    for token in re.findall(r"`([A-Za-z0-9_./{},*-]+)`", text):
        m = re.match(r"^(.*)\{([^}]*)\}(.*)$", token)
        parts = [m.group(1) + p + m.group(3) for p in m.group(2).split(",")] if m else [token]
        names.update(parts)
    return names


def main():
    source = sys.argv[1]
    text = open(os.path.join(source, "docs", "architecture.md"), encoding="utf-8").read()
    names = named_paths(text)
    missing = []
    for root in ROOTS:
        for folder, _, files in os.walk(os.path.join(source, root)):
            for f in sorted(files):
                if not f.endswith(EXTENSIONS):
                    continue
                path = os.path.relpath(os.path.join(folder, f), source)
                stem = os.path.splitext(path)[0]
                if path not in names and stem + ".*" not in names:
                    missing.append(path)
    if missing:
        print("docs/architecture.md does not name %d files:" % len(missing))
        for m in missing:
            print("  " + m)
        return 1
    print("docs/architecture.md names every source file")
    return 0


if __name__ == "__main__":
    sys.exit(main())
