#!/usr/bin/env python3
"""Runs every entry of catalogue.toml against the real knotwork binary.

Each entry names a bad input file of this folder, the command line that reads it, and the one
line knotwork must print. The check is exact (but for the numbers an entry lists as `varies`,
rounding noise that differs by CPU): the exit code, stderr being that single line,
stdout empty, and no file or folder appearing anywhere in the scratch copy of this folder
(no output directory, no hidden staging folder, no partial file).

Usage: check_catalogue.py KNOTWORK_BINARY [NAME ...]   (names select entries by file)
"""
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))


def listing(folder):
    found = set()
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            found.add(os.path.relpath(os.path.join(root, name), folder))
    return found


def check(binary, entry, scratch):
    before = listing(scratch)
    args = shlex.split(entry["args"])
    try:
        done = subprocess.run([binary] + args, cwd=scratch, capture_output=True, text=True, timeout=300)
    except subprocess.TimeoutExpired:
        return ["did not finish in 300 s"]
    problems = []
    expected_code = entry.get("code", 2)
    if done.returncode != expected_code:
        problems.append(f"exit code {done.returncode}, expected {expected_code}")
    lines = done.stderr.splitlines()
    expected = "knotwork: error: " + entry["error"]
    # `varies`: numbers of the line that are rounding noise (an ill-conditioned value in double
    # precision, which differs with the CPU's vector math); any number matches there.
    pattern = re.escape(expected)
    for number in entry.get("varies", []):
        if re.escape(number) not in pattern:
            return [f"`varies` names {number}, which is not in the expected line"]
        pattern = pattern.replace(re.escape(number), r"-?[0-9]+(\.[0-9]+)?(e[-+]?[0-9]+)?", 1)
    if not (len(lines) == 1 and re.fullmatch(pattern, lines[0])):
        problems.append("stderr was:\n      " + "\n      ".join(lines or ["(nothing)"]) + "\n    expected:\n      " + expected)
    if done.stdout:
        problems.append("stdout was not empty: " + done.stdout[:200])
    appeared = sorted(listing(scratch) - before)
    if appeared:
        problems.append("files appeared: " + ", ".join(appeared))
    return problems


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    binary = os.path.abspath(sys.argv[1])
    wanted = set(sys.argv[2:])
    with open(os.path.join(HERE, "catalogue.toml"), "rb") as f:
        entries = tomllib.load(f)["input"]
    files = {e["file"] for e in entries}
    unlisted = sorted(n for n in os.listdir(HERE)
                      if n not in files and n not in {"catalogue.toml", "check_catalogue.py", "README.md"}
                      and not n.startswith("uses_"))
    passed = failed = 0
    with tempfile.TemporaryDirectory(prefix="knotwork-bad-inputs-") as tmp:
        scratch = os.path.join(tmp, "inputs")
        shutil.copytree(HERE, scratch)
        for entry in entries:
            if wanted and entry["file"] not in wanted:
                continue
            if not os.path.exists(os.path.join(scratch, entry["file"])):
                problems = ["the file is missing from tests/bad_inputs"]
            else:
                problems = check(binary, entry, scratch)
            if problems:
                failed += 1
                print(f"FAIL {entry['file']}: knotwork {entry['args']}")
                for p in problems:
                    print("    " + p)
            else:
                passed += 1
                print(f"ok   {entry['file']}")
    if unlisted and not wanted:
        failed += 1
        print("FAIL files in tests/bad_inputs without a catalogue entry: " + ", ".join(unlisted))
    print(f"{passed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
