"""The sweep example: its 12 runs give the same numbers serially, in threads and on a Dask
LocalCluster, and the script runs and draws its figure."""

import importlib.util
import subprocess
import sys

import pytest

from conftest import ROOT

EXAMPLE = ROOT / "python" / "examples" / "sweep_impact.py"


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("sweep_impact", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules["sweep_impact"] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def serial(example):
    pairs = example.grid()
    assert len(pairs) == 12
    return example.sweep_serial(pairs)


def test_threads_give_the_serial_numbers(example, serial):
    assert example.sweep_local(example.grid(), workers=2) == serial


def test_a_dask_cluster_gives_the_serial_numbers(example, serial):
    from dask import distributed

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            assert example.sweep_dask(example.grid(), client) == serial


def test_the_elastic_error_falls_with_dt_and_viscosity_levels_it_off(serial):
    elastic = [r["l2_error"] for r in serial if r["alpha"] == 0.0]
    assert elastic == sorted(elastic, reverse=True)
    viscous = [r["l2_error"] for r in serial if r["alpha"] == max(r["alpha"] for r in serial)]
    assert viscous[-1] > elastic[-1]


def test_the_script_runs_and_draws_its_figure(tmp_path):
    figure = tmp_path / "sweep.png"
    done = subprocess.run([sys.executable, str(EXAMPLE), "--figure", str(figure)],
                          capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert f"wrote {figure}" in done.stdout
    assert len(done.stdout.splitlines()) == 1 + 12 + 1
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
