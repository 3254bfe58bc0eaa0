#!/usr/bin/env python3
"""SIGINT or SIGTERM while knotwork writes its output leaves nothing behind.

Starts `knotwork run` (and `knotwork converge`) on a case large enough that writing the
ParaView files takes a while, waits until a staged output file is being written (its size
grows), sends the signal, and checks: the exit code is 128 + the signal, stderr ends with one
line naming the signal, and the output folder, which the run created, is gone with everything
in it. A second check interrupts during the solve, before any output exists.

Usage: check_interrupt.py KNOTWORK_BINARY
"""
import os
import signal
import subprocess
import sys
import tempfile
import time

CASE = """
[geometry]
type = "rectangle"
[space]
degree = 2
elements = {elements}
[problem]
exact = "sin(pi*x)*sin(pi*y)"
[solver]
method = "direct"
[output]
samples = 8
"""


def staged_files(out):
    """Files inside knotwork's hidden staging folder, with their sizes."""
    found = {}
    if not os.path.isdir(out):
        return found
    for name in os.listdir(out):
        if name.startswith(".knotwork-staging-"):
            folder = os.path.join(out, name)
            for f in os.listdir(folder) if os.path.isdir(folder) else []:
                try:
                    found[f] = os.path.getsize(os.path.join(folder, f))
                except FileNotFoundError:
                    pass
    return found


def interrupt(binary, tmp, command, sig, when, elements):
    """Runs the command, sends `sig` at `when` ("output" or "solve"); returns a list of problems."""
    case = os.path.join(tmp, "interrupt.toml")
    with open(case, "w") as f:
        f.write(CASE.format(elements=elements))
    out = os.path.join(tmp, f"out-{command}-{sig.name}-{when}")
    args = [binary, command, case, "--out", out] + (["--levels", "2"] if command == "converge" else [])
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 600
    caught = None
    while time.monotonic() < deadline and p.poll() is None:
        if when == "output":
            staged = staged_files(out)
            if any(size > 0 for size in staged.values()):
                caught = staged
                p.send_signal(sig)
                break
        elif when == "solve" and os.path.isdir(out):
            time.sleep(0.2)  # the output folder exists from the start; the solve is under way
            caught = {}
            p.send_signal(sig)
            break
        time.sleep(0.001)
    try:
        stdout, stderr = p.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        p.kill()
        return [f"{command}: still running 120 s after {sig.name}"]
    if caught is None:
        return [f"{command}: finished (exit {p.returncode}) before the {when} could be interrupted; "
                f"raise the case's elements"]
    problems = []
    if p.returncode != 128 + sig.value:
        problems.append(f"exit code {p.returncode}, expected {128 + sig.value}")
    lines = stderr.strip().splitlines()
    word = {"SIGINT": "interrupted (SIGINT)", "SIGTERM": "terminated (SIGTERM)"}[sig.name]
    if not lines or lines[-1] != f"knotwork: error: {word}; no partial output left behind":
        problems.append("last stderr line: " + (lines[-1] if lines else "(none)"))
    if os.path.exists(out):
        left = [os.path.relpath(os.path.join(r, n), out) for r, d, fs in os.walk(out) for n in d + fs]
        problems.append("the output folder is still there, holding: " + (", ".join(left) or "nothing"))
    detail = ", ".join(f"{k} at {v} bytes" for k, v in sorted(caught.items())) or "no file yet"
    print(f"ok   {command} {sig.name} during the {when} ({detail})" if not problems else
          f"FAIL {command} {sig.name} during the {when} ({detail})")
    return problems


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    binary = os.path.abspath(sys.argv[1])
    elements = int(os.environ.get("KNOTWORK_INTERRUPT_ELEMENTS", "400"))
    passed = failed = 0
    with tempfile.TemporaryDirectory(prefix="knotwork-interrupt-") as tmp:
        for command, sig, when in [("run", signal.SIGTERM, "output"), ("run", signal.SIGINT, "output"),
                                   ("converge", signal.SIGINT, "output"), ("run", signal.SIGTERM, "solve")]:
            problems = interrupt(binary, tmp, command, sig, when, elements)
            for p in problems:
                print("    " + p)
            failed += bool(problems)
            passed += not problems
    print(f"{passed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
