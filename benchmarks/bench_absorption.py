"""Build and load times of the default absorption table, and its spline accuracy.

Run: ``python benchmarks/bench_absorption.py`` (builds into a temporary cache folder, so the
build is timed even when ``~/.cache/invflame`` already holds the table).
"""

import os
import tempfile
import time

import numpy as np

from invflame.spectroscopy.absorption_table import AbsorptionTable, default_linelists
from invflame.spectroscopy.table_accuracy import spline_error


def main():
    with tempfile.TemporaryDirectory() as folder:
        os.environ["INVFLAME_CACHE"] = folder
        start = time.perf_counter()
        linelists = default_linelists()
        lines_time = time.perf_counter() - start
        start = time.perf_counter()
        table = AbsorptionTable.default(progress=False)
        build = time.perf_counter() - start
        start = time.perf_counter()
        AbsorptionTable.default(progress=False)
        load = time.perf_counter() - start
    counts = ", ".join(f"{name} {len(lines)}" for name, lines in linelists.items())
    print(f"lines: {counts} (line lists in {lines_time:.2f} s)")
    print(f"grid: {table.wavenumber.size} points, {table.temperatures.size} T nodes "
          f"{table.temperatures[0]:g}-{table.temperatures[-1]:g} K")
    print(f"build (line lists + table, {os.cpu_count()} CPUs): {build:.2f} s")
    print(f"load from cache (line lists + key + file): {load:.2f} s")
    nodes = table.temperatures
    midpoints = 0.5 * (nodes[1:] + nodes[:-1])
    errors = spline_error(table, linelists, midpoints)
    for j, name in enumerate(table.species):
        if errors[:, j].any():
            worst = np.argmax(errors[:, j])
            print(f"spline error {name}: max {100 * errors[worst, j]:.3f} % at "
                  f"{midpoints[worst]:.0f} K (interval midpoints, spectra smoothed to 1 cm-1)")


if __name__ == "__main__":
    main()
