#!/usr/bin/env python3
"""The folders are the layers (docs/ARCHITECTURE.md): no source file includes a header of a
layer above its own. Run from anywhere: check_layers.py SOURCE_DIR. Prints every offending
include as FILE:LINE and exits 1; prints the number of includes checked and exits 0 otherwise."""
import pathlib
import re
import sys

# Bottom to top. A folder may include its own layer and every layer below it.
LAYERS = ["quadrature", "basis", "solver", "cases", "families", "studies", "app"]
# Folders that sit on top of everything (they are programs and tests, not libraries).
ON_TOP = {"app", "python", "bench", "tests", "fuzz"}
# Inside basis/, the shared core may not include a family's construction.
BASIS_SHARED = {"core", "exact", "tmesh"}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/([^"]+)"')


def rank(folder):
    return len(LAYERS) if folder in ON_TOP else LAYERS.index(folder)


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    offending, checked = [], 0
    for folder in LAYERS + sorted(ON_TOP - {"app"}):
        for path in sorted((root / folder).rglob("*")):
            if path.suffix not in (".cpp", ".hpp", ".h", ".inc") or "build" in path.relative_to(root).parts[:1]:
                continue
            for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
                m = INCLUDE.match(line)
                if not m or m.group(1) not in LAYERS:
                    continue
                checked += 1
                target = m.group(1)
                where = f"{path.relative_to(root)}:{number}"
                if target == "app" and folder != "app":
                    offending.append(f"{where}: {folder}/ includes app/ (the command line; call studies/ instead)")
                elif rank(target) > rank(folder):
                    offending.append(f"{where}: {folder}/ includes {target}/ (a layer above it)")
                sub = path.relative_to(root / folder).parts
                if folder == "basis" and target == "basis" and sub[0] in BASIS_SHARED:
                    below = m.group(2).split("/")[0]
                    if below not in BASIS_SHARED:
                        offending.append(f"{where}: basis/{sub[0]}/ includes basis/{below}/ (a family's construction)")
    for o in offending:
        print(o)
    if offending:
        print(f"{len(offending)} include(s) cross the layers upward")
        return 1
    print(f"{checked} includes checked: none crosses the layers upward")
    return 0


if __name__ == "__main__":
    sys.exit(main())
