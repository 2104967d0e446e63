"""The arrays and files of `viscobar.run` against the command line's files for the same scene
and keys, bit for bit, on a bar, a plane, a plane with friction, a thermal bar and a plane with
a temperature, uncoupled and coupled."""

import filecmp
import threading
import time
import tomllib

import numpy as np
import pytest

import viscobar
from conftest import cli, read_csv, read_summary, same_bits, set_args, without_clock

#: Each scene with overrides that keep it short and sample its steps and nodes.
CASES = {
    "impact": {"output.every": "7", "output.nodes": "13", "output.diagnostics_every": "4"},
    "plane-tilted-drop": {"time.end": "0.3", "output.every": "3"},
    "plane-friction-tilted-drop": {"time.end": "0.3"},
    "thermal-impact": {"time.end": "0.5", "output.nodes": "21"},
    "plane-brake": {"time.end": "0.3", "output.every": "3"},
    "plane-brake coupled": {"time.end": "0.3", "output.every": "3", "heat.coupling": "0.5"},
}

#: The cases with a temperature, and those with friction.
HEATED = {"thermal-impact", "plane-brake", "plane-brake coupled"}
FRICTIONAL = {"plane-friction-tilted-drop", "plane-brake", "plane-brake coupled"}


def scene_of(case):
    """The built-in scene a case runs (its name's first word)."""
    return case.split()[0]


def cli_run(scene, overrides, folder):
    done = cli("run", scene, "--out", str(folder), *set_args(overrides))
    assert done.returncode == 0, done.stderr
    return folder


@pytest.mark.parametrize("case", CASES)
def test_arrays_hold_the_bits_of_the_cli_files(case, out):
    overrides, scene = CASES[case], scene_of(case)
    files = cli_run(scene, overrides, out / "cli")
    run = viscobar.run(scene, set=overrides)

    history = read_csv(files / "history.csv")
    assert list(run.history) == list(history)
    for column, values in history.items():
        assert same_bits(run.history[column], values), column
    assert run.history["step"].dtype == np.float64
    columns = list(run.history)
    if case in FRICTIONAL:
        # The frictional floor's tangential total, beside its reaction.
        at = columns.index("reaction_bottom")
        assert columns[at + 1] == "tangential_reaction_bottom"
    else:
        assert not any(c.startswith("tangential_reaction") for c in columns)

    table = read_csv(files / "displacement.csv")
    kept, nodes = len(run.times), len(run.positions)
    assert same_bits(table["t"], np.repeat(run.times, nodes))
    plane = run.body == "plane"
    assert run.displacement.shape == ((kept, nodes, 2) if plane else (kept, nodes))
    assert run.velocity.shape == run.displacement.shape
    if plane:
        assert run.positions.shape == (nodes, 2)
        assert same_bits(table["x"], np.tile(run.positions[:, 0], kept))
        assert same_bits(table["y"], np.tile(run.positions[:, 1], kept))
        fields = {"ux": run.displacement[..., 0], "uy": run.displacement[..., 1],
                  "vx": run.velocity[..., 0], "vy": run.velocity[..., 1]}
    else:
        assert same_bits(table["x"], np.tile(run.positions, kept))
        fields = {"u": run.displacement, "v": run.velocity}
    if case in HEATED:
        assert run.theta.shape == (kept, nodes)
        fields["theta"] = run.theta
    else:
        assert run.theta is None
    assert sorted(table) == sorted(["t", "x", *(["y"] if plane else []), *fields])
    for column, values in fields.items():
        assert same_bits(table[column], values.ravel()), column

    summary = read_summary(files / "summary.json")
    assert without_clock(run.summary) == without_clock(summary)
    assert run.summary["output"]["kept_steps"] == kept


@pytest.mark.parametrize("case", CASES)
def test_write_gives_the_cli_files(case, out):
    overrides, scene = CASES[case], scene_of(case)
    files = cli_run(scene, overrides, out / "cli")
    run = viscobar.run(scene, set=overrides)
    run.write(out / "python")
    for name in ["history.csv", "displacement.csv"]:
        assert filecmp.cmp(files / name, out / "python" / name, shallow=False), name
    written = read_summary(out / "python" / "summary.json")
    assert without_clock(written) == without_clock(read_summary(files / "summary.json"))
    assert written == run.summary


