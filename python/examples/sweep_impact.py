"""A sweep over viscosity and time step on the `impact` scene, run in parallel on one machine
(concurrent.futures) or on a Dask cluster, with the error against the elastic closed form.

The scene: an elastic bar on [0, L] moving at -v0 onto an obstacle a0 below its left end
(README, "Using it"). Its closed form (d'Alembert) is

    u(x, t) = max(-v0 min(t, t1 + x), v0 (t - 2 t1 - 2L)),   t1 = a0 / v0,

the solution of the elastic bar (alpha = 0). Each run of the grid takes one viscosity alpha
and one time step dt, the mesh refined with it (dt / dx = 1, as the scene has it), and
measures the largest discrete L2 error of u against the closed form over the kept steps. At
alpha = 0 the error is the scheme's and falls with dt; at alpha > 0 it levels off at the
viscous bar's distance from the elastic one.

    python sweep_impact.py                       # threads on this machine: sweep_impact.png
    python sweep_impact.py --figure out.png --workers 2
    python sweep_impact.py --scheduler tcp://scheduler:8786   # the same runs on a Dask cluster

viscobar releases the GIL while it steps, so the runs of a ThreadPoolExecutor go in parallel.
On Dask each run is a task; the workers need viscobar installed (`pip install ./python`), and
this file is sent to them by `client.upload_file` when it is imported rather than run.
"""

import argparse
import concurrent.futures
import itertools
import sys

import numpy as np

import viscobar

#: The viscosities of the grid.
ALPHAS = (0.0, 0.001, 0.01)
#: The time steps of the grid; the mesh has 1 / dt elements (dt / dx = 1).
STEPS = (0.02, 0.01, 0.005, 0.0025)
#: The scene's data, as `viscobar.show("impact")` gives them.
LENGTH, GAP, SPEED = 1.0, 0.1, 1.0


def exact(x, t):
    """The closed form u(x, t) of the elastic impact, on arrays x and t (broadcast)."""
    t1 = GAP / SPEED
    return np.maximum(-SPEED * np.minimum(t, t1 + x), SPEED * (t - 2 * t1 - 2 * LENGTH))


def error(alpha, dt):
    """Runs `impact` with viscosity `alpha` and time step `dt`; the largest L2 error over the
    kept steps (trapezoidal rule on the nodes) and the run's final energy."""
    elements = round(LENGTH / dt)
    run = viscobar.run(
        "impact",
        set={"bar.viscosity": alpha, "time.step": dt, "mesh.elements": elements},
    )
    x, t, u = run.positions, run.times, run.displacement
    e2 = (u - exact(x[None, :], t[:, None])) ** 2
    dx = np.diff(x)
    l2 = np.sqrt(((e2[:, 1:] + e2[:, :-1]) / 2 * dx).sum(axis=1))
    return {
        "alpha": alpha,
        "dt": dt,
        "l2_error": float(l2.max()),
        "energy_final": run.summary["energy_final"],
    }


def grid(alphas=ALPHAS, steps=STEPS):
    """The (alpha, dt) pairs of the sweep, alpha first."""
    return list(itertools.product(alphas, steps))


def sweep_serial(pairs):
    """The runs one after the other."""
    return [error(a, dt) for a, dt in pairs]


def sweep_local(pairs, workers=None):
    """The runs on this machine's cores: threads, which step in parallel."""
    with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(error, *zip(*pairs)))


def sweep_dask(pairs, client):
    """The runs as tasks of the Dask cluster of `client` (a `dask.distributed.Client`)."""
    if __name__ != "__main__":
        # Imported, this module is pickled by reference: the workers need its file.
        client.upload_file(__file__)
    futures = client.map(error, *zip(*pairs), pure=False)
    return client.gather(futures)


def figure(results, path):
    """Draws the error against dt, one line per alpha, into `path` (matplotlib, Agg)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4))
    for alpha in sorted({r["alpha"] for r in results}):
        rows = sorted((r["dt"], r["l2_error"]) for r in results if r["alpha"] == alpha)
        ax.loglog(*zip(*rows), marker="o", label=f"alpha = {alpha:g}")
    ax.set_xlabel("dt (= dx)")
    ax.set_ylabel("max over t of the L2 error of u")
    ax.set_title("impact: error against the elastic closed form")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--figure", default="sweep_impact.png", help="the figure's file")
    parser.add_argument("--workers", type=int, default=None, help="threads (default: cores)")
    parser.add_argument("--scheduler", help="a Dask scheduler's address, e.g. tcp://host:8786")
    args = parser.parse_args(argv)
    pairs = grid()
    if args.scheduler:
        from dask.distributed import Client

        with Client(args.scheduler) as client:
            results = sweep_dask(pairs, client)
    else:
        results = sweep_local(pairs, args.workers)
    print(f"{'alpha':>8} {'dt':>8} {'L2 error':>12} {'final energy':>14}")
    for r in results:
        print(f"{r['alpha']:8g} {r['dt']:8g} {r['l2_error']:12.4e} {r['energy_final']:14.6f}")
    figure(results, args.figure)
    print(f"wrote {args.figure}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
