#!/usr/bin/env python3
"""README.md is the first page: at most 200 lines, and every file it names exists.

The layers issue made README.md a first page (install, the first case, the families, where to
go next) and moved the dated records to docs/records/; this keeps it one as the project grows,
and catches a renamed case or document the page still points to.
Usage: check_first_page.py PROJECT_SOURCE_DIR
"""
import pathlib
import re
import sys

LIMIT = 200


def main() -> int:
    root = pathlib.Path(sys.argv[1])
    readme = root / "README.md"
    lines = readme.read_text(encoding="utf-8").splitlines()
    problems = []
    if len(lines) > LIMIT:
        problems.append(f"{readme}: {len(lines)} lines, more than the first page's {LIMIT}")
    named = set(re.findall(r"\b(?:cases|docs|scripts|examples|tests)/[A-Za-z0-9_./-]*[A-Za-z0-9_]", "\n".join(lines)))
    for path in sorted(named):
        if not (root / path).exists():
            problems.append(f"{readme}: names {path}, which does not exist")
    for p in problems:
        print(p)
    if not named:
        print(f"{readme}: names no file at all; the pattern above no longer matches it")
        return 1
    if problems:
        return 1
    print(f"{readme}: {len(lines)} lines, {len(named)} files named, all present")
    return 0


if __name__ == "__main__":
    sys.exit(main())