def test_a_vtu_scene_is_written_as_the_cli_writes_it(out):
    overrides = {"time.end": "0.05", "output.format": "vtu"}
    files = cli_run("plane-strip", overrides, out / "cli")
    run = viscobar.run("plane-strip", set=overrides)
    run.write(out / "python")
    assert sorted(p.name for p in (out / "python").iterdir()) == ["history.csv", "solution.pvd",
                                                                    "summary.json", "vtu"]
    for name in ["history.csv", "solution.pvd"]:
        assert filecmp.cmp(files / name, out / "python" / name, shallow=False), name
    vtu = sorted(p.name for p in (files / "vtu").iterdir())
    assert vtu == sorted(p.name for p in (out / "python" / "vtu").iterdir())
    for name in vtu:
        assert filecmp.cmp(files / "vtu" / name, out / "python" / "vtu" / name, shallow=False)


def test_scenes_and_show_are_the_cli_lists_and_texts():
    listing = cli("scenes")
    assert listing.returncode == 0
    names = [line.split()[0] for line in listing.stdout.splitlines() if not line.startswith(" ")]
    assert viscobar.scenes() == names
    for name in ["impact", "thermal-impact", "plane-friction-slope"]:
        assert viscobar.show(name) == cli("show", name).stdout


def history_bits(run):
    return {k: v.view(np.uint64).tolist() for k, v in run.history.items()}


def test_a_scene_by_name_path_text_or_dict_runs_the_same(tmp_path):
    overrides = {"time.end": 0.5}
    text = viscobar.show("impact")
    path = tmp_path / "impact.toml"
    path.write_text(text)
    by_name = viscobar.run("impact", set=overrides)
    assert by_name.name == "impact"
    forms = [(str(path), "impact"), (path, "impact"), (text, "scene"),
             (tomllib.loads(text), "scene")]
    for scene, name in forms:
        run = viscobar.run(scene, set=overrides)
        assert history_bits(run) == history_bits(by_name)
        assert same_bits(run.displacement, by_name.displacement)
        assert run.name == name


def test_set_and_solver_mean_what_the_cli_flags_mean():
    base = viscobar.run("impact", set={"time.step": 0.005, "time.end": 0.5})
    as_text = viscobar.run("impact", set={"time.step": "0.005", "time.end": "0.5"})
    assert history_bits(base) == history_bits(as_text)
    assert base.summary["dt"] == 0.005
    osqp = viscobar.run("impact", solver="osqp", set={"time.end": 0.5})
    by_key = viscobar.run("impact", set={"time.end": 0.5, "solver.method": "osqp"})
    assert osqp.summary["solver"] == by_key.summary["solver"] == "osqp"
    assert history_bits(osqp) == history_bits(by_key)
    # A str value is --set's text: an expression that is not TOML is taken as a string.
    loaded = viscobar.run("impact", set={"load.density": "0.1*x", "time.end": 0.5})
    assert loaded.summary["max_energy_rise"] is None


def test_arrays_are_read_only():
    run = viscobar.run("impact", set={"time.end": 0.2})
    for array in [run.times, run.positions, run.displacement, run.velocity,
                  run.history["energy"]]:
        with pytest.raises(ValueError):
            array[0] = 1.0


#: Seconds the main thread sleeps after the run has started: far below the run's length
#: (about a second here), far above a thread switch.
STARTED_SLEEP_S = 0.05


def test_the_gil_is_released_while_stepping():
    """The main thread runs Python code while the run steps: its clock reads a time before
    the run's stepping ended, which it could not if the run held the GIL."""
    started, result = threading.Event(), {}

    def work():
        result["start"] = time.perf_counter()
        started.set()
        result["run"] = viscobar.run("impact", set={"mesh.elements": 40000, "time.step": 1e-4,
                                                    "time.end": 0.5, "output.every": 100})

    worker = threading.Thread(target=work)
    worker.start()
    started.wait()
    time.sleep(STARTED_SLEEP_S)
    during = time.perf_counter()
    worker.join()
    run = result["run"]
    assert run.summary["steps"] == 5000
    # The run's own clock starts after `start`: stepping ended after start + wall_time_s.
    assert during < result["start"] + run.summary["wall_time_s"], (during - result["start"],
                                                                    run.summary["wall_time_s"])
