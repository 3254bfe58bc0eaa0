"""The cost of a knotwork call from Python against the CLI, for a small case (docs/PYTHON.md).

Usage, from the repository root after the build:
    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [case] [--repeat N]
"""
import argparse
import math
import statistics
import subprocess
import time

import numpy as np

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("case", nargs="?", default="cases/square_sinsin.toml")
parser.add_argument("--repeat", type=int, default=20)
parser.add_argument("--binary", default="build/app/knotwork")
args = parser.parse_args()

cli = []
for _ in range(args.repeat):
    t = time.perf_counter()
    subprocess.run([args.binary, "run", args.case, "--no-output", "--json", "-q"], capture_output=True, check=True)
    cli.append(time.perf_counter() - t)
t = time.perf_counter()
import knotwork  # noqa: E402

imported = time.perf_counter() - t
py, pipeline = [], []
for _ in range(args.repeat):
    t = time.perf_counter()
    r = knotwork.run(args.case)
    py.append(time.perf_counter() - t)
    pipeline.append(r.timings["total_without_output"])
m = statistics.median
print(f"case {args.case}: {r.dofs} dofs; medians of {args.repeat}")
print(f"  CLI, a new process each time      {m(cli) * 1e3:8.1f} ms")
print(f"  knotwork.run in one interpreter   {m(py) * 1e3:8.1f} ms")
print(f"  of which the pipeline (timings)   {m(pipeline) * 1e3:8.1f} ms")
print(f"  Python's own cost per call        {(m(py) - m(pipeline)) * 1e3:8.1f} ms")
print(f"  import knotwork (once)            {imported * 1e3:8.1f} ms")

# A source given as a Python function against the same source as a formula, 64 x 64 elements
# (p = 2): the function is called once per cell with its quadrature points, the GIL taken.
square = {"geometry": {"type": "rectangle"}, "space": {"degree": 2, "elements": 64}}
formula = dict(square, problem={"exact": "sin(pi*x)*sin(pi*y)", "source": "2*pi^2*sin(pi*x)*sin(pi*y)"})
function = dict(square, problem={"exact": "sin(pi*x)*sin(pi*y)",
                                 "source": lambda x, y: 2 * math.pi**2 * np.sin(math.pi * x) * np.sin(math.pi * y)})
timings = {"formula": [], "function": []}
for _ in range(args.repeat):
    for name, case in (("formula", formula), ("function", function)):
        r = knotwork.run(case)
        timings[name].append((r.timings["assembly"], r.timings["total_without_output"]))
print(f"source as a formula or a Python function: {r.dofs} dofs (64 x 64, p = 2); medians of {args.repeat}, alternating")
for name, t in timings.items():
    print(f"  {name:<9} assembly {m(a for a, _ in t) * 1e3:7.1f} ms   total {m(b for _, b in t) * 1e3:7.1f} ms")
ratio = m(a for a, _ in timings["function"]) / m(a for a, _ in timings["formula"])
print(f"  assembly with the Python function: {ratio:.2f} x the formula's")
