"""The Python package's overhead: the time of `viscobar.run` (scene read from Python, run in
memory, outputs turned into numpy arrays) over the library's own in-memory run of the same
scene, timed in Rust in the same process and build (`viscobar._library_run_seconds`). A
benchmark, not a test: it prints the ratios (target <= 1.1x); benches/README.md names it.

    target/venv/bin/python python/bench/ratio.py [--repeats 5]

Two references: `outputs`, the library's `output::memory::record_any` (what `run` keeps:
history rows and sampled profiles), and `records`, its `run_in_memory` (every step's record,
no profiles). Runs alternate Python and Rust; each ratio is the median of the pairs' ratios.
"""

import argparse
import statistics
import time

import viscobar

#: A 1e4-element bar over 1000 steps (dt = dx; contact from t = 0.05) and a 1e4-unknown plane
#: (101 x 51 nodes, two unknowns each) over 100 steps.
CASES = {
    "bar, 1e4 elements, 1000 steps": (
        "impact",
        {"mesh.elements": 10000, "time.step": 1e-4, "time.end": 0.1, "left.gap": 0.05},
    ),
    "plane, 10302 unknowns, 100 steps": (
        "plane-tilted-drop",
        {"mesh.nx": 100, "mesh.ny": 50, "time.step": 0.002, "time.end": 0.2},
    ),
}


def python_seconds(scene, overrides):
    start = time.perf_counter()
    viscobar.run(scene, set=overrides)
    return time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print(f"{'case':34} {'python s':>9} {'outputs s':>9} {'ratio':>6} {'records s':>9} {'ratio':>6}")
    for label, (scene, overrides) in CASES.items():
        viscobar.run(scene, set=overrides)  # warm caches and pages
        py, outputs, records = [], [], []
        for _ in range(args.repeats):
            py.append(python_seconds(scene, overrides))
            outputs.append(viscobar._library_run_seconds(scene, set=overrides, keep="outputs"))
            records.append(viscobar._library_run_seconds(scene, set=overrides, keep="records"))
        ratio = lambda ref: statistics.median(p / r for p, r in zip(py, ref))
        print(
            f"{label:34} {statistics.median(py):9.3f} {statistics.median(outputs):9.3f} "
            f"{ratio(outputs):5.3f}x {statistics.median(records):9.3f} {ratio(records):5.3f}x"
        )


if __name__ == "__main__":
    main()
