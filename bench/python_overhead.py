"""The cost of a knotwork call from Python against the CLI, for a small case (docs/PYTHON.md).

Usage, from the repository root after the build:
    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [case] [--repeat N]
"""
import argparse
import statistics
import subprocess
import time

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
